#include "core/homogenizer.hpp"

#include <fmt/format.h>

#include <cmath>

#include "core/error.hpp"
#include "core/parallel_bond.hpp"

namespace plydem {
namespace {

// Energy Hessian of the cell over z = (6 macro strains, 6 dofs per basis particle).
Eigen::MatrixXd cell_hessian(const UnitCell& cell, const std::vector<FamilyStiffness>& families) {
  require(!cell.basis.empty() && cell.radius.size() == cell.basis.size(),
          "unit cell: basis and radius lists must be non-empty and of equal size");
  require(cell.volume > 0 && std::isfinite(cell.volume), "unit cell: volume must be positive");
  require(static_cast<int>(families.size()) >= cell.family_count,
          fmt::format("unit cell has {} bond families but {} stiffnesses were given",
                      cell.family_count, families.size()));
  const int n = static_cast<int>(cell.basis.size());
  const int size = 6 + 6 * n;
  Eigen::MatrixXd hessian = Eigen::MatrixXd::Zero(size, size);
  for (int b = 0; b < static_cast<int>(cell.bonds.size()); ++b) {
    const UnitCell::Bond& bond = cell.bonds[b];
    // Messages are formatted only on failure: the calibration evaluates cells many times.
    if (!(bond.first >= 0 && bond.first < n && bond.second >= 0 && bond.second < n &&
          bond.family >= 0 && bond.family < cell.family_count)) {
      throw Error(fmt::format("unit-cell bond {} refers to a missing particle or family", b));
    }
    const Matrix12d k = parallel_bond_stiffness(cell_bond(cell, b, families[bond.family]));
    // Bond dofs (u_i, theta_i, u_j, theta_j) as a linear map of z: u = E x + fluctuation.
    Eigen::MatrixXd map = Eigen::MatrixXd::Zero(12, size);
    const Eigen::Vector3d x_i = cell.basis[bond.first];
    const Eigen::Vector3d x_j =
        cell.basis[bond.second] + cell.lattice_vectors * bond.image.cast<double>();
    for (int s = 0; s < 6; ++s) {
      const Eigen::Matrix3d e = voigt_unit_strain(s);
      map.block<3, 1>(0, s) = e * x_i;
      map.block<3, 1>(6, s) = e * x_j;
    }
    map.block<6, 6>(0, 6 + 6 * bond.first) += Eigen::Matrix<double, 6, 6>::Identity();
    map.block<6, 6>(6, 6 + 6 * bond.second) += Eigen::Matrix<double, 6, 6>::Identity();
    hessian += map.transpose() * k * map;
  }
  return hessian;
}

// The static condensation of a cell's internal dofs (all spins and shifts except the first
// particle's translation, which only moves the cell rigidly), shared by relaxed_stiffness and
// relaxed_motion: K_qq's eigen-decomposition, with the inverse of each eigenvalue (0 for the zero
// modes, e.g. a layer's out-of-plane motion, which carry no coupling to in-plane strains: a
// pseudo-inverse drops them).
struct Condensation {
  Eigen::MatrixXd hessian;  // over (6 strains, 6 dofs per particle)
  Eigen::MatrixXd vectors;  // eigenvectors of K_qq
  Eigen::VectorXd inverse;  // 1 / eigenvalue, 0 for a zero mode
  int internal = 0;         // number of internal dofs; they start at row 9 of the Hessian
  Eigen::MatrixXd k_eq() const { return hessian.block(0, 9, 6, internal); }
};

Condensation condense(const UnitCell& cell, const std::vector<FamilyStiffness>& families) {
  Condensation c;
  c.hessian = cell_hessian(cell, families);
  c.internal = static_cast<int>(c.hessian.rows()) - 9;
  const Eigen::MatrixXd k_qq = c.hessian.bottomRightCorner(c.internal, c.internal);
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(k_qq);
  const Eigen::VectorXd lambda = eig.eigenvalues();
  const double cutoff = 1e-12 * std::max(lambda.cwiseAbs().maxCoeff(), 1e-300);
  c.inverse = Eigen::VectorXd::Zero(c.internal);
  for (int i = 0; i < c.internal; ++i) {
    require(lambda(i) > -cutoff,
            "unit cell: the internal stiffness is indefinite (a negative bond stiffness makes the "
            "lattice unstable)");
    if (lambda(i) > cutoff) c.inverse(i) = 1.0 / lambda(i);
  }
  c.vectors = eig.eigenvectors();
  return c;
}

}  // namespace

BondParameters cell_bond(const UnitCell& cell, int b, const FamilyStiffness& k) {
  const UnitCell::Bond& bond = cell.bonds[b];
  const Eigen::Vector3d branch = cell.branch(b);
  const double length = branch.norm();
  if (!(length > 0)) throw Error(fmt::format("unit-cell bond {} has zero length", b));
  const double gap = length - cell.radius[bond.first] - cell.radius[bond.second];
  BondParameters p;
  p.normal = branch / length;
  p.lever_first = cell.radius[bond.first] + 0.5 * gap;
  p.lever_second = cell.radius[bond.second] + 0.5 * gap;
  p.normal_stiffness = k.normal;
  p.shear_stiffness = k.shear;
  p.bending_stiffness = k.bending;
  p.twisting_stiffness = k.twisting;
  return p;
}

Eigen::Matrix3d voigt_unit_strain(int k) {
  Eigen::Matrix3d e = Eigen::Matrix3d::Zero();
  switch (k) {
    case 0:
      e(0, 0) = 1;
      break;
    case 1:
      e(1, 1) = 1;
      break;
    case 2:
      e(2, 2) = 1;
      break;
    case 3:
      e(1, 2) = e(2, 1) = 0.5;
      break;
    case 4:
      e(0, 2) = e(2, 0) = 0.5;
      break;
    default:
      e(0, 1) = e(1, 0) = 0.5;
      break;
  }
  return e;
}

Eigen::Vector3d UnitCell::branch(int b) const {
  const Bond& bond = bonds[b];
  return basis[bond.second] + lattice_vectors * bond.image.cast<double>() - basis[bond.first];
}

Matrix6d affine_stiffness(const UnitCell& cell, const std::vector<FamilyStiffness>& families) {
  return cell_hessian(cell, families).topLeftCorner<6, 6>() / cell.volume;
}

Matrix6d relaxed_stiffness(const UnitCell& cell, const std::vector<FamilyStiffness>& families) {
  const Condensation c = condense(cell, families);
  const Eigen::MatrixXd projected = c.k_eq() * c.vectors;
  const Eigen::MatrixXd condensed =
      c.hessian.topLeftCorner(6, 6) - projected * c.inverse.asDiagonal() * projected.transpose();
  return condensed / cell.volume;
}

CellMotion relaxed_motion(const UnitCell& cell, const std::vector<FamilyStiffness>& families,
                          const Vector6d& strain) {
  require(strain.allFinite(), "relaxed motion: the macroscopic strain is not finite");
  const Condensation c = condense(cell, families);
  // Minimum energy over the internal dofs q at fixed strain: K_qq q = -K_qe strain.
  const Eigen::VectorXd q =
      -(c.vectors *
        (c.inverse.asDiagonal() * (c.vectors.transpose() * (c.k_eq().transpose() * strain))));
  CellMotion motion;
  for (int k = 0; k < 6; ++k) motion.strain += strain(k) * voigt_unit_strain(k);
  const int n = static_cast<int>(cell.basis.size());
  motion.fluctuation.assign(n, Eigen::Vector3d::Zero());
  motion.rotation.assign(n, Eigen::Vector3d::Zero());
  // q starts with the first particle's rotation, then (translation, rotation) of the others.
  motion.rotation[0] = q.head<3>();
  for (int i = 1; i < n; ++i) {
    motion.fluctuation[i] = q.segment<3>(6 * i - 3);
    motion.rotation[i] = q.segment<3>(6 * i);
  }
  return motion;
}

Eigen::Vector3d CellMotion::displacement(const UnitCell& cell, int particle,
                                         const Eigen::Vector3i& image) const {
  const Eigen::Vector3d x = cell.basis[particle] + cell.lattice_vectors * image.cast<double>();
  return strain * x + fluctuation[particle];
}

Eigen::Matrix3d in_plane_block(const Matrix6d& c) {
  const int idx[3] = {0, 1, 5};
  Eigen::Matrix3d q;
  for (int r = 0; r < 3; ++r)
    for (int s = 0; s < 3; ++s) q(r, s) = c(idx[r], idx[s]);
  return q;
}

double relative_difference(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  return (a - b).norm() / b.norm();
}

}  // namespace plydem
