#pragma once
/// \file
/// The in-plane stiffness of a built specimen, measured with the engine's own bonds: three static
/// solves (solvers/static_solver.hpp) in which the particles of a boundary frame (within `band` of
/// the specimen's x and y extremes) follow the affine displacements of the unit strains eps_xx,
/// eps_yy and gamma_xy, and every other degree of freedom (interior displacements, all rotations,
/// the frame's z motion) settles to equilibrium. The volume-averaged stress of each solve follows
/// from the frame's reactions, sigma = (1/V) sum_i r_i (x) x_i (the average-stress theorem; V = the
/// particles' material volume), which gives the 3x3 membrane stiffness column by column.
///
/// Prescribed boundary displacements bound the stiffness from above; the bound closes as the frame
/// shrinks relative to the specimen (the paper's coupon: within 0.1% of the periodic value for
/// hex2d). Gxy = 1 / (C^-1)_66, the modulus under shear stress alone, as CLT defines it.
///
/// The interior measure. The frame holds its particles affine, which a laminate's plies resist
/// near it (their lattices are turned against each other, so the interface bonds between them
/// relax with particle-scale fluctuations that the frame forbids); across a narrow coupon that
/// boundary layer is a good part of the specimen. The same three solves also give the stiffness of
/// an interior window, `interior_margin` inside the frame: the window's mean stress is the
/// particles' virial stress, sigma_W = -(1/V_W) sum_b w_b (f_b,i (x) x_i + f_b,j (x) x_j) over the
/// bonds with an end in the window (w_b = 1 with both ends inside, 1/2 with one: each particle owns
/// half of each of its bonds, so that a uniform state is measured exactly), V_W the window
/// particles' volume; its mean strain is the least-squares fit of the window particles'
/// displacements (core/measurements.hpp). C_W = [sigma_W] [eps_W]^-1 over the three cases is the
/// membrane stiffness of the laminate as its bulk carries it, interface bonds included, with no
/// free edge and no frame. A laminate of plies turned against each other has no common period,
/// so no exactly periodic cell exists for it; the window is the periodic cell's stand-in.

#include <Eigen/Dense>

#include "core/elasticity.hpp"
#include "core/model.hpp"
#include "solvers/linear_solver.hpp"

namespace plydem {

struct SpecimenStiffness {
  Eigen::Matrix3d stiffness =
      Eigen::Matrix3d::Zero();  ///< (xx, yy, xy) membrane stiffness / h [Pa]
  InPlaneConstants constants;   ///< from `stiffness`, Gxy among them
  double volume = 0;            ///< material volume V [m^3]
  int frame_particles = 0;      ///< particles with prescribed displacements
  /// The interior window's stiffness (see the file comment) [Pa], its constants, its particles
  /// and its distance from the frame [m]; zero where the specimen has no such window.
  Eigen::Matrix3d interior_stiffness = Eigen::Matrix3d::Zero();
  InPlaneConstants interior_constants;
  int interior_particles = 0;
  double interior_margin = 0;
  int factorizations = 0;  ///< of the stiffness matrix (one serves the three solves)
  int solves = 0;          ///< static solves (three)
  /// The solves' linear solver (StaticResult::method_name), their Krylov iterations (summed; 0
  /// for a direct factor) and what --linear-solver auto chose and why.
  std::string linear_solver;
  int linear_iterations = 0;
  std::string linear_solver_choice;
  double wall_seconds = 0;
};

/// Measures the specimen (the model is copied; `model` is left untouched). `band` [m] is the
/// frame's width; 0 = two particle diameters (2 x the largest radius x 2). The interior window lies
/// `interior_margin` [m] inside the frame (0 = the frame's width again); where that leaves no
/// window of at least three particle diameters across, the interior is not measured. Throws
/// plydem::Error for
/// an empty specimen or one whose interior the frame would swallow, or when a solve is refused
/// (solve_static names the cause). The three solves share one factorization (StaticSystem), made
/// by `linear_solver` (solvers/linear_solver.hpp); `force` is StaticSettings::force.
SpecimenStiffness measure_specimen_stiffness(
    const Model& model, double band = 0, LinearSolverKind linear_solver = LinearSolverKind::kAuto,
    double interior_margin = 0, bool force = false);

}  // namespace plydem
