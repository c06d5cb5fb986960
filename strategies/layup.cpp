// The layup strings of strategies/laminate.hpp on their own, text only: the layup's fuzz target
// (tests/fuzz) builds this file alone.
#include <fmt/format.h>

#include <cctype>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "core/units.hpp"
#include "strategies/laminate.hpp"

namespace plydem {
namespace {

// One angle in degrees, or the pair 45/-45 for "±45" / "+-45".
std::vector<double> parse_ply(const std::string& token, const std::string& layup) {
  std::string number = token;
  bool plus_minus = false;
  for (const std::string prefix : {"±", "+-"}) {
    if (number.rfind(prefix, 0) == 0) {
      number = number.substr(prefix.size());
      plus_minus = true;
    }
  }
  std::size_t used = 0;
  double degrees = 0;
  try {
    degrees = std::stod(number, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (number.empty() || used != number.size() || !std::isfinite(degrees)) {
    throw Error(fmt::format("layup '{}': '{}' is not a ply angle in degrees", layup, token));
  }
  if (std::abs(degrees) > 360) {
    throw Error(fmt::format("layup '{}': ply angle {} deg is out of range", layup, token));
  }
  if (plus_minus) return {degrees * kDegree, -degrees * kDegree};
  return {degrees * kDegree};
}

}  // namespace

std::vector<double> parse_layup(const std::string& text) {
  std::string layup;
  for (char c : text) {
    if (!std::isspace(static_cast<unsigned char>(c))) layup += c;
  }
  const auto open = layup.find('[');
  const auto close = layup.rfind(']');
  if (open != 0 || close == std::string::npos || close < open) {
    throw Error(fmt::format(
        "layup '{}' is not of the form [a/b/c] with an optional count and 's' after the bracket, "
        "e.g. [0/90/0], [0/30/45]s, [0/90]2s",
        text));
  }
  const std::string body = layup.substr(1, close - 1);
  std::string suffix = layup.substr(close + 1);
  bool symmetric = false;
  if (!suffix.empty() && (suffix.back() == 's' || suffix.back() == 'S')) {
    symmetric = true;
    suffix.pop_back();
  }
  int repeat = 1;
  if (!suffix.empty()) {
    std::size_t used = 0;
    try {
      repeat = std::stoi(suffix, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used != suffix.size() || repeat < 1 || repeat > 100) {
      throw Error(
          fmt::format("layup '{}': '{}' after the bracket is not a repeat count (1..100) "
                      "optionally followed by 's'",
                      text, layup.substr(close + 1)));
    }
  }
  if (body.empty()) throw Error(fmt::format("layup '{}' has no plies", text));
  std::vector<double> group;
  std::size_t start = 0;
  while (start <= body.size()) {
    const std::size_t slash = body.find('/', start);
    const std::string token =
        body.substr(start, slash == std::string::npos ? std::string::npos : slash - start);
    if (token.empty()) throw Error(fmt::format("layup '{}' has an empty ply between '/'", text));
    // A subscript count: "90_2" is 90/90 ("±45_2" is 45/-45/45/-45).
    std::string ply = token;
    int count = 1;
    if (const std::size_t under = token.find('_'); under != std::string::npos) {
      ply = token.substr(0, under);
      const std::string digits = token.substr(under + 1);
      std::size_t used = 0;
      try {
        count = std::stoi(digits, &used);
      } catch (const std::exception&) {
        used = 0;
      }
      if (digits.empty() || used != digits.size() || count < 1 || count > 100) {
        throw Error(
            fmt::format("layup '{}': '{}' is not a ply angle with a count (1..100) "
                        "after '_', e.g. 90_2",
                        text, token));
      }
    }
    const std::vector<double> plies = parse_ply(ply, text);
    for (int c = 0; c < count; ++c) group.insert(group.end(), plies.begin(), plies.end());
    if (slash == std::string::npos) break;
    start = slash + 1;
  }
  std::vector<double> angles;
  for (int r = 0; r < repeat; ++r) angles.insert(angles.end(), group.begin(), group.end());
  if (symmetric) {
    // Not angles.insert(end, angles.rbegin(), angles.rend()): a range of the vector itself.
    const std::vector<double> half = angles;
    angles.insert(angles.end(), half.rbegin(), half.rend());
  }
  return angles;
}

std::string format_layup(const std::vector<double>& ply_angles) {
  std::string out = "[";
  for (std::size_t k = 0; k < ply_angles.size(); ++k) {
    out += fmt::format("{}{:g}", k ? "/" : "", std::round(ply_angles[k] / kDegree * 1e6) / 1e6);
  }
  return out + "]";
}

}  // namespace plydem
