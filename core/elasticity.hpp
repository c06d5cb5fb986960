#pragma once
/// \file
/// Elasticity of a ply and of a laminate: the 3D stiffness of a transversely isotropic ply
/// (eq. 23 with the C55 row, ERRATA §2), the plane-stress reduced stiffness Q (eq. 29), its
/// rotation to a ply angle (eq. 32), and the in-plane engineering constants from a membrane
/// stiffness (ERRATA conventions). Voigt order 3D: (11, 22, 33, 23, 13, 12) with engineering shear
/// strains; in-plane: (xx, yy, xy) with gamma_xy = 2 eps_xy. Angles in radians, counter-clockwise
/// from +x.

#include <Eigen/Dense>
#include <vector>

#include "core/material.hpp"

namespace plydem {

using Matrix6d = Eigen::Matrix<double, 6, 6>;

/// 3D compliance of the ply in its material axes (1 = fibre). Not validated: validate() uses it.
Matrix6d compliance_3d(const Material& material);
/// 3D stiffness of the ply in its material axes: eq. (23) with the C55 = G12 row.
/// Throws plydem::Error unless validate(material) passes.
Matrix6d stiffness_3d(const Material& material);
/// Plane-stress reduced stiffness Q in material axes, eq. (29).
/// Throws plydem::Error unless validate(material) passes.
Eigen::Matrix3d reduced_stiffness(const Material& material);
/// Q-bar: a plane-stress stiffness (xx, yy, xy) of a ply whose fibre lies at `ply_angle` from +x,
/// eq. (32) in matrix form.
Eigen::Matrix3d rotate_reduced_stiffness(const Eigen::Matrix3d& Q, double ply_angle);

/// In-plane engineering constants from a membrane stiffness (Q-bar, or A/h of a laminate).
struct InPlaneConstants {
  double Ex = 0, Ey = 0, nu_xy = 0, nu_yx = 0, Gxy = 0;
  /// Shear coupling under sigma_x alone: gamma_xy / eps_x = a16 / a11.
  double shear_coupling_x = 0;
};
/// Ex = 1/a11, Ey = 1/a22, nu_xy = -a12/a11, nu_yx = -a12/a22, Gxy = 1/a66 with a = inverse of the
/// 3x3 stiffness. Throws plydem::Error if the stiffness is not positive definite.
InPlaneConstants in_plane_constants(const Eigen::Matrix3d& membrane_stiffness);

/// One ply of a laminate.
struct Ply {
  Material material;
  double angle = 0;      ///< fibre angle from +x [rad]
  double thickness = 0;  ///< [m]
};

/// Classical lamination theory: extensional stiffness A = sum Q-bar_k t_k [N/m].
Eigen::Matrix3d laminate_extensional_stiffness(const std::vector<Ply>& plies);
/// The laminate's in-plane constants from A/h.
InPlaneConstants laminate_constants(const std::vector<Ply>& plies);

/// True if the symmetric matrix is positive definite (Cholesky succeeds, smallest eigenvalue > 0).
bool is_positive_definite(const Eigen::MatrixXd& symmetric);

}  // namespace plydem
