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

namespace {

// Each particle's sums over its intact, undamaged bonds: spread = sum r r^T and moved = sum du r^T,
// in-plane, r the reference branch vector and du the relative displacement (from either end: both
// change sign, the products do not).
struct SiteSums {
  std::vector<Eigen::Matrix2d> spread, moved;
  // Site k's in-plane strain (site_strains), NaN where its bonds do not span the plane.
  Eigen::Vector3d strain(std::size_t k) const;
};

SiteSums site_sums(const Particles& particles, const Bonds& bonds, bool subtract_free_offsets) {
  const auto n = static_cast<std::size_t>(particles.size());
  SiteSums sums{std::vector<Eigen::Matrix2d>(n, Eigen::Matrix2d::Zero()),
                std::vector<Eigen::Matrix2d>(n, Eigen::Matrix2d::Zero())};
  for (int b = 0; b < bonds.size(); ++b) {
    if (bonds.is_broken(b) || bonds.damage(b) > 0) continue;  // open, or softening in a crack
    const int i = bonds.first(b), j = bonds.second(b);
    const Eigen::Vector2d r = (particles.reference_position.row(j).head<2>() -
                               particles.reference_position.row(i).head<2>())
                                  .transpose();
    Eigen::Vector2d du =
        (particles.displacement.row(j).head<2>() - particles.displacement.row(i).head<2>())
            .transpose();
    if (subtract_free_offsets) du -= bonds.free_offset.row(b).head<2>().transpose().matrix();
    for (int end : {i, j}) {
      sums.spread[static_cast<std::size_t>(end)] += r * r.transpose();
      sums.moved[static_cast<std::size_t>(end)] += du * r.transpose();
    }
  }
  return sums;
}

// Whether a site's bonds span the plane (the spread is not singular relative to its own size).
bool spans_plane(const Eigen::Matrix2d& spread) {
  return spread.determinant() > 1e-10 * spread.trace() * spread.trace();
}

// The in-plane stress of a site whose bonds all lie along one line d (a strand: the particles a
// crack left hanging by their bonds along the fibre, say): the uniaxial stress along d that its
// stretch eps_dd = d^T G d gives, E_d eps_dd with E_d the ply's modulus along d; zero for a site
// without bonds.
Eigen::Vector3d strand_stress(const Eigen::Matrix2d& spread, const Eigen::Matrix2d& moved,
                              const Eigen::Matrix3d& q_bar) {
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eigen(spread);
  const double largest = eigen.eigenvalues()(1);
  if (!(largest > 0)) return Eigen::Vector3d::Zero();
  const Eigen::Vector2d d = eigen.eigenvectors().col(1);
  const double stretch = d.dot(moved * d) / largest;
  // A uniaxial stress s along d is s v in (xx, yy, xy), v = (dx^2, dy^2, dx dy); the stretch along
  // d is v . (Q-bar^-1 s v), so E_d = 1 / (v . Q-bar^-1 v).
  const Eigen::Vector3d v(d.x() * d.x(), d.y() * d.y(), d.x() * d.y());
  const double modulus = 1.0 / v.dot(q_bar.ldlt().solve(v));
  return modulus * stretch * v;
}

Eigen::Vector3d SiteSums::strain(std::size_t k) const {
  if (!spans_plane(spread[k]))
    return Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
  const Eigen::Matrix2d g = moved[k] * spread[k].inverse();
  return {g(0, 0), g(1, 1), g(0, 1) + g(1, 0)};
}

}  // namespace

std::vector<Eigen::Vector3d> site_strains(const Particles& particles, const Bonds& bonds) {
  const SiteSums sums = site_sums(particles, bonds, true);
  std::vector<Eigen::Vector3d> strain(sums.spread.size());
  for (std::size_t k = 0; k < strain.size(); ++k) strain[k] = sums.strain(k);
  return strain;
}

