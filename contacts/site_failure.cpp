#include "contacts/site_failure.hpp"

#include <fmt/format.h>
#include <cmath>
#include <cstddef>

#include "contacts/bond_kernel.hpp"
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

std::vector<SiteFailure> site_failures(const Particles& particles, const Bonds& bonds,
                                       std::span<const double> ply_angles,
                                       FailureCriterion criterion, const LaminaStrength& strength) {
  const std::vector<Eigen::Matrix3d> stress = particle_stresses(particles, bonds);
  std::vector<SiteFailure> sites(stress.size());
  for (int i = 0; i < particles.size(); ++i) {
    const int ply = particles.ply(i);
    require(ply >= 0 && static_cast<std::size_t>(ply) < ply_angles.size(),
            fmt::format("site failure: particle {} is in ply {}, and {} ply angle(s) were given", i,
                        ply, ply_angles.size()));
    const double angle = ply_angles[static_cast<std::size_t>(ply)];
    const Eigen::Matrix3d& sigma = stress[static_cast<std::size_t>(i)];
    SiteFailure& site = sites[static_cast<std::size_t>(i)];
    site.failure =
        ply_failure(criterion, to_ply_axes(sigma(0, 0), sigma(1, 1), sigma(0, 1), angle), strength);
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
