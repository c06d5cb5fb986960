#include "contacts/site_failure.hpp"

#include <fmt/format.h>
#include <cmath>
#include <cstddef>
#include <limits>

#include "core/elasticity.hpp"
#include "core/error.hpp"

namespace plydem {

Eigen::Vector3d crack_normal(const PlyFailure& failure, double ply_angle) {
  const double c = std::cos(ply_angle), s = std::sin(ply_angle);
  if (failure.mode == PlyFailureMode::kFibreTension ||
      failure.mode == PlyFailureMode::kFibreCompression) {
    return {c, s, 0.0};
  }
  const double phi = failure.fracture_angle;
  return {-s * std::cos(phi), c * std::cos(phi), std::sin(phi)};
}

std::vector<Eigen::Vector3d> site_strains(const Particles& particles, const Bonds& bonds) {
  const auto n = static_cast<std::size_t>(particles.size());
  std::vector<Eigen::Matrix2d> spread(n, Eigen::Matrix2d::Zero());  // sum of r r^T
  std::vector<Eigen::Matrix2d> moved(n, Eigen::Matrix2d::Zero());   // sum of du r^T
  for (int b = 0; b < bonds.size(); ++b) {
    if (bonds.is_broken(b)) continue;
    const int i = bonds.first(b), j = bonds.second(b);
    const Eigen::Vector2d r = (particles.reference_position.row(j).head<2>() -
                               particles.reference_position.row(i).head<2>())
                                  .transpose();
    const Eigen::Vector2d du =
        (particles.displacement.row(j).head<2>() - particles.displacement.row(i).head<2>())
            .transpose();
    // The bond seen from either end: r and du both change sign, r r^T and du r^T do not.
    for (int end : {i, j}) {
      spread[static_cast<std::size_t>(end)] += r * r.transpose();
      moved[static_cast<std::size_t>(end)] += du * r.transpose();
    }
  }
  std::vector<Eigen::Vector3d> strain(n);
  constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  for (std::size_t k = 0; k < n; ++k) {
    const Eigen::Matrix2d& a = spread[k];
    // The bonds span the plane unless the spread is singular (relative to its own size).
    if (!(a.determinant() > 1e-10 * a.trace() * a.trace())) {
      strain[k] = Eigen::Vector3d::Constant(kNaN);
      continue;
    }
    const Eigen::Matrix2d g = moved[k] * a.inverse();
    strain[k] = Eigen::Vector3d(g(0, 0), g(1, 1), g(0, 1) + g(1, 0));
  }
  return strain;
}

std::vector<SiteFailure> site_failures(const Particles& particles, const Bonds& bonds,
                                       std::span<const double> ply_angles,
                                       FailureCriterion criterion, const Material& material) {
  const std::vector<Eigen::Vector3d> strain = site_strains(particles, bonds);
  const Eigen::Matrix3d q = reduced_stiffness(material);
  std::vector<Eigen::Matrix3d> q_bar(ply_angles.size());
  for (std::size_t ply = 0; ply < ply_angles.size(); ++ply)
    q_bar[ply] = rotate_reduced_stiffness(q, ply_angles[ply]);
  std::vector<SiteFailure> sites(strain.size());
  for (int i = 0; i < particles.size(); ++i) {
    const int ply = particles.ply(i);
    require(ply >= 0 && static_cast<std::size_t>(ply) < ply_angles.size(),
            fmt::format("site failure: particle {} is in ply {}, and {} ply angle(s) were given", i,
                        ply, ply_angles.size()));
    const auto k = static_cast<std::size_t>(i);
    SiteFailure& site = sites[k];
    if (!strain[k].allFinite()) {
      site.failure.load_factor = std::numeric_limits<double>::infinity();
      continue;
    }
    const double angle = ply_angles[static_cast<std::size_t>(ply)];
    const Eigen::Vector3d sigma = q_bar[static_cast<std::size_t>(ply)] * strain[k];
    site.failure =
        ply_failure(criterion, to_ply_axes(sigma(0), sigma(1), sigma(2), angle), material.strength);
    site.crack_normal = crack_normal(site.failure, angle);
  }
  return sites;
}

std::vector<int> bonds_across_crack(const Particles& particles, const Bonds& bonds, int site,
                                    const Eigen::Vector3d& normal) {
  require(site >= 0 && site < particles.size(),
          fmt::format("a crack at particle {}, of {}", site, particles.size()));
  require(std::abs(normal.norm() - 1) < 1e-9,
          fmt::format("a crack's normal must be a unit vector (its length is {})", normal.norm()));
  std::vector<int> crossing;
  for (int b = 0; b < bonds.size(); ++b) {
    if (bonds.is_broken(b) || (bonds.first(b) != site && bonds.second(b) != site)) continue;
    // The bond's direction from the site: bonds.normal points from the first to the second.
    const double outward = bonds.first(b) == site ? 1.0 : -1.0;
    const Eigen::Vector3d direction(bonds.normal(b, 0), bonds.normal(b, 1), bonds.normal(b, 2));
    if (outward * normal.dot(direction) > 1e-6) crossing.push_back(b);
  }
  return crossing;
}

int first_failing_site(const std::vector<SiteFailure>& sites) {
  int first = -1;
  for (std::size_t i = 0; i < sites.size(); ++i) {
    const double factor = sites[i].failure.load_factor;
    if (!std::isfinite(factor)) continue;
    if (first < 0 || factor < sites[static_cast<std::size_t>(first)].failure.load_factor) {
      first = static_cast<int>(i);
    }
  }
  return first;
}

}  // namespace plydem
