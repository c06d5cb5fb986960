// The small shared pieces of core/ that several layers use: disjoint sets, the TOML reader.
#include <doctest/doctest.h>
#include <fmt/format.h>

#include <utility>
#include <vector>

#include "core/disjoint_sets.hpp"
#include "core/error.hpp"
#include "core/toml_reader.hpp"

using namespace plydem;

TEST_CASE("disjoint sets: a set's representative is its lowest index, whatever the join order") {
  DisjointSets forward(6), backward(6);
  const std::vector<std::pair<int, int>> joins = {{5, 3}, {3, 1}, {4, 2}, {2, 0}};
  for (const auto& [a, b] : joins) CHECK(forward.join(a, b));
  for (auto it = joins.rbegin(); it != joins.rend(); ++it)
    CHECK(backward.join(it->second, it->first));
  for (int i = 0; i < 6; ++i) {
    const int lowest = i % 2 == 0 ? 0 : 1;
    CHECK(forward.find(i) == lowest);
    CHECK(backward.find(i) == lowest);
  }
  CHECK_FALSE(forward.join(5, 1));  // one set already
  CHECK(forward.join(5, 4));
  for (int i = 0; i < 6; ++i) CHECK(forward.find(i) == 0);
}

TEST_CASE("toml reader: a syntax error becomes plydem::Error in the caller's words") {
  const auto words = [](const TomlSyntaxError& e) {
    return fmt::format("x.toml:{}:{}: {}", e.line, e.column, e.description);
  };
  const toml::table table = parse_toml("a = 1\nb = 2.5\nc = 'text'\n", "x.toml", words);
  CHECK(toml_number(*table.get("a")) == 1.0);
  CHECK(toml_number(*table.get("b")) == 2.5);
  CHECK_FALSE(toml_number(*table.get("c")).has_value());
  CHECK_THROWS_WITH_AS(parse_toml("a = 1\nb = = 2\n", "x.toml", words),
                       doctest::Contains("x.toml:2:"), Error);
}
