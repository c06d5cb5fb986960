#include "core/elasticity.hpp"

#include <fmt/format.h>

#include <cmath>
#include <sstream>
#include <string>

#include "core/error.hpp"

namespace plydem {
namespace {

// Stress transformation from global (x, y) to ply axes (1, 2) for a fibre at `angle`
// counter-clockwise from +x, Voigt (xx, yy, xy) with tensor shear stress: sigma_12 = T sigma_xy.
// Engineering shear strain makes the strain transform with T^-T (Reuter's matrix folded in), so
// energy sigma . eps is the same in both frames.
Eigen::Matrix3d stress_rotation(double angle) {
  const double c = std::cos(angle);
  const double s = std::sin(angle);
  Eigen::Matrix3d T;
  T << c * c, s * s, 2 * s * c,  //
      s * s, c * c, -2 * s * c,  //
      -s * c, s * c, c * c - s * s;
  return T;
}

}  // namespace

Matrix6d compliance_3d(const Material& m) {
  // Transversely isotropic about axis 1: E3 = E2, nu13 = nu12 (ERRATA §2, Table 1), G13 = G12,
  // G23 = E2 / (2 (1 + nu23)). Engineering shear strains, so the shear entries are 1/G.
  Matrix6d S = Matrix6d::Zero();
  S(0, 0) = 1.0 / m.E1;
  S(1, 1) = 1.0 / m.E2;
  S(2, 2) = 1.0 / m.E2;
  S(0, 1) = S(1, 0) = -m.nu12 / m.E1;
  S(0, 2) = S(2, 0) = -m.nu12 / m.E1;
  S(1, 2) = S(2, 1) = -m.nu23 / m.E2;
  S(3, 3) = 1.0 / m.G23();
  S(4, 4) = 1.0 / m.G12;
  S(5, 5) = 1.0 / m.G12;
  return S;
}

Matrix6d stiffness_3d(const Material& material) {
  validate(material);
  // Inverting the compliance is the definition; eq. (23) (with its missing C55 row restored,
  // ERRATA §2) is the same matrix in closed form, which the tests check independently.
  Matrix6d C = compliance_3d(material).llt().solve(Matrix6d::Identity());
  // Make the result exactly symmetric; the solve leaves round-off of order 1e-16 relative.
  return 0.5 * (C + C.transpose());
}

Eigen::Matrix3d reduced_stiffness(const Material& material) {
  validate(material);
  // Plane stress (sigma_3 = tau_23 = tau_13 = 0) keeps the (11, 22, 12) block of the compliance;
  // its inverse is eq. (29).
  const Matrix6d S = compliance_3d(material);
  Eigen::Matrix3d S_plane;
  S_plane << S(0, 0), S(0, 1), 0.0,  //
      S(1, 0), S(1, 1), 0.0,         //
      0.0, 0.0, S(5, 5);
  Eigen::Matrix3d Q = S_plane.inverse();
  return 0.5 * (Q + Q.transpose());
}

Eigen::Matrix3d rotate_reduced_stiffness(const Eigen::Matrix3d& Q, double ply_angle) {
  // sigma_xy = T^-1 sigma_12 = T^-1 Q eps_12 = T^-1 Q T^-T eps_xy; T^-1 is T at -angle. This is
  // eq. (32) in matrix form and symmetric by construction.
  const Eigen::Matrix3d T_inverse = stress_rotation(-ply_angle);
  return T_inverse * Q * T_inverse.transpose();
}

InPlaneConstants in_plane_constants(const Eigen::Matrix3d& membrane_stiffness) {
  if (!is_positive_definite(membrane_stiffness)) {
    std::ostringstream message;
    message << "in-plane stiffness is not symmetric positive definite, so it has no engineering "
               "constants:\n"
            << membrane_stiffness;
    throw Error(message.str());
  }
  const Eigen::Matrix3d a = membrane_stiffness.llt().solve(Eigen::Matrix3d::Identity());
  InPlaneConstants k;
  k.Ex = 1.0 / a(0, 0);
  k.Ey = 1.0 / a(1, 1);
  k.nu_xy = -a(0, 1) / a(0, 0);
  k.nu_yx = -a(0, 1) / a(1, 1);
  k.Gxy = 1.0 / a(2, 2);
  k.shear_coupling_x = a(0, 2) / a(0, 0);
  return k;
}

Eigen::Matrix3d laminate_extensional_stiffness(const std::vector<Ply>& plies) {
  require(!plies.empty(), "laminate has no plies");
  Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
  for (std::size_t k = 0; k < plies.size(); ++k) {
    const Ply& ply = plies[k];
    require(std::isfinite(ply.thickness) && ply.thickness > 0,
            "laminate ply " + std::to_string(k) + ": thickness must be finite and positive, got " +
                fmt::format("{:.6g}", ply.thickness) + " m");
    require(std::isfinite(ply.angle),
            "laminate ply " + std::to_string(k) + ": angle must be finite");
    A += rotate_reduced_stiffness(reduced_stiffness(ply.material), ply.angle) * ply.thickness;
  }
  return A;
}

InPlaneConstants laminate_constants(const std::vector<Ply>& plies) {
  const Eigen::Matrix3d A = laminate_extensional_stiffness(plies);
  double h = 0;
  for (const Ply& ply : plies) h += ply.thickness;
  return in_plane_constants(A / h);
}

bool is_positive_definite(const Eigen::MatrixXd& symmetric) {
  if (symmetric.rows() == 0 || symmetric.rows() != symmetric.cols()) return false;
  if (!symmetric.allFinite()) return false;
  // Cholesky reads one triangle only; a matrix that is not symmetric has no energy form to be
  // positive, so reject it rather than judge half of it.
  const double scale = symmetric.cwiseAbs().maxCoeff();
  if (!((symmetric - symmetric.transpose()).cwiseAbs().maxCoeff() <= 1e-12 * scale)) return false;
  if (symmetric.llt().info() != Eigen::Success) return false;
  // Cholesky succeeds on some matrices whose smallest eigenvalue is round-off zero; ask the
  // eigenvalues too.
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(symmetric, Eigen::EigenvaluesOnly);
  return eigen.info() == Eigen::Success && eigen.eigenvalues().minCoeff() > 0;
}

}  // namespace plydem
