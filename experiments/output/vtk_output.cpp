#include "experiments/output/vtk_output.hpp"

#include <fmt/format.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <utility>

#include "contacts/bond_kernel.hpp"
#include "core/error.hpp"

namespace plydem {
namespace {

namespace fs = std::filesystem;

constexpr int kVtkVertex = 1;
constexpr int kVtkLine = 3;

Eigen::Vector3d row3(const Vector3Array& a, int i) {
  return {a(i, 0), a(i, 1), a(i, 2)};
}

// A VTK XML file being assembled in memory, written in one go.
class VtuWriter {
 public:
  VtuWriter(int points, int cells) {
    out_ += "<?xml version=\"1.0\"?>\n";
    out_ +=
        "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" "
        "header_type=\"UInt64\">\n";
    out_ += "  <UnstructuredGrid>\n";
    out_ += fmt::format("    <Piece NumberOfPoints=\"{}\" NumberOfCells=\"{}\">\n", points, cells);
  }
  void open(const char* section) { out_ += fmt::format("      <{}>\n", section); }
  void close(const char* section) { out_ += fmt::format("      </{}>\n", section); }

  // One DataArray of doubles, `components` per tuple, from rows of a Vector3Array or a column.
  void doubles(const std::string& name, const Vector3Array& values) {
    begin("Float64", name, 3);
    for (Eigen::Index i = 0; i < values.rows(); ++i)
      out_ += fmt::format("{} {} {}\n", values(i, 0), values(i, 1), values(i, 2));
    end();
  }
  void doubles(const std::string& name, const Eigen::ArrayXd& values) {
    begin("Float64", name, 1);
    for (Eigen::Index i = 0; i < values.size(); ++i) out_ += fmt::format("{}\n", values(i));
    end();
  }
  void ints(const char* type, const std::string& name, const Eigen::ArrayXi& values) {
    begin(type, name, 1);
    for (Eigen::Index i = 0; i < values.size(); ++i) out_ += fmt::format("{}\n", values(i));
    end();
  }

  // The Cells section: connectivity (point indices), offsets (end of each cell) and types.
  void cells(const std::vector<int>& connectivity, int points_per_cell, int cell_type) {
    const int cells = static_cast<int>(connectivity.size()) / points_per_cell;
    open("Cells");
    begin("Int64", "connectivity", 1);
    for (std::size_t k = 0; k < connectivity.size(); ++k)
      out_ += fmt::format("{}{}", connectivity[k], (k + 1) % points_per_cell == 0 ? "\n" : " ");
    end();
    begin("Int64", "offsets", 1);
    for (int c = 1; c <= cells; ++c) out_ += fmt::format("{}\n", c * points_per_cell);
    end();
    begin("UInt8", "types", 1);
    for (int c = 0; c < cells; ++c) out_ += fmt::format("{}\n", cell_type);
    end();
    close("Cells");
  }

  void points(const Vector3Array& position) {
    open("Points");
    begin("Float64", "position", 3);
    for (Eigen::Index i = 0; i < position.rows(); ++i)
      out_ += fmt::format("{} {} {}\n", position(i, 0), position(i, 1), position(i, 2));
    end();
    close("Points");
  }

  void save(const std::string& path) {
    out_ += "    </Piece>\n  </UnstructuredGrid>\n</VTKFile>\n";
    std::ofstream file(path, std::ios::binary);
    if (!file) throw Error(fmt::format("cannot open {} for writing", path));
    file << out_;
    file.close();
    if (!file) throw Error(fmt::format("writing {} failed", path));
  }

 private:
  void begin(const char* type, const std::string& name, int components) {
    out_ += fmt::format(
        "        <DataArray type=\"{}\" Name=\"{}\" NumberOfComponents=\"{}\" format=\"ascii\">\n",
        type, name, components);
  }
  void end() { out_ += "        </DataArray>\n"; }

