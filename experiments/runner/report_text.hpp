#pragma once
/// \file
/// Text pieces every experiment's report.md and file names share.

#include <fmt/format.h>

#include <cctype>
#include <cmath>
#include <string>
#include <vector>

namespace plydem {

/// `text` as a file-name stem: every character but letters, digits, '-' and '_' becomes '_'.
inline std::string file_stem(std::string text) {
  for (char& ch : text) {
    if (!std::isalnum(static_cast<unsigned char>(ch)) && ch != '-' && ch != '_') ch = '_';
  }
  return text;
}

/// One Markdown table row: "| a | b |\n".
inline std::string markdown_row(const std::vector<std::string>& cells) {
  std::string line = "|";
  for (const std::string& cell : cells) line += fmt::format(" {} |", cell);
  return line + "\n";
}

/// value relative to reference as "+1.23%"; "–" when either is not finite or reference is 0.
inline std::string percent_change(double value, double reference) {
  if (!std::isfinite(value) || !std::isfinite(reference) || reference == 0) return "–";
  return fmt::format("{:+.2f}%", 100.0 * (value / reference - 1.0));
}

}  // namespace plydem
