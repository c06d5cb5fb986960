#pragma once
/// \file
/// ParaView output: a Model (core/model.hpp) as VTK XML UnstructuredGrid files (.vtu), and a .pvd
/// collection for a series of states (load stages, time steps).
///
/// A model is written as two files, so that each carries its own cell data:
///   - particles: one VTK_VERTEX cell per particle; point data displacement, velocity, rotation
///     (3 components each), radius, ply, group (BoundaryGroup), and optionally force and torque
///     (what Particles::force and ::torque hold: the last evaluation of the kernel or a solver),
///     and the arrays VtkOptions adds (the strength test's cracked sites, say);
///   - bonds: one VTK_LINE cell per bond between its two particles; cell data family (the
///     packing's bond family of an in-ply bond, -1 - k for an interface bond above ply k), kind
///     (BondKind: 0 in-ply, 1 interface), normal_stiffness, shear_stiffness, bending_stiffness,
///     twisting_stiffness, and the bond's response at the current state through the one bond law
///     (core/parallel_bond.hpp): force (|F| [N]), normal_force (n.F, positive in tension [N]) and
///     strain_energy [J]; the bond's state (BondState: 0 intact, 1 broken in tension, 2 broken in
///     shear) and damage (0 intact .. 1 broken; a broken bond keeps its cell, with zero
///     stiffness); the point data repeats the particles' displacement so that ParaView's
///     "Warp By Vector" works.
///
/// Points sit at the reference positions plus `displacement_scale` times the displacements
/// (0 = reference configuration, 1 = current; elastic micro-strains are invisible at 1).
/// Everything is ASCII with full double precision (shortest round-trip decimal), SI units.
/// In ParaView: open the .pvd (or the .vtu), "Glyph" (Sphere, Scale Array: radius, factor 2) for
/// particles, "Tube" or plain lines coloured by force for bonds.

#include <string>
#include <utility>
#include <vector>

#include "core/model.hpp"

namespace plydem {

struct VtkOptions {
  /// Points at reference_position + displacement_scale * displacement. Must be finite.
  double displacement_scale = 1.0;
  /// Also write the particles' force and torque arrays.
  bool include_force = true;
  /// More point data for the particles' file, by name: one value or one 3-vector per particle.
  std::vector<std::pair<std::string, Eigen::ArrayXd>> particle_scalars;
  std::vector<std::pair<std::string, Vector3Array>> particle_vectors;
};

/// Writes the particles of `model` to `path` (.vtu). Throws plydem::Error if the model is
/// inconsistent, an option is not finite, or the file cannot be written.
void write_particles_vtu(const Model& model, const std::string& path,
                         const VtkOptions& options = {});

/// Writes the bonds of `model` to `path` (.vtu). Throws like write_particles_vtu.
void write_bonds_vtu(const Model& model, const std::string& path, const VtkOptions& options = {});

/// A ParaView collection (.pvd) of .vtu files: a time or stage series, each entry possibly in
/// several parts (particles and bonds). The .pvd refers to its files by their paths relative to
/// the .pvd's directory.
class VtkSeries {
 public:
  /// The collection will be written to `pvd_path`; its directory must exist or be creatable.
  explicit VtkSeries(std::string pvd_path);

  /// Writes `model` as <stem>_<index>_particles.vtu and <stem>_<index>_bonds.vtu beside the .pvd
  /// (index = the number of states added so far), adds both at `time` (parts 0 and 1), and
  /// rewrites the .pvd, so that an interrupted run leaves a readable series.
  void add_model(double time, const Model& model, const VtkOptions& options = {});

  /// Adds an existing dataset file at `time` as `part` and rewrites the .pvd.
  void add_file(double time, const std::string& file, int part = 0);

  const std::string& path() const { return pvd_path_; }
  /// The .vtu files added so far, as written into the .pvd.
  std::vector<std::string> files() const;

 private:
  struct Entry {
    double time = 0;
    int part = 0;
    std::string file;
  };
  void write() const;
  std::string pvd_path_;
  std::string stem_;
  int states_ = 0;
  std::vector<Entry> entries_;
};

}  // namespace plydem
