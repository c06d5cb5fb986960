#include <doctest/doctest.h>
#include <fmt/format.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/error.hpp"
#include "experiments/output/external_tool.hpp"
#include "experiments/output/figures.hpp"
#include "experiments/runner/experiment.hpp"
#include "support/test_support.hpp"

using plydem::Error;
using plydem::ExperimentConfig;

TEST_CASE("an experiment config gives typed values, dotted keys and fallbacks") {
  const ExperimentConfig c = ExperimentConfig::parse(
      "experiment = \"laminate\"\ndescription = \"Table 4\"\nangles = [0, 15, 30.5]\n"
      "strategies = [\"hex2d\", \"square\"]\ncycles = 200000\n[fem]\nelement = \"C3D20R\"\n"
      "size_mm = 0.5\nrun = false\n",
      "table4.toml");
  CHECK(c.kind() == "laminate");
  CHECK(c.description() == "Table 4");
  CHECK(c.numbers("angles", {}) == std::vector<double>{0, 15, 30.5});
  CHECK(c.strings("strategies", {}) == std::vector<std::string>{"hex2d", "square"});
  CHECK(c.integer("cycles", 0) == 200000);
  CHECK(c.number("cycles", 0) == 200000.0);
  CHECK(c.string("fem.element", "") == "C3D20R");
  CHECK(c.number("fem.size_mm", 0) == 0.5);
  CHECK(c.boolean("fem.run", true) == false);
  CHECK(c.number("missing", 7) == 7);
  CHECK_NOTHROW(
      c.require_known_keys({"experiment", "description", "angles", "strategies", "cycles", "fem"}));
}

TEST_CASE("an experiment config refuses wrong types, unknown keys and malformed TOML") {
  const ExperimentConfig c =
      ExperimentConfig::parse("cycles = 2.5\nname = 3\nangels = [0]\nsign = -1\n", "bad.toml");
  CHECK_THROWS_WITH_AS(c.integer("cycles", 0), doctest::Contains("'cycles' must be an integer"),
                       Error);
  CHECK_THROWS_WITH_AS(c.string("name", ""), doctest::Contains("'name' must be a string"), Error);
  CHECK_THROWS_WITH_AS(c.integer("sign", 0), doctest::Contains("must not be negative"), Error);
  CHECK_THROWS_WITH_AS(c.kind(), doctest::Contains("'experiment'"), Error);
  CHECK_THROWS_WITH_AS(c.require_known_keys({"cycles", "name", "angles", "sign"}),
                       doctest::Contains("unknown key 'angels'"), Error);
  CHECK_THROWS_WITH_AS(ExperimentConfig::parse("a = [1, \n", "broken.toml"),
                       doctest::Contains("broken.toml:"), Error);
  CHECK_THROWS_WITH_AS(ExperimentConfig::parse("x = nan\n", "nan.toml").number("x", 0),
                       doctest::Contains("finite"), Error);
  CHECK_THROWS_WITH_AS(ExperimentConfig::load("/nonexistent/table9.toml"),
                       doctest::Contains("cannot be read"), Error);
}

TEST_CASE("gnuplot draws a PNG, or plydem says plainly that it is missing") {
  const plydem::GnuplotAvailability gnuplot = plydem::gnuplot_availability();
  CHECK_FALSE(plydem::gnuplot_availability("/nonexistent/gnuplot").available);
  CHECK(plydem::gnuplot_availability("no-such-gnuplot").message.find("not installed") !=
        std::string::npos);
  if (!gnuplot.available) {
    plydem::test::skip(gnuplot.message);
    return;
  }
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / fmt::format("plydem_gnuplot_{}", ::getpid());
  std::filesystem::create_directories(dir);
  plydem::run_gnuplot("set terminal pngcairo size 200,150\nset output 'line.png'\nplot x\n", dir,
                      "line.gp");
  CHECK(std::filesystem::file_size(dir / "line.png") > 100);
  CHECK_THROWS_WITH_AS(plydem::run_gnuplot("plot undefined_variable_xyz\n", dir, "bad.gp"),
                       doctest::Contains("gnuplot failed"), Error);
  std::filesystem::remove_all(dir);
}

TEST_CASE("plot_curves gives curves that belong together one colour, and each set its marker") {
  const plydem::GnuplotAvailability gnuplot = plydem::gnuplot_availability();
  if (!gnuplot.available) {
    plydem::test::skip(gnuplot.message);
    return;
  }
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / fmt::format("plydem_curves_{}", ::getpid());
  using plydem::Curve;
  using plydem::Marker;
  const std::vector<Curve> curves = {
      {"model", {0, 1}, {0, 1}, true, 0, Marker::kDisc},
      {"reference", {0, 1}, {0, 2}, false, 0},
      {"model, coarser", {0, 1}, {0, 1.5}, true, 9, Marker::kCircle},  // 9: the palette's second
      {"model, cured", {0, 1}, {0, 0.5}, true, 9, Marker::kSquare},
      {"gnuplot's colour", {0, 1}, {1, 0}, false}};
  const plydem::Figure figure = plydem::plot_curves(curves, dir, "curves", "t", "x", "y");
  CHECK(std::filesystem::file_size(dir / "curves.png") > 100);
  std::ifstream file(dir / "plots" / "curves.gp");
  std::stringstream text;
  text << file.rdbuf();
  const std::string script = text.str();
  auto occurrences = [&](const std::string& what) {
    int n = 0;
    for (auto at = script.find(what); at != std::string::npos; at = script.find(what, at + 1)) ++n;
    return n;
  };
  CHECK(occurrences("lc rgb '#0072b2'") == 2);
  CHECK(occurrences("lc rgb '#d55e00'") == 2);
  CHECK(occurrences("lc rgb") == 4);  // the last curve's colour is gnuplot's
  CHECK(occurrences("pt 7 ps 1.2 lw 2") == 1);
  CHECK(occurrences("pt 6 ps 1.2 lw 1") == 1);
  CHECK(occurrences("pt 5 ps 1.1 lw 2") == 1);
  CHECK(occurrences("lines dt 2 lw 2") == 2);
  std::filesystem::remove_all(dir);
}
