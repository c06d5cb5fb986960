#pragma once
/// \file
/// The linear parallel bond of paper Sec. 2.2 (eqs. 1-3), in small-displacement form: the one bond
/// law of plydem. The explicit kernel, the static solver and the unit-cell homogenizer all evaluate
/// a bond through the functions here, so that every path simulates the same model.
///
/// A bond joins particle i (first) and j (second). With reference unit normal n (i -> j) and the
/// contact point at lever s_i from i and s_j from j, the relative displacement of the contact point
/// and the relative rotation are
///   du = (u_j - u_i) - (s_i theta_i + s_j theta_j) x n,     dtheta = theta_j - theta_i,
/// both zero under any rigid translation or (infinitesimal) rigid rotation. A bond with a free
/// offset q (an eigen-displacement: cure shrinkage) takes du - q for du. The bond carries
///   F = k_n (n.du) n + k_s (du - (n.du) n)          acting +F on i and -F on j,
///   M = k_t (n.dtheta) n + k_b (dtheta - (n.dtheta) n)   acting +M on i and -M on j,
/// plus the moments of F about each centre. This is the exact gradient of the bond energy
///   E = 1/2 du.(k_n nn + k_s (I - nn)).du + 1/2 dtheta.(k_t nn + k_b (I - nn)).dtheta,
/// which the energy test of the integrator relies on.
///
/// Out-of-plane shear. A bond may carry its shear along the layer normal with a stiffness of its
/// own, k_z = r k_s (r = out_of_plane_shear_ratio; 1, isotropic shear, for every bond a strategy
/// builds): with z the unit part of e_z perpendicular to n (none for a bond along z, where r does
/// nothing), k_s (I - nn) above becomes k_s (I - nn) + (r - 1) k_s z z. A ply built as one particle
/// layer has no other transverse shear: particle spin relieves the interface bonds' shear, so the
/// layer's in-plane bonds carry the ply's G13 and G23 this way (strategies/laminate.hpp,
/// InterfaceStiffness::transverse_shear). Because k_z scales with k_s, damage and breaking, which
/// scale or zero k_s, act on it too.

#include <Eigen/Dense>

namespace plydem {

using Matrix12d = Eigen::Matrix<double, 12, 12>;

/// Stiffnesses and reference geometry of one bond.
struct BondParameters {
  Eigen::Vector3d normal;  ///< unit, first -> second
  double lever_first = 0;
  double lever_second = 0;
  double normal_stiffness = 0;
  double shear_stiffness = 0;
  double bending_stiffness = 0;
  double twisting_stiffness = 0;
  double out_of_plane_shear_ratio = 1;  ///< r = k_z / k_s (see the file comment)
  /// The relative displacement at which the bond carries no force (Bonds::free_offset): du of the
  /// file comment is taken from it.
  Eigen::Vector3d free_offset = Eigen::Vector3d::Zero();
};

/// z of the file comment: the unit part of e_z perpendicular to `n`; zero for a bond along z.
inline Eigen::Vector3d out_of_plane_direction(const Eigen::Vector3d& n) {
  const Eigen::Vector3d z = Eigen::Vector3d::UnitZ() - n.z() * n;
  const double length = z.norm();
  return length > 1e-12 ? Eigen::Vector3d(z / length) : Eigen::Vector3d::Zero();
}

/// The shear stiffness tensor k_s (I - nn) + (r - 1) k_s z z of bond `b`.
inline Eigen::Matrix3d shear_stiffness_tensor(const BondParameters& b) {
  const Eigen::Vector3d& n = b.normal;
  Eigen::Matrix3d d = b.shear_stiffness * (Eigen::Matrix3d::Identity() - n * n.transpose());
  if (b.out_of_plane_shear_ratio != 1) {
    const Eigen::Vector3d z = out_of_plane_direction(n);
    d += (b.out_of_plane_shear_ratio - 1) * b.shear_stiffness * z * z.transpose();
  }
  return d;
}

/// The shear force of bond `b` at tangential relative displacement `du_s` (du - (n.du) n).
inline Eigen::Vector3d shear_force(const BondParameters& b, const Eigen::Vector3d& du_s) {
  Eigen::Vector3d f = b.shear_stiffness * du_s;
  if (b.out_of_plane_shear_ratio != 1) {
    const Eigen::Vector3d z = out_of_plane_direction(b.normal);
    f += ((b.out_of_plane_shear_ratio - 1) * b.shear_stiffness * z.dot(du_s)) * z;
  }
  return f;
}

/// What one bond does to its two particles.
struct BondResponse {
  Eigen::Vector3d force_on_first;  ///< +F; the second particle receives -F
  Eigen::Vector3d torque_on_first;
  Eigen::Vector3d torque_on_second;
  double energy = 0;
};

inline Eigen::Vector3d contact_relative_displacement(const BondParameters& b,
                                                     const Eigen::Vector3d& u_i,
                                                     const Eigen::Vector3d& theta_i,
                                                     const Eigen::Vector3d& u_j,
                                                     const Eigen::Vector3d& theta_j) {
  return (u_j - u_i) - (b.lever_first * theta_i + b.lever_second * theta_j).cross(b.normal) -
         b.free_offset;
}

inline BondResponse parallel_bond_response(const BondParameters& b, const Eigen::Vector3d& u_i,
                                           const Eigen::Vector3d& theta_i,
                                           const Eigen::Vector3d& u_j,
                                           const Eigen::Vector3d& theta_j) {
  const Eigen::Vector3d& n = b.normal;
  const Eigen::Vector3d du = contact_relative_displacement(b, u_i, theta_i, u_j, theta_j);
  const double du_n = n.dot(du);
  const Eigen::Vector3d du_s = du - du_n * n;
  const Eigen::Vector3d dtheta = theta_j - theta_i;
  const double dtheta_n = n.dot(dtheta);
  const Eigen::Vector3d dtheta_s = dtheta - dtheta_n * n;

  const Eigen::Vector3d f_s = shear_force(b, du_s);
  const Eigen::Vector3d force = b.normal_stiffness * du_n * n + f_s;
  const Eigen::Vector3d moment =
      b.twisting_stiffness * dtheta_n * n + b.bending_stiffness * dtheta_s;
  const Eigen::Vector3d n_cross_f = n.cross(force);
  BondResponse r;
  r.force_on_first = force;
  r.torque_on_first = b.lever_first * n_cross_f + moment;
  r.torque_on_second = b.lever_second * n_cross_f - moment;
  r.energy = 0.5 * (b.normal_stiffness * du_n * du_n + f_s.dot(du_s) +
                    b.twisting_stiffness * dtheta_n * dtheta_n +
                    b.bending_stiffness * dtheta_s.squaredNorm());
  return r;
}

/// The bond's 12x12 stiffness over (u_i, theta_i, u_j, theta_j): generalized forces = -K q.
/// Built from the same kinematics as parallel_bond_response (tests check K q against it).
/// Defined in core/parallel_bond.cpp: its fixed-size products cost every file that includes this
/// header about a second of compile time when inline.
Matrix12d parallel_bond_stiffness(const BondParameters& b);

}  // namespace plydem
