// The small shared pieces of core/ that several layers use: disjoint sets, the TOML reader, the
// registry of factories by name, the stopwatch.
#include <doctest/doctest.h>
#include <fmt/format.h>

#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "core/disjoint_sets.hpp"
#include "core/error.hpp"
#include "core/registry.hpp"
#include "core/stopwatch.hpp"
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

namespace {

struct Widget {
  int size = 0;
};

FactoryRegistry<Widget> widget_registry() {
  FactoryRegistry<Widget> registry({"widget", "a widget needs a name",
                                    "a widget named '{}' is already registered",
                                    "unknown widget '{}'; registered widgets: {}"});
  registry.add("small", "one unit", [] { return std::make_unique<Widget>(Widget{1}); });
  registry.add("large", "ten units", [] { return std::make_unique<Widget>(Widget{10}); });
  return registry;
}

}  // namespace

TEST_CASE("registry: names in order, a new instance per create, errors in the registry's words") {
  FactoryRegistry<Widget> registry = widget_registry();
  CHECK(registry.names() == std::vector<std::string>{"large", "small"});
  CHECK(registry.contains("small"));
  CHECK_FALSE(registry.contains("medium"));
  CHECK(registry.create("large")->size == 10);
  CHECK(registry.create("small").get() != registry.create("small").get());
  CHECK(registry.description("small") == "one unit");
  CHECK_THROWS_WITH_AS(registry.create("medium"),
                       "unknown widget 'medium'; registered widgets: large, small", Error);
  CHECK_THROWS_WITH_AS(registry.description("medium"), "unknown widget 'medium'", Error);
  CHECK_THROWS_WITH_AS(registry.add("small", "", [] { return std::make_unique<Widget>(); }),
                       "a widget named 'small' is already registered", Error);
  CHECK_THROWS_WITH_AS(registry.add("", "", [] { return std::make_unique<Widget>(); }),
                       "a widget needs a name", Error);
  CHECK_THROWS_WITH_AS(registry.add("empty", "", nullptr), "widget 'empty' has no factory", Error);
  CHECK(registry.names().size() == 2);  // the refused ones were not added
}

TEST_CASE("stopwatch: seconds since the start; a lap starts again") {
  Stopwatch clock;
  const double first = clock.seconds();
  CHECK(first >= 0);
  CHECK(clock.seconds() >= first);  // steady: never backwards
  const double lap = clock.lap();
  CHECK(lap >= first);
  clock.restart();
  CHECK(clock.seconds() >= 0);
}