  std::string out_;
};

Vector3Array drawn_positions(const Model& model, const VtkOptions& options) {
  if (!std::isfinite(options.displacement_scale))
    throw Error(
        fmt::format("VTK displacement scale must be finite, got {}", options.displacement_scale));
  model.check_consistency();
  return model.particles.reference_position +
         options.displacement_scale * model.particles.displacement;
}

}  // namespace

void write_particles_vtu(const Model& model, const std::string& path, const VtkOptions& options) {
  const Vector3Array position = drawn_positions(model, options);
  const Particles& p = model.particles;
  const int n = p.size();
  VtuWriter vtu(n, n);
  vtu.open("PointData Scalars=\"radius\" Vectors=\"displacement\"");
  vtu.doubles("displacement", p.displacement);
  vtu.doubles("velocity", p.velocity);
  vtu.doubles("rotation", p.rotation);
  vtu.doubles("radius", p.radius);
  vtu.ints("Int32", "ply", p.ply);
  vtu.ints("Int32", "group", p.group);
  if (options.include_force) {
    vtu.doubles("force", p.force);
    vtu.doubles("torque", p.torque);
  }
  auto require_size = [&](const std::string& name, Eigen::Index rows) {
    require(rows == n,
            fmt::format("VTK point data '{}' has {} values for {} particles", name, rows, n));
  };
  for (const auto& [name, values] : options.particle_scalars) {
    require_size(name, values.size());
    vtu.doubles(name, values);
  }
  for (const auto& [name, values] : options.particle_vectors) {
    require_size(name, values.rows());
    vtu.doubles(name, values);
  }
  vtu.close("PointData");
  vtu.points(position);
  std::vector<int> connectivity(n);
  for (int i = 0; i < n; ++i) connectivity[i] = i;
  vtu.cells(connectivity, 1, kVtkVertex);
  vtu.save(path);
}

void write_bonds_vtu(const Model& model, const std::string& path, const VtkOptions& options) {
  const Vector3Array position = drawn_positions(model, options);
  const Particles& p = model.particles;
  const Bonds& bonds = model.bonds;
  const int m = bonds.size();
  Eigen::ArrayXd force(m), normal_force(m), energy(m);
  std::vector<int> connectivity(2 * static_cast<std::size_t>(m));
  for (int b = 0; b < m; ++b) {
    const int i = bonds.first(b), j = bonds.second(b);
    const BondParameters params = bond_parameters(bonds, b);
    const BondResponse r =
        parallel_bond_response(params, row3(p.displacement, i), row3(p.rotation, i),
                               row3(p.displacement, j), row3(p.rotation, j));
    force(b) = r.force_on_first.norm();
    normal_force(b) = params.normal.dot(r.force_on_first);  // +F pulls the first towards the second
    energy(b) = r.energy;
    connectivity[2 * b] = i;
    connectivity[2 * b + 1] = j;
  }
  VtuWriter vtu(p.size(), m);
  vtu.open("PointData Vectors=\"displacement\"");
  vtu.doubles("displacement", p.displacement);
  vtu.close("PointData");
  vtu.open("CellData Scalars=\"force\"");
  // "family" keeps the meaning it had before bonds had a kind: an interface bond's family is
  // written as -1 - k for the interface above ply k (Bonds::family holds k).
  Eigen::ArrayXi family = bonds.family;
  for (int b = 0; b < m; ++b)
    if (bonds.is_interface(b)) family(b) = -1 - bonds.family(b);
  vtu.ints("Int32", "family", family);
  vtu.ints("Int32", "kind", bonds.kind);
  vtu.doubles("normal_stiffness", bonds.normal_stiffness);
  vtu.doubles("shear_stiffness", bonds.shear_stiffness);
  vtu.doubles("bending_stiffness", bonds.bending_stiffness);
  vtu.doubles("twisting_stiffness", bonds.twisting_stiffness);
  vtu.doubles("force", force);
  vtu.doubles("normal_force", normal_force);
  vtu.doubles("strain_energy", energy);
  vtu.ints("Int32", "state", bonds.state);
  vtu.doubles("damage", bonds.damage);
  vtu.close("CellData");
  vtu.points(position);
  vtu.cells(connectivity, 2, kVtkLine);
  vtu.save(path);
}

VtkSeries::VtkSeries(std::string pvd_path) : pvd_path_(std::move(pvd_path)) {
  require(!pvd_path_.empty(), "the .pvd path is empty");
  const fs::path path(pvd_path_);
  stem_ = path.stem().string();
  require(!stem_.empty(), fmt::format("the .pvd path '{}' names no file", pvd_path_));
  if (path.has_parent_path()) {
    std::error_code ec;
    fs::create_directories(path.parent_path(), ec);
    require(fs::is_directory(path.parent_path()),
            fmt::format("cannot create the directory of {}", pvd_path_));
  }
}

void VtkSeries::add_model(double time, const Model& model, const VtkOptions& options) {
  require(std::isfinite(time), "a VTK series time must be finite");
  const fs::path directory = fs::path(pvd_path_).parent_path();
  const std::string particles = fmt::format("{}_{}_particles.vtu", stem_, states_);
  const std::string bonds = fmt::format("{}_{}_bonds.vtu", stem_, states_);
  write_particles_vtu(model, (directory / particles).string(), options);
  write_bonds_vtu(model, (directory / bonds).string(), options);
  ++states_;
  entries_.push_back({time, 0, particles});
  entries_.push_back({time, 1, bonds});
  write();
}

void VtkSeries::add_file(double time, const std::string& file, int part) {
  require(std::isfinite(time), "a VTK series time must be finite");
  require(!file.empty() && file.find('"') == std::string::npos &&
              file.find('<') == std::string::npos && file.find('&') == std::string::npos,
          fmt::format("'{}' cannot be listed in a .pvd file", file));
  require(part >= 0, "a VTK series part must be >= 0");
  entries_.push_back({time, part, file});
  write();
}

std::vector<std::string> VtkSeries::files() const {
  std::vector<std::string> names;
  for (const Entry& e : entries_) names.push_back(e.file);
  return names;
}

void VtkSeries::write() const {
  std::string out = "<?xml version=\"1.0\"?>\n";
  out += "<VTKFile type=\"Collection\" version=\"1.0\" byte_order=\"LittleEndian\">\n";
  out += "  <Collection>\n";
  for (const Entry& e : entries_)
    out += fmt::format("    <DataSet timestep=\"{}\" part=\"{}\" file=\"{}\"/>\n", e.time, e.part,
                       e.file);
  out += "  </Collection>\n</VTKFile>\n";
  std::ofstream file(pvd_path_, std::ios::binary);
  if (!file) throw Error(fmt::format("cannot open {} for writing", pvd_path_));
  file << out;
  file.close();
  if (!file) throw Error(fmt::format("writing {} failed", pvd_path_));
}

}  // namespace plydem