std::vector<PlyStress> site_ply_stresses(const Particles& particles, const Bonds& bonds,
                                         std::span<const double> ply_angles,
                                         const Material& material,
                                         std::span<const double> plastic_shear,
                                         bool subtract_free_offsets) {
  require(
      plastic_shear.empty() || plastic_shear.size() == static_cast<std::size_t>(particles.size()),
      fmt::format("site stress: {} plastic shear strains for {} particles", plastic_shear.size(),
                  particles.size()));
  const SiteSums sums = site_sums(particles, bonds, subtract_free_offsets);
  const Eigen::Matrix3d q = reduced_stiffness(material);
  std::vector<Eigen::Matrix3d> q_bar(ply_angles.size());
  for (std::size_t ply = 0; ply < ply_angles.size(); ++ply)
    q_bar[ply] = rotate_reduced_stiffness(q, ply_angles[ply]);
  std::vector<PlyStress> stresses(sums.spread.size());
  for (int i = 0; i < particles.size(); ++i) {
    const int ply = particles.ply(i);
    require(ply >= 0 && static_cast<std::size_t>(ply) < ply_angles.size(),
            fmt::format("site failure: particle {} is in ply {}, and {} ply angle(s) were given", i,
                        ply, ply_angles.size()));
    const auto k = static_cast<std::size_t>(i);
    const Eigen::Matrix3d& stiffness = q_bar[static_cast<std::size_t>(ply)];
    const Eigen::Vector3d strain = sums.strain(k);
    const Eigen::Vector3d sigma = strain.allFinite()
                                      ? Eigen::Vector3d(stiffness * strain)
                                      : strand_stress(sums.spread[k], sums.moved[k], stiffness);
    stresses[k] =
        to_ply_axes(sigma(0), sigma(1), sigma(2), ply_angles[static_cast<std::size_t>(ply)]);
    // In the ply's axes the reduced stiffness does not couple shear to the normal strains.
    if (!plastic_shear.empty() && strain.allFinite())
      stresses[k].tau12 -= q(2, 2) * plastic_shear[k];
  }
  return stresses;
}

namespace {

// Each site's strengths times its factor (site_failures).
LaminaStrength site_strength(const Material& material, std::span<const double> strength_factors,
                             int i) {
  LaminaStrength strength = material.strength;
  if (strength_factors.empty()) return strength;
  const double f = strength_factors[static_cast<std::size_t>(i)];
  require(std::isfinite(f) && f > 0,
          fmt::format("site failure: particle {} has strength factor {}", i, f));
  for (double* s : {&strength.XT, &strength.XC, &strength.YT, &strength.YC, &strength.S12}) *s *= f;
  return strength;
}

void require_strength_factors(const Particles& particles,
                              std::span<const double> strength_factors) {
  require(strength_factors.empty() ||
              strength_factors.size() == static_cast<std::size_t>(particles.size()),
          fmt::format("site failure: {} strength factors for {} particles", strength_factors.size(),
                      particles.size()));
}

}  // namespace

std::vector<SiteFailure> site_failures(const Particles& particles, const Bonds& bonds,
                                       std::span<const double> ply_angles,
                                       FailureCriterion criterion, const Material& material,
                                       std::span<const double> strength_factors,
                                       std::span<const double> plastic_shear) {
  require_strength_factors(particles, strength_factors);
  const std::vector<PlyStress> stresses =
      site_ply_stresses(particles, bonds, ply_angles, material, plastic_shear);
  std::vector<SiteFailure> sites(stresses.size());
  for (int i = 0; i < particles.size(); ++i) {
    const auto k = static_cast<std::size_t>(i);
    SiteFailure& site = sites[k];
    site.failure =
        ply_failure(criterion, stresses[k], site_strength(material, strength_factors, i));
    site.crack_normal =
        crack_normal(site.failure, ply_angles[static_cast<std::size_t>(particles.ply(i))]);
  }
  return sites;
}

