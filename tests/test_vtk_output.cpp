// ParaView output: a small hex2d coupon written as particles and bonds .vtu files (and a .pvd
// series), read back by a strict structural check of the XML here and, when python3 with VTK is
// installed, by VTK's own vtkXMLUnstructuredGridReader (tests/data/check_vtu.py).
#include <doctest/doctest.h>
#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <numbers>
#include <sstream>

#include "contacts/bond_kernel.hpp"
#include "core/error.hpp"
#include "core/material.hpp"
#include "experiments/output/vtk_output.hpp"
#include "strategies/laminate.hpp"
#include "strategies/registry.hpp"
#include "support/test_support.hpp"

using namespace plydem;
using namespace plydem::test;
namespace fs = std::filesystem;

namespace {

// A fresh directory under the system's temporary directory, removed at the end of the test.
struct TemporaryDirectory {
  fs::path path;
  TemporaryDirectory() {
    std::string pattern = (fs::temp_directory_path() / "plydem-vtk-XXXXXX").string();
    REQUIRE(::mkdtemp(pattern.data()) != nullptr);
    path = pattern;
  }
  ~TemporaryDirectory() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
};

std::string read_file(const fs::path& path) {
  std::ifstream in(path);
  REQUIRE(in);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// What the strict structural check finds in a .vtu file.
struct VtuContent {
  long points = -1, cells = -1;
  std::map<std::string, std::vector<double>> point_data, cell_data;
  std::map<std::string, int> components;
  std::vector<double> coordinates, connectivity, offsets, types;
};

std::string attribute(const std::string& tag, const std::string& name) {
  const std::string key = " " + name + "=\"";
  const auto begin = tag.find(key);
  if (begin == std::string::npos) return {};
  const auto end = tag.find('"', begin + key.size());
  REQUIRE(end != std::string::npos);
  return tag.substr(begin + key.size(), end - begin - key.size());
}

// Every tag balanced, every DataArray's values counted against the piece's sizes.
VtuContent check_vtu_structure(const std::string& text) {
  VtuContent content;
  std::vector<std::string> open;
  std::size_t pos = 0;
  std::string section, array_name, array_tag;
  std::size_t array_start = 0;
  while ((pos = text.find('<', pos)) != std::string::npos) {
    const std::size_t close = text.find('>', pos);
    REQUIRE(close != std::string::npos);
    const std::string tag = text.substr(pos, close - pos + 1);
    pos = close + 1;
    if (tag.rfind("<?", 0) == 0) continue;
    if (tag.rfind("</", 0) == 0) {
      const std::string name = tag.substr(2, tag.size() - 3);
      REQUIRE(!open.empty());
      REQUIRE(open.back() == name);
      open.pop_back();
      if (name == "DataArray") {
        std::vector<double> values;
        std::istringstream words(text.substr(array_start, pos - tag.size() - array_start));
        for (std::string word; words >> word;) {
          char* end = nullptr;
          values.push_back(std::strtod(word.c_str(), &end));
          REQUIRE(*end == '\0');
          REQUIRE(std::isfinite(values.back()));
        }
        const int components = std::stoi(attribute(array_tag, "NumberOfComponents"));
        content.components[array_name] = components;
        if (section == "PointData") {
          REQUIRE(values.size() == static_cast<std::size_t>(content.points * components));
          content.point_data[array_name] = values;
        } else if (section == "CellData") {
          REQUIRE(values.size() == static_cast<std::size_t>(content.cells * components));
          content.cell_data[array_name] = values;
        } else if (section == "Points") {
          REQUIRE(components == 3);
          REQUIRE(values.size() == static_cast<std::size_t>(3 * content.points));
          content.coordinates = values;
        } else if (section == "Cells") {
          if (array_name == "connectivity") content.connectivity = values;
          if (array_name == "offsets") content.offsets = values;
          if (array_name == "types") content.types = values;
        } else {
          FAIL("a DataArray outside PointData, CellData, Points and Cells");
        }
      }
      continue;
    }
    const bool self_closing = tag[tag.size() - 2] == '/';
    const std::string name = tag.substr(1, tag.find_first_of(" />", 1) - 1);
    if (name == "Piece") {
      content.points = std::stol(attribute(tag, "NumberOfPoints"));
      content.cells = std::stol(attribute(tag, "NumberOfCells"));
    }
    if (name == "PointData" || name == "CellData" || name == "Points" || name == "Cells")
      section = name;
    if (name == "DataArray") {
      array_name = attribute(tag, "Name");
      array_tag = tag;
      array_start = pos;
      CHECK(attribute(tag, "format") == "ascii");
    }
    if (!self_closing) open.push_back(name);
  }
  REQUIRE(open.empty());
  REQUIRE(content.points >= 0);
  REQUIRE(content.offsets.size() == static_cast<std::size_t>(content.cells));
  REQUIRE(content.types.size() == static_cast<std::size_t>(content.cells));
  double previous = 0;
  for (double offset : content.offsets) {
    REQUIRE(offset > previous);
    previous = offset;
  }
  REQUIRE(content.connectivity.size() == static_cast<std::size_t>(previous));
  for (double index : content.connectivity) REQUIRE((index >= 0 && index < content.points));
  return content;
}

// python3 with VTK's XML reader, if any: $PLYDEM_PYTHON, the system's python3 (Debian's
// python3-vtk9 installs for /usr/bin/python3, which a pyenv or venv python3 on PATH hides), then
// python3 on PATH. Only the reader's module is imported: `import vtk` loads all of VTK (1.5 s).
std::string python_with_vtk() {
  std::vector<std::string> candidates;
  if (const char* env = std::getenv("PLYDEM_PYTHON")) candidates.emplace_back(env);
  candidates.emplace_back("/usr/bin/python3");
  candidates.emplace_back("python3");
  for (const auto& python : candidates) {
    const std::string command =
        fmt::format("{} -c \"import vtkmodules.vtkIOXML\" > /dev/null 2>&1", python);
    if (std::system(command.c_str()) == 0) return python;
  }
  return {};
}

double abs_sum(const Eigen::ArrayXd& values) {
  return values.abs().sum();
}
double abs_sum(const Vector3Array& values) {
  return values.abs().sum();
}
double abs_sum(const Eigen::ArrayXi& values) {
  return values.abs().cast<double>().sum();
}
double abs_sum(const std::vector<double>& values) {
  double sum = 0;
  for (double v : values) sum += std::abs(v);
  return sum;
}

// A 30 deg hex2d coupon under an affine stretch, with rotations, velocities and groups set so that
// every written array holds something.
Model stretched_coupon() {
  CouponSpec spec;
  spec.material = load_material("eglass-my750");
  spec.ply_angle = 30 * std::numbers::pi / 180;
  spec.length = 0.6e-3;
  spec.width = 0.3e-3;
  Model model = default_registry().create("hex2d")->build(spec).model;
  Particles& p = model.particles;
  for (int i = 0; i < p.size(); ++i) {
    const double x = p.reference_position(i, 0), y = p.reference_position(i, 1);
    p.displacement.row(i) << 1e-3 * x, -0.3e-3 * y + 0.2e-3 * x, 0;
    p.velocity.row(i) << 0.01 * x, 0, -0.02 * y;
    p.group(i) = i % 3;
  }
  compute_bond_forces(p, model.bonds);
  return model;
}

}  // namespace

TEST_CASE("particles and bonds .vtu files hold the model's arrays, readable by VTK") {
  Model model = stretched_coupon();
  model.particles.rotation.col(2) = 1e-4;  // a rigid spin of every particle
  const Particles& p = model.particles;
  const Bonds& bonds = model.bonds;
  REQUIRE(p.size() > 20);
  REQUIRE(bonds.size() > 40);
  TemporaryDirectory dir;
  const fs::path particles_file = dir.path / "coupon_particles.vtu";
  const fs::path bonds_file = dir.path / "coupon_bonds.vtu";
  VtkOptions options;
  options.displacement_scale = 100;
  write_particles_vtu(model, particles_file.string(), options);
  write_bonds_vtu(model, bonds_file.string(), options);

  const VtuContent particles = check_vtu_structure(read_file(particles_file));
  CHECK(particles.points == p.size());
  CHECK(particles.cells == p.size());
  for (double t : particles.types) CHECK(t == 1);  // VTK_VERTEX
  for (const char* name : {"displacement", "velocity", "rotation", "force", "torque"})
    CHECK(particles.components.at(name) == 3);
  for (const char* name : {"radius", "ply", "group"}) CHECK(particles.components.at(name) == 1);
  // Full precision: the arrays come back bit for bit.
  for (int i = 0; i < p.size(); ++i) {
    for (int c = 0; c < 3; ++c) {
      REQUIRE(particles.point_data.at("displacement")[3 * i + c] == p.displacement(i, c));
      REQUIRE(particles.point_data.at("force")[3 * i + c] == p.force(i, c));
      REQUIRE(particles.coordinates[3 * i + c] ==
              p.reference_position(i, c) + 100 * p.displacement(i, c));
    }
    REQUIRE(particles.point_data.at("radius")[i] == p.radius(i));
    REQUIRE(particles.point_data.at("group")[i] == p.group(i));
  }

  const VtuContent written = check_vtu_structure(read_file(bonds_file));
  CHECK(written.points == p.size());
  CHECK(written.cells == bonds.size());
  for (double t : written.types) CHECK(t == 3);  // VTK_LINE
  // Bond forces by hand: under the affine stretch du = grad(u) (x_j - x_i); a uniform spin
  // theta_z moves the contact points by -(s_i + s_j) theta x n = -L theta_z (e_z x n), so the bond
  // sees du - L theta_z (e_z x n); F = k_n (n.du) n + k_s (du - (n.du) n).
  Eigen::Matrix3d grad = Eigen::Matrix3d::Zero();
  grad(0, 0) = 1e-3;
  grad(1, 0) = 0.2e-3;
  grad(1, 1) = -0.3e-3;
  double energy = 0;
  for (int b = 0; b < bonds.size(); ++b) {
    const Eigen::Vector3d n = bonds.normal.row(b).matrix().transpose();
    const Eigen::Vector3d spin_shift = -bonds.length(b) * 1e-4 * Eigen::Vector3d::UnitZ().cross(n);
    const Eigen::Vector3d du = grad * (bonds.length(b) * n) + spin_shift;
    const double dn = n.dot(du);
    const Eigen::Vector3d ds = du - dn * n;
    const Eigen::Vector3d f = bonds.normal_stiffness(b) * dn * n + bonds.shear_stiffness(b) * ds;
    CHECK(written.cell_data.at("force")[b] == doctest::Approx(f.norm()).epsilon(1e-9));
    CHECK(written.cell_data.at("normal_force")[b] ==
          doctest::Approx(bonds.normal_stiffness(b) * dn).epsilon(1e-9));
    const double e =
        0.5 * (bonds.normal_stiffness(b) * dn * dn + bonds.shear_stiffness(b) * ds.squaredNorm());
    CHECK(written.cell_data.at("strain_energy")[b] == doctest::Approx(e).epsilon(1e-9));
    CHECK(written.cell_data.at("family")[b] == bonds.family(b));
    CHECK(written.cell_data.at("kind")[b] == static_cast<int>(BondKind::kInPly));
    CHECK(written.cell_data.at("normal_stiffness")[b] == bonds.normal_stiffness(b));
    CHECK(written.connectivity[2 * b] == bonds.first(b));
    CHECK(written.connectivity[2 * b + 1] == bonds.second(b));
    energy += e;
  }
  CHECK(abs_sum(written.cell_data.at("strain_energy")) ==
        doctest::Approx(bond_strain_energy(p, bonds)).epsilon(1e-9));
  CHECK(energy == doctest::Approx(bond_strain_energy(p, bonds)).epsilon(1e-9));

  const std::string python = python_with_vtk();
  if (python.empty()) {
    skip(
        "python3 with VTK (Debian: python3-vtk9) is not installed: VTK reader check not run, "
        "structure checked");
    return;
  }
  const std::string script = std::string(PLYDEM_TEST_DATA_DIR) + "/check_vtu.py";
  const Vector3Array drawn = p.reference_position + 100 * p.displacement;
  const std::string particles_check = fmt::format(
      "{} {} {} {} {} 1 points={}:3 displacement={}:3 velocity={}:3 rotation={}:3 radius={} "
      "ply={} group={} force={}:3 torque={}:3",
      python, script, particles_file.string(), p.size(), p.size(), abs_sum(drawn),
      abs_sum(p.displacement), abs_sum(p.velocity), abs_sum(p.rotation), abs_sum(p.radius),
      abs_sum(p.ply), abs_sum(p.group), abs_sum(p.force), abs_sum(p.torque));
  CHECK(std::system(particles_check.c_str()) == 0);
  const std::string bonds_check = fmt::format(
      "{} {} {} {} {} 3 points={}:3 displacement={}:3 family={} normal_stiffness={} "
      "shear_stiffness={} bending_stiffness={} twisting_stiffness={} force={} normal_force={} "
      "strain_energy={}",
      python, script, bonds_file.string(), p.size(), bonds.size(), abs_sum(drawn),
      abs_sum(p.displacement), abs_sum(bonds.family), abs_sum(bonds.normal_stiffness),
      abs_sum(bonds.shear_stiffness), abs_sum(bonds.bending_stiffness),
      abs_sum(bonds.twisting_stiffness), abs_sum(written.cell_data.at("force")),
      abs_sum(written.cell_data.at("normal_force")),
      abs_sum(written.cell_data.at("strain_energy")));
  CHECK(std::system(bonds_check.c_str()) == 0);
  // A wrong expectation fails: the checker can tell.
  const std::string wrong = fmt::format("{} {} {} {} {} 1 > /dev/null", python, script,
                                        particles_file.string(), p.size(), p.size() + 1);
  CHECK(std::system(wrong.c_str()) != 0);
}

TEST_CASE("a laminate's bonds file marks interface bonds by kind, family -1 - k as before") {
  LaminateSpec spec;
  spec.coupon.material = load_material("eglass-my750");
  spec.coupon.length = 0.4e-3;
  spec.coupon.width = 0.3e-3;
  spec.ply_angles = parse_layup("[0/90/0]");
  const Model model = build_laminate(*default_registry().create("hex2d"), spec).model;
  const Bonds& bonds = model.bonds;
  TemporaryDirectory dir;
  const fs::path bonds_file = dir.path / "laminate_bonds.vtu";
  write_bonds_vtu(model, bonds_file.string(), VtkOptions{});
  const VtuContent written = check_vtu_structure(read_file(bonds_file));
  REQUIRE(written.cells == bonds.size());
  int interface_bonds[2] = {0, 0};
  for (int b = 0; b < bonds.size(); ++b) {
    const int lower =
        std::min(model.particles.ply(bonds.first(b)), model.particles.ply(bonds.second(b)));
    if (bonds.is_interface(b)) {
      CHECK(bonds.family(b) == lower);
      CHECK(written.cell_data.at("kind")[b] == 1);
      CHECK(written.cell_data.at("family")[b] == -1 - lower);
      ++interface_bonds[lower];
    } else {
      CHECK(written.cell_data.at("kind")[b] == 0);
      CHECK(written.cell_data.at("family")[b] == bonds.family(b));
      CHECK(bonds.family(b) >= 0);
    }
  }
  CHECK(interface_bonds[0] > 0);
  CHECK(interface_bonds[1] > 0);
}

TEST_CASE("a .pvd series lists each state's particles and bonds files") {
  Model model = stretched_coupon();
  TemporaryDirectory dir;
  VtkSeries series((dir.path / "run" / "tension.pvd").string());
  series.add_model(0.0, model);
  model.particles.displacement *= 2;
  VtkOptions reference_unforced;
  reference_unforced.displacement_scale = 0.0;
  reference_unforced.include_force = false;
  series.add_model(1.0, model, reference_unforced);
  const std::vector<std::string> files = series.files();
  REQUIRE(files.size() == 4);
  CHECK(files[0] == "tension_0_particles.vtu");
  CHECK(files[3] == "tension_1_bonds.vtu");
  for (const auto& f : files) {
    const VtuContent content = check_vtu_structure(read_file(dir.path / "run" / f));
    CHECK(content.points == model.particles.size());
  }
  // Drawn at the reference positions without forces.
  const VtuContent second = check_vtu_structure(read_file(dir.path / "run" / files[2]));
  CHECK(second.point_data.count("force") == 0);
  CHECK(second.coordinates[0] == model.particles.reference_position(0, 0));
  const std::string pvd = read_file(dir.path / "run" / "tension.pvd");
  CHECK(pvd.find("<DataSet timestep=\"1\" part=\"1\" file=\"tension_1_bonds.vtu\"/>") !=
        std::string::npos);
  CHECK(pvd.find("type=\"Collection\"") != std::string::npos);
}

TEST_CASE("VTK output refuses what it cannot write") {
  Model model = stretched_coupon();
  TemporaryDirectory dir;
  CHECK_THROWS_WITH_AS(write_particles_vtu(model, (dir.path / "missing" / "a.vtu").string()),
                       doctest::Contains("cannot open"), Error);
  VtkOptions not_finite;
  not_finite.displacement_scale = NAN;
  CHECK_THROWS_WITH_AS(write_bonds_vtu(model, (dir.path / "b.vtu").string(), not_finite),
                       doctest::Contains("displacement scale"), Error);
  // Extra point data must have a value per particle.
  VtkOptions short_array;
  short_array.particle_scalars = {{"crack_energy", Eigen::ArrayXd::Zero(1)}};
  CHECK_THROWS_WITH_AS(write_particles_vtu(model, (dir.path / "c.vtu").string(), short_array),
                       doctest::Contains("VTK point data 'crack_energy' has 1 values for"), Error);
  model.bonds.normal_stiffness(0) = -1;
  CHECK_THROWS_AS(write_bonds_vtu(model, (dir.path / "c.vtu").string()), Error);
}
