#include "core/parallel_bond.hpp"

namespace plydem {

Matrix12d parallel_bond_stiffness(const BondParameters& b) {
  const Eigen::Vector3d& n = b.normal;
  Eigen::Matrix3d n_cross;
  n_cross << 0, -n.z(), n.y(), n.z(), 0, -n.x(), -n.y(), n.x(), 0;
  const Eigen::Matrix3d nn = n * n.transpose();
  const Eigen::Matrix3d shear_projector = Eigen::Matrix3d::Identity() - nn;
  // du = B_u q, dtheta = B_theta q; -(s theta) x n = s [n]x theta.
  Eigen::Matrix<double, 3, 12> B_u;
  B_u << -Eigen::Matrix3d::Identity(), b.lever_first * n_cross, Eigen::Matrix3d::Identity(),
      b.lever_second * n_cross;
  Eigen::Matrix<double, 3, 12> B_theta;
  B_theta << Eigen::Matrix3d::Zero(), -Eigen::Matrix3d::Identity(), Eigen::Matrix3d::Zero(),
      Eigen::Matrix3d::Identity();
  const Eigen::Matrix3d D_u = b.normal_stiffness * nn + shear_stiffness_tensor(b);
  const Eigen::Matrix3d D_theta = b.twisting_stiffness * nn + b.bending_stiffness * shear_projector;
  return B_u.transpose() * D_u * B_u + B_theta.transpose() * D_theta * B_theta;
}

}  // namespace plydem