std::vector<SiteFailure> preloaded_site_failures(
    const Particles& particles, std::span<const PlyStress> preload, std::span<const PlyStress> unit,
    std::span<const double> ply_angles, FailureCriterion criterion, const Material& material,
    std::span<const double> strength_factors) {
  require_strength_factors(particles, strength_factors);
  const auto n = static_cast<std::size_t>(particles.size());
  require(preload.size() == n && unit.size() == n,
          fmt::format("site failure: {} preload and {} unit stresses for {} particles",
                      preload.size(), unit.size(), n));
  std::vector<SiteFailure> sites(n);
  for (int i = 0; i < particles.size(); ++i) {
    const auto k = static_cast<std::size_t>(i);
    const int ply = particles.ply(i);
    require(ply >= 0 && static_cast<std::size_t>(ply) < ply_angles.size(),
            fmt::format("site failure: particle {} is in ply {}, and {} ply angle(s) were given", i,
                        ply, ply_angles.size()));
    SiteFailure& site = sites[k];
    site.failure = preloaded_ply_failure(criterion, preload[k], unit[k],
                                         site_strength(material, strength_factors, i));
    site.crack_normal = crack_normal(site.failure, ply_angles[static_cast<std::size_t>(ply)]);
  }
  return sites;
}

namespace {

Eigen::Vector3d reference(const Particles& p, int i) {
  return p.reference_position.row(i).transpose().matrix();
}

// The lattice around a site, from its in-ply bonds in the reference configuration (broken or
// not): the spacing of the lattice's lines along a unit vector n (the smallest |l . n| of its bonds
// that have a component along n: the distance from the site's line to the next), the area of the
// lattice's cell in the layer (the smallest non-zero |l1 x l2| of two of its in-plane bonds) and
// its longest bond.
struct SiteLattice {
  double spacing = 0;
  double cell_area = 0;
  double reach = 0;
};

SiteLattice site_lattice(const Particles& particles, const Bonds& bonds, int site,
                         const Eigen::Vector3d& n) {
  std::vector<Eigen::Vector3d> branches;
  for (int b = 0; b < bonds.size(); ++b) {
    if (bonds.is_interface(b) || (bonds.first(b) != site && bonds.second(b) != site)) continue;
    const int other = bonds.first(b) == site ? bonds.second(b) : bonds.first(b);
    branches.push_back(reference(particles, other) - reference(particles, site));
  }
  SiteLattice lattice;
  double spacing = std::numeric_limits<double>::infinity();
  double area = std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < branches.size(); ++k) {
    const Eigen::Vector3d& l = branches[k];
    lattice.reach = std::max(lattice.reach, l.norm());
    const double along = std::abs(l.dot(n));
    if (along > 1e-6 * l.norm()) spacing = std::min(spacing, along);
    for (std::size_t m = k + 1; m < branches.size(); ++m) {
      const double cross = std::abs(l.x() * branches[m].y() - l.y() * branches[m].x());
      if (cross > 1e-6 * l.squaredNorm()) area = std::min(area, cross);
    }
  }
  lattice.spacing = std::isfinite(spacing) ? spacing : 0;
  lattice.cell_area = std::isfinite(area) ? area : 0;
  return lattice;
}

}  // namespace

