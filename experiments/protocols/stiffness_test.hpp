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
  int factorizations = 0;       ///< of the stiffness matrix (one serves the three solves)
  int solves = 0;               ///< static solves (three)
  double wall_seconds = 0;
};

/// Measures the specimen (the model is copied; `model` is left untouched). `band` [m] is the
/// frame's width; 0 = two particle diameters (2 x the largest radius x 2). Throws plydem::Error for
/// an empty specimen or one whose interior the frame would swallow, or when a solve is refused
/// (solve_static names the cause). The three solves share one factorization (StaticSystem), made
/// by `linear_solver` (solvers/linear_solver.hpp).
SpecimenStiffness measure_specimen_stiffness(
    const Model& model, double band = 0, LinearSolverKind linear_solver = LinearSolverKind::kAuto);

}  // namespace plydem
