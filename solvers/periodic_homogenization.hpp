#pragma once
/// \file
/// Periodic homogenization of a whole built specimen (issue 4): the specimen is one period of an
/// infinite medium; each bond that crosses the period's boundary joins `first` to an image of
/// `second`. Under a macroscopic strain E every particle moves by E x plus a periodic fluctuation
/// w, and turns by its own rotation; the effective stiffness is the energy Hessian in E after w and
/// the rotations settle to minimum energy (static condensation, one sparse solve per unit strain).
///
/// This is unit-cell homogenization (core/homogenizer.hpp) for cells of 10^2 .. 10^6 particles
/// with a stiffness per bond instead of per family, so that a random packing, a supercell of a
/// regular lattice or a built sample can be measured with the engine's own bond law
/// (core/parallel_bond.hpp).
///
/// Directions that are not periodic (a layer's thickness) carry no image offsets; the particles'
/// fluctuations along them are free, so the in-plane block of a layer is its plane-stress
/// stiffness, as for UnitCell. Voigt order (11, 22, 33, 23, 13, 12), engineering shear strains.

#include <array>
#include <string>

#include "core/elasticity.hpp"
#include "core/homogenizer.hpp"
#include "core/model.hpp"
#include "solvers/static_solver.hpp"

namespace plydem {

/// One period of a periodic specimen.
struct PeriodicModel {
  /// Particles of one period and their bonds. Bond geometry (normal, length, levers) is that of
  /// the branch first -> image of second.
  Model model;
  /// Columns are the periods [m]. A non-periodic direction's column is unused.
  Eigen::Matrix3d lattice_vectors = Eigen::Matrix3d::Identity();
  std::array<bool, 3> periodic{true, true, false};
  /// Per bond, the period (in lattice vectors) holding the image of `second`; zero in every
  /// non-periodic direction.
  Eigen::Array<int, Eigen::Dynamic, 3> bond_image;
  /// Material volume of one period [m^3] (for a layer: period area x thickness).
  double volume = 0;

  /// Branch vector of bond b, first -> image of second [m].
  Eigen::Vector3d branch(int b) const;
  /// Throws plydem::Error naming the first inconsistency (sizes, images in a non-periodic
  /// direction, geometry that does not match the branch, non-positive volume), after
  /// model.check_consistency().
  void check_consistency() const;
};

/// `repeats` copies of `cell` along its lattice vectors (1 in a non-periodic direction), each bond
/// of family f with stiffness families[f]; particle masses and volumes from the cell volume and
/// `density` [kg/m^3]. The supercell's stiffness equals the unit cell's: tests compare the two.
PeriodicModel periodic_supercell(const UnitCell& cell, const std::vector<FamilyStiffness>& families,
                                 const std::array<int, 3>& repeats,
                                 const std::array<bool, 3>& periodic, double density = 1.0);

struct PeriodicHomogenization {
  Matrix6d affine = Matrix6d::Zero();   ///< all particles follow E x, none turns [Pa]
  Matrix6d relaxed = Matrix6d::Zero();  ///< fluctuations and rotations at minimum energy [Pa]
  int particles = 0;
  int bonds = 0;
  int internal_dofs = 0;  ///< fluctuation and rotation dofs condensed out
  /// Internal dofs without stiffness of their own (e.g. particle spins in a network of normal
  /// springs) plus zero pivots of the factorization: zero-energy modes of the fluctuations that
  /// the macro strains do not load, set to zero. Rigid translations are not counted.
  int zero_modes = 0;
  std::string method;  ///< the sparse solver used
  double seconds = 0;  ///< wall-clock time of the whole homogenization
};

/// Affine and relaxed effective stiffness of one period. Throws plydem::Error naming the cause for
/// an inconsistent model, a negative stiffness (an unstable calibration), a loose particle (no
/// bonds) or a mechanism that the macro strains load (the bonds do not restrain some internal
/// dofs, and straining the period would move them). Zero-energy modes that the strains do not load
/// (rigid translations of the fluctuation, spins of particles without rotational stiffness, a
/// lattice's sliding planes) do not change the stiffness; they are counted in zero_modes.
///
/// H_ww (the fluctuation and rotation block) is the static solver's stiffness of `periodic.model`
/// (solvers/stiffness_assembly.hpp), with one particle's translations fixed (the rigid
/// translations); it is factorized with SupernodalCholesky up to settings.direct_max_dofs internal
/// dofs and solved by conjugate gradients above (settings.method, preconditioner, cg_tolerance and
/// pivot_tolerance as for solve_static). The six columns of H_wE are the right-hand sides; relaxed
/// = (H_EE - H_Ew H_ww^-1 H_wE) / volume, affine = H_EE / volume.
///
/// With `fluctuations`, also the relaxed motion per unit macro strain: a 6n x 6 matrix, row
/// 6 i + c the translation (c < 3) or rotation (c >= 3) of particle i under unit strain s in
/// column s, beyond the affine E x (zero for dofs left out). Calibrations use it for the
/// sensitivity of the relaxed stiffness to each bond (the envelope theorem).
PeriodicHomogenization homogenize_periodic(const PeriodicModel& periodic,
                                           const StaticSettings& settings = {},
                                           Eigen::MatrixXd* fluctuations = nullptr);

}  // namespace plydem