std::vector<int> bonds_across_crack(const Particles& particles, const Bonds& bonds, int site,
                                    const Eigen::Vector3d& normal) {
  require(site >= 0 && site < particles.size(),
          fmt::format("a crack at particle {}, of {}", site, particles.size()));
  require(std::abs(normal.norm() - 1) < 1e-9,
          fmt::format("a crack's normal must be a unit vector (its length is {})", normal.norm()));
  std::vector<int> crossing;
  const Eigen::Vector3d xs = reference(particles, site);
  // The crack's segment in the layer: its in-plane normal and direction, and its length along
  // that direction (the cell's area over the spacing of the lattice's lines along the normal).
  const Eigen::Vector3d planar(normal.x(), normal.y(), 0);
  const bool in_layer = planar.norm() > 1e-9;
  const Eigen::Vector3d n_plane = in_layer ? Eigen::Vector3d(planar.normalized()) : planar;
  const Eigen::Vector3d t(-n_plane.y(), n_plane.x(), 0);
  const SiteLattice lattice =
      in_layer ? site_lattice(particles, bonds, site, n_plane) : SiteLattice{};
  const double half = lattice.spacing > 0 ? 0.5 * lattice.cell_area / lattice.spacing : 0;
  for (int b = 0; b < bonds.size(); ++b) {
    if (bonds.is_broken(b) || bonds.is_interface(b)) continue;  // a ply's crack stays in its ply
    const int i = bonds.first(b), j = bonds.second(b);
    if (i == site || j == site) {
      // The bond's direction from the site: bonds.normal points from the first to the second.
      const double outward = i == site ? 1.0 : -1.0;
      const Eigen::Vector3d direction(bonds.normal(b, 0), bonds.normal(b, 1), bonds.normal(b, 2));
      if (outward * normal.dot(direction) > 1e-6) crossing.push_back(b);
      continue;
    }
    if (!(half > 0)) continue;
    // Another site's bond that crosses this site's segment of the plane, in the site's layer.
    const Eigen::Vector3d xi = reference(particles, i), xj = reference(particles, j);
    const double tolerance = 1e-6 * bonds.length(b);
    if ((xi - xs).norm() > 2 * lattice.reach || std::abs(xi.z() - xs.z()) > tolerance ||
        std::abs(xj.z() - xs.z()) > tolerance)
      continue;
    const double si = n_plane.dot(xi - xs), sj = n_plane.dot(xj - xs);
    if (!(std::min(si, sj) <= tolerance && std::max(si, sj) > tolerance)) continue;
    const Eigen::Vector3d at = std::abs(si) <= tolerance ? xi
                               : std::abs(sj) <= tolerance
                                   ? xj
                                   : Eigen::Vector3d(xi + (xj - xi) * si / (si - sj));
    const double along = t.dot(at - xs);
    if (std::abs(along) <= half * (1 + 1e-6)) crossing.push_back(b);
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

BondState crack_bond_state(PlyFailureMode mode) {
  const bool compression =
      mode == PlyFailureMode::kFibreCompression || mode == PlyFailureMode::kMatrixCompression;
  return compression ? BondState::kBrokenShear : BondState::kBrokenTension;
}

OpeningSite next_opening_site(const Particles& particles, const Bonds& bonds,
                              std::vector<SiteFailure>& sites, double tie_tolerance) {
  const double never = std::numeric_limits<double>::infinity();
  while (true) {
    const int first = first_failing_site(sites);
    if (first < 0) return {};
    const double factor = sites[static_cast<std::size_t>(first)].failure.load_factor;
    // A tie within tie_tolerance goes to the lowest index, whatever the round-off.
    int chosen = first;
    for (int i = 0; i < first; ++i)
      if (sites[static_cast<std::size_t>(i)].failure.load_factor <= factor * (1 + tie_tolerance)) {
        chosen = i;
        break;
      }
    OpeningSite opening;
    opening.particle = chosen;
    opening.site = sites[static_cast<std::size_t>(chosen)];
    opening.normal = opening.site.crack_normal;
    opening.bonds = bonds_across_crack(particles, bonds, chosen, opening.normal);
    if (opening.bonds.empty()) {
      opening.normal = -opening.normal;
      opening.bonds = bonds_across_crack(particles, bonds, chosen, opening.normal);
    }
    std::erase_if(opening.bonds, [&](int b) { return bonds.damage(b) > 0; });
    if (!opening.bonds.empty()) return opening;
    sites[static_cast<std::size_t>(chosen)].failure.load_factor = never;  // open on both sides
  }
}

double crack_share(const Particles& particles, const Bonds& bonds, int site,
                   const Eigen::Vector3d& normal) {
  const SiteLattice lattice = site_lattice(particles, bonds, site, normal);
  require(lattice.spacing > 0,
          fmt::format("particle {} has no in-ply bond across its crack plane", site));
  return particles.volume(site) / lattice.spacing;
}

}  // namespace plydem
