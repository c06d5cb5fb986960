#pragma once
/// \file
/// Cure stresses (issue 33; ../shared/DAMAGE_NOTES.md §6): a laminate cooled from its stress-free
/// temperature by delta_T < 0 shrinks ply by ply, each ply by its thermal strain
///   eps_th = R(theta) diag(alpha1, alpha2, alpha2) R(theta)^T delta_T
/// in the coupon's axes (theta its fibre angle about z). A bond takes it as a free offset
/// (core/model.hpp, Bonds::free_offset): the relative displacement eps_th (x_second - x_first) at
/// which it carries no force, eps_th the mean of its two ends' plies' (an interface bond's ends lie
/// in two plies). A ply alone then shrinks free of stress, exactly (a uniform strain moves every
/// bond by its free offset and turns no particle); plies bonded together restrain each other's
/// shrinkage, which is what lamination theory's thermal force resultant describes. A solver that
/// takes the offsets (the static solver, the reference backend) solves the cure as a load like
/// any other; those that do not refuse a model with them.

#include <Eigen/Dense>
#include <vector>

#include "core/elasticity.hpp"
#include "core/model.hpp"
#include "solvers/static_solver.hpp"

namespace plydem {

/// A ply's thermal strain in the coupon's axes at temperature change `delta_T` [K] (the tensor,
/// not Voigt). Throws plydem::Error if the ply's material has no thermal expansion or delta_T is
/// not finite.
Eigen::Matrix3d ply_thermal_strain(const Ply& ply, double delta_T);

/// Sets every bond's free offset to its plies' mean thermal strain times its branch vector
/// (length * normal); `plies[k]` is ply k of Particles::ply. delta_T = 0 clears the offsets.
/// Throws plydem::Error naming the problem for a particle's ply out of range, a ply without
/// thermal expansion (when delta_T != 0) or a non-finite delta_T.
void set_cure_offsets(Model& model, const std::vector<Ply>& plies, double delta_T);

/// Classical lamination theory's thermal ply stresses of a free laminate (no mechanical load,
/// symmetric: no bending): N_T = sum_k Qbar_k eps_th,k t_k, eps0 = A^-1 N_T and each ply's
/// (sigma_x, sigma_y, tau_xy) = Qbar_k (eps0 - eps_th,k) [Pa], one row per ply.
std::vector<Eigen::Vector3d> clt_thermal_ply_stresses(const std::vector<Ply>& plies,
                                                      double delta_T);

/// The cure of a free laminate as the DEM simulates it: set_cure_offsets, then the static solve
/// with only the rigid-body modes pinned (solvers/static_solver.hpp), the state written into
/// `model`. Returns each ply's mean particle stress (sigma_x, sigma_y, tau_xy) [Pa] over the
/// particles within `half` [m] of the coupon's centre in x and y (away from the free edges, where
/// lamination theory holds), one row per ply. Throws plydem::Error as set_cure_offsets and the
/// static solve do, or for a ply with no particle in the centre.
std::vector<Eigen::Vector3d> solve_cure(Model& model, const std::vector<Ply>& plies, double delta_T,
                                        double half);

/// A cured coupon held where its cure left it: set_cure_offsets, the free laminate's cure (the
/// static solve with only the rigid-body modes pinned, the state written into `model`), and that
/// state's value at every dof `held` flags (one row per particle, Dof columns; zero elsewhere):
/// the preload of an events run (solvers/bond_events.hpp, EventSettings::preload), whose grips
/// then hold the cured coupon carrying nothing before the load. Throws plydem::Error as
/// set_cure_offsets and the static solve do, or for `held` of another size.
DofArray cured_preload(Model& model, const std::vector<Ply>& plies, double delta_T,
                       const DofFlags& held);

}  // namespace plydem
