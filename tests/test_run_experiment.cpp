// `plydem run`: the Table 4 and Table 5 experiments run quick into a temporary folder; their
// report, results.csv, figures and VTU files are checked, and the laminate moduli against CLT
// written out here by hand from E-glass/MY750's engineering constants (paper Table 1, ERRATA §2).
#include <doctest/doctest.h>
#include <fmt/format.h>
#include <unistd.h>

#include <Eigen/Dense>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <numbers>
#include <sstream>
#include <utility>

#include "core/error.hpp"
#include "experiments/output/external_tool.hpp"
#include "experiments/runner/run_experiment.hpp"

using namespace plydem;
namespace fs = std::filesystem;

namespace {

const fs::path kExperiments = fs::path(PLYDEM_TEST_DATA_DIR) / ".." / ".." / "experiments";

fs::path temp_dir(const std::string& name) {
  const fs::path dir =
      fs::temp_directory_path() / fmt::format("plydem_run_{}_{}", name, ::getpid());
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::string read(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// Plane-stress Q of E-glass/MY750 (E1 45.6, E2 16.2, G12 5.83 GPa, nu12 0.278) turned to `deg`:
// eq. (32) written out.
Eigen::Matrix3d q_bar(double deg) {
  const double E1 = 45.6e9, E2 = 16.2e9, G12 = 5.83e9, nu12 = 0.278;
  const double nu21 = nu12 * E2 / E1;
  const double d = 1 - nu12 * nu21;
  const double Q11 = E1 / d, Q22 = E2 / d, Q12 = nu12 * E2 / d, Q66 = G12;
  const double t = deg * std::numbers::pi / 180, c = std::cos(t), s = std::sin(t);
  const double c2 = c * c, s2 = s * s;
  Eigen::Matrix3d q;
  q(0, 0) = Q11 * c2 * c2 + 2 * (Q12 + 2 * Q66) * s2 * c2 + Q22 * s2 * s2;
  q(1, 1) = Q11 * s2 * s2 + 2 * (Q12 + 2 * Q66) * s2 * c2 + Q22 * c2 * c2;
  q(0, 1) = q(1, 0) = (Q11 + Q22 - 4 * Q66) * s2 * c2 + Q12 * (s2 * s2 + c2 * c2);
  q(0, 2) = q(2, 0) = (Q11 - Q12 - 2 * Q66) * s * c2 * c + (Q12 - Q22 + 2 * Q66) * s2 * s * c;
  q(1, 2) = q(2, 1) = (Q11 - Q12 - 2 * Q66) * s2 * s * c + (Q12 - Q22 + 2 * Q66) * s * c2 * c;
  q(2, 2) = (Q11 + Q22 - 2 * Q12 - 2 * Q66) * s2 * c2 + Q66 * (s2 * s2 + c2 * c2);
  return q;
}

struct Clt {
  double Ex, Ey, nu_xy, nu_yx;
};
// CLT of equal-thickness plies: A/h is the mean Q-bar; Ex = 1/a11, nu_xy = -a12/a11, ...
Clt clt(const std::vector<double>& degrees) {
  Eigen::Matrix3d a = Eigen::Matrix3d::Zero();
  for (double deg : degrees) a += q_bar(deg) / static_cast<double>(degrees.size());
  const Eigen::Matrix3d s = a.inverse();
  return {1 / s(0, 0), 1 / s(1, 1), -s(0, 1) / s(0, 0), -s(0, 1) / s(1, 1)};
}

// results.csv as (case, quantity, source) -> value, checking the header and the field count.
std::map<std::string, double> parse_results(const fs::path& path) {
  std::ifstream in(path);
  std::string line;
  REQUIRE(std::getline(in, line));
  CHECK(line == "experiment,case,quantity,source,value,unit");
  std::map<std::string, double> values;
  while (std::getline(in, line)) {
    std::vector<std::string> fields;
    std::string field;
    bool quoted = false;
    for (char ch : line) {
      if (ch == '"')
        quoted = !quoted;
      else if (ch == ',' && !quoted)
        fields.push_back(std::exchange(field, ""));
      else
        field += ch;
    }
    fields.push_back(field);
    REQUIRE(fields.size() == 6);
    values[fmt::format("{}|{}|{}", fields[1], fields[2], fields[3])] = std::stod(fields[4]);
  }
  return values;
}

bool is_png(const fs::path& path) {
  const std::string head = read(path).substr(0, 8);
  return head == std::string("\x89PNG\r\n\x1a\n", 8);
}

// Runs experiments/NAME.toml quick and checks everything a run must leave; returns the values.
std::map<std::string, double> run_quick(const std::string& name, const std::string& table) {
  const fs::path dir = temp_dir(name);
  RunOptions options;
  options.config = kExperiments / fmt::format("{}.toml", name);
  options.out_dir = dir;
  options.quick = true;
  const RunSummary summary = run_experiment(options);
  const std::string report = read(dir / "report.md");
  CHECK(report.find(fmt::format("## {}:", table)) != std::string::npos);
  CHECK(report.find("rel. err.") != std::string::npos);
  CHECK(report.find("CLT (correct, A matrix)") != std::string::npos);
  CHECK(report.find("free grips") != std::string::npos);
  CHECK(report.find("γxy/εx") != std::string::npos);
  CHECK(report.find("quick run") != std::string::npos);
  CHECK(report.find("## Files") != std::string::npos);
  if (find_executable("ccx")) {
    CHECK(report.find("| CalculiX (C3D8I") != std::string::npos);
  } else {
    CHECK(report.find("CalculiX not installed") != std::string::npos);
  }
  int pngs = 0, vtus = 0;
  for (const fs::path& file : summary.output.files) {
    INFO(file.string());
    CHECK(fs::exists(dir / file));
    if (file.extension() == ".png") {
      CHECK(is_png(dir / file));
      ++pngs;
    }
    if (file.extension() == ".vtu") {
      CHECK(read(dir / file).find("<VTKFile type=\"UnstructuredGrid\"") != std::string::npos);
      ++vtus;
    }
  }
  if (gnuplot_availability().available) CHECK(pngs >= 3);  // bonds, ux map, stress-strain
  CHECK(vtus == 2);                                        // particles and bonds
  CHECK(fs::exists(dir / "vtu" / fmt::format("{}.pvd", name)));
  const std::map<std::string, double> values = parse_results(dir / "results.csv");
  fs::remove_all(dir);
  return values;
}

}  // namespace

TEST_CASE("results.csv quotes fields that hold commas or quotes") {
  const std::string csv = results_csv({{"t", "[0/90/0]", "Ex", "dem hex2d", 36.0091234567, "GPa"},
                                       {"t", "a,b", "say \"x\"", "clt", 0.5, "1"}});
  CHECK(csv ==
        "experiment,case,quantity,source,value,unit\n"
        "t,[0/90/0],Ex,dem hex2d,36.00912346,GPa\n"
        "t,\"a,b\",\"say \"\"x\"\"\",clt,0.5,1\n");
}

TEST_CASE("run --list finds the paper's experiment configs with their descriptions") {
  const std::vector<ConfigListing> list = list_experiment_configs(kExperiments);
  std::map<std::string, std::string> by_name;
  for (const ConfigListing& c : list) by_name[c.name] = c.description;
  for (const char* name : {"table2", "table3", "table4", "table5"}) {
    INFO(name);
    REQUIRE(by_name.count(name) == 1);
    CHECK(by_name[name].find(fmt::format("Table {}", name[5])) == 0);
  }
  CHECK_THROWS_WITH_AS(list_experiment_configs("/nonexistent"), doctest::Contains("not a folder"),
                       Error);
}

TEST_CASE("run refuses a missing config, malformed TOML, an unknown kind and an unknown key") {
  const fs::path dir = temp_dir("errors");
  RunOptions options;
  options.out_dir = dir / "out";
  options.config = dir / "missing.toml";
  CHECK_THROWS_WITH_AS(run_experiment(options), doctest::Contains("cannot be read"), Error);
  auto write = [&](const std::string& file, const std::string& text) {
    std::ofstream(dir / file) << text;
    options.config = dir / file;
  };
  write("broken.toml", "experiment = \"laminate\"\nlayup = [0, \n");
  CHECK_THROWS_WITH_AS(run_experiment(options), doctest::Contains("broken.toml:"), Error);
  write("kind.toml", "experiment = \"table9\"\n");
  CHECK_THROWS_WITH_AS(run_experiment(options),
                       doctest::Contains("unknown experiment kind 'table9'"), Error);
  write("key.toml", "experiment = \"laminate\"\nlayup = \"[0/90/0]\"\nlayups = 1\n");
  CHECK_THROWS_WITH_AS(run_experiment(options), doctest::Contains("unknown key 'layups'"), Error);
  write("coupon.toml",
        "experiment = \"laminate\"\nlayup = \"[0/90/0]\"\n[coupon]\nlenght_mm = 3\n");
  CHECK_THROWS_WITH_AS(run_experiment(options), doctest::Contains("unknown key 'coupon.lenght_mm'"),
                       Error);
  CHECK_FALSE(fs::exists(dir / "out" / "report.md"));
  fs::remove_all(dir);
}

TEST_CASE("quick run: Table 4, the [0/90/0] laminate, within 2% and 0.015 of CLT") {
  const Clt ref = clt({0, 90, 0});
  const std::map<std::string, double> v = run_quick("table4", "Table 4");
  const std::string c = "[0/90/0]";
  // The library's CLT row agrees with the hand-written one.
  CHECK(v.at(c + "|Ex|clt") == doctest::Approx(ref.Ex * 1e-9).epsilon(1e-9));
  CHECK(v.at(c + "|nu_yx|clt") == doctest::Approx(ref.nu_yx).epsilon(1e-9));
  CHECK(std::abs(v.at(c + "|Ex|dem hex2d") / (ref.Ex * 1e-9) - 1) < 0.02);
  CHECK(std::abs(v.at(c + "|Ey|dem hex2d") / (ref.Ey * 1e-9) - 1) < 0.02);
  CHECK(std::abs(v.at(c + "|nu_xy|dem hex2d") - ref.nu_xy) < 0.015);
  CHECK(std::abs(v.at(c + "|nu_yx|dem hex2d") - ref.nu_yx) < 0.015);
  const std::string m = "|dem hex2d membrane";
  CHECK(std::abs(v.at(c + "|Ex" + m) / (ref.Ex * 1e-9) - 1) < 0.02);
  CHECK(std::abs(v.at(c + "|Ey" + m) / (ref.Ey * 1e-9) - 1) < 0.02);
  CHECK(std::abs(v.at(c + "|nu_xy" + m) - ref.nu_xy) < 0.015);
  CHECK(std::abs(v.at(c + "|nu_yx" + m) - ref.nu_yx) < 0.015);
  // The paper's values come from the config.
  CHECK(v.at(c + "|Ex|paper dem") == doctest::Approx(36.12));
  if (v.count(c + "|Ex|calculix")) {
    CHECK(std::abs(v.at(c + "|Ex|calculix") / (ref.Ex * 1e-9) - 1) < 0.01);
    CHECK(std::abs(v.at(c + "|nu_xy|calculix") - ref.nu_xy) < 0.01);
  }
}

TEST_CASE("quick run: Table 5, the [0/30/45]s laminate, within 2% and 0.015 of CLT") {
  const Clt ref = clt({0, 30, 45, 45, 30, 0});
  const std::map<std::string, double> v = run_quick("table5", "Table 5");
  const std::string c = "[0/30/45/45/30/0]";
  CHECK(v.at(c + "|Ex|clt") == doctest::Approx(ref.Ex * 1e-9).epsilon(1e-9));
  // The membrane stiffness of the DEM coupon (affine boundary frame): the laminate's A/h as its
  // bonds carry it.
  const std::string m = "|dem hex2d membrane";
  CHECK(std::abs(v.at(c + "|Ex" + m) / (ref.Ex * 1e-9) - 1) < 0.02);
  CHECK(std::abs(v.at(c + "|Ey" + m) / (ref.Ey * 1e-9) - 1) < 0.02);
  CHECK(std::abs(v.at(c + "|nu_xy" + m) - ref.nu_xy) < 0.015);
  CHECK(std::abs(v.at(c + "|nu_yx" + m) - ref.nu_yx) < 0.015);
  // Reciprocity of a linear elastic result (ERRATA §1): nu_yx Ex = nu_xy Ey.
  CHECK(v.at(c + "|nu_yx" + m) * v.at(c + "|Ex" + m) ==
        doctest::Approx(v.at(c + "|nu_xy" + m) * v.at(c + "|Ey" + m)).epsilon(1e-6));
  // The tension test pulled along x. (Along y, the quick 10 x 3 mm coupon of this 1.2 mm thick
  // coupled laminate still has free-edge and grip zones: Ey -2.8%, nu_yx +0.019 against CLT; the
  // full 20 x 5 mm coupon of table5.toml reaches Ey -1.2%, nu_yx +0.009. Not checked here.)
  CHECK(std::abs(v.at(c + "|Ex|dem hex2d") / (ref.Ex * 1e-9) - 1) < 0.02);
  CHECK(std::abs(v.at(c + "|nu_xy|dem hex2d") - ref.nu_xy) < 0.015);
  CHECK(std::abs(v.at(c + "|shear coupling gamma_xy/eps_x|dem hex2d") -
                 v.at(c + "|shear coupling gamma_xy/eps_x|clt")) < 0.03);
  // The paper's theory row (30.617 GPa) is not CLT: it is flagged.
  CHECK(std::abs(v.at(c + "|Ex|paper theory") / (ref.Ex * 1e-9) - 1) > 0.05);
}
