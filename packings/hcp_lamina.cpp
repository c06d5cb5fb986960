#include "packings/hcp_lamina.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/error.hpp"
#include "core/progress.hpp"

namespace plydem {
namespace {

// Bonded pairs must be this much closer than any other pair.
constexpr double kShellSeparation = 1.01;

}  // namespace

double HcpLamina::close_packed_layer_spacing(double spacing) {
  return spacing * std::sqrt(2.0 / 3.0);
}

std::pair<double, double> HcpLamina::layer_spacing_limits() {
  // In units of l: the stacked A and A' particles, 2c apart, beyond the longest bond (l for
  // c <= l sqrt(2/3), where this bound lies); the second in-plane shell, sqrt(3) l, beyond the
  // inclined bond sqrt(1/3 + c^2).
  const double lower = kShellSeparation / 2.0;
  const double upper = std::sqrt(3.0 / (kShellSeparation * kShellSeparation) - 1.0 / 3.0);
  return {lower, upper};
}

HcpLamina::HcpLamina(double spacing, double layer_spacing, double lattice_angle)
    : spacing_(spacing), layer_spacing_(layer_spacing), lattice_angle_(lattice_angle) {
  require(std::isfinite(spacing) && spacing > 0,
          fmt::format("HCP lamina: particle spacing must be positive, got {}", spacing));
  require(std::isfinite(lattice_angle), "HCP lamina: lattice angle is not finite");
  const auto [lower, upper] = layer_spacing_limits();
  require(std::isfinite(layer_spacing) && layer_spacing > lower * spacing &&
              layer_spacing < upper * spacing,
          fmt::format("HCP lamina: layer spacing c = {:.6g} particle radii must lie between {:.6g} "
                      "and {:.6g} radii (beyond them other pairs are as close as the bonded "
                      "neighbours)",
                      2.0 * layer_spacing / spacing, 2.0 * lower, 2.0 * upper));
}

double HcpLamina::inclined_bond_length() const {
  return std::sqrt(spacing_ * spacing_ / 3.0 + layer_spacing_ * layer_spacing_);
}

double HcpLamina::cell_area() const {
  return std::sqrt(3.0) / 2.0 * spacing_ * spacing_;
}

double HcpLamina::family_angle(int family) const {
  require(family >= 0 && family < kFamilyCount, "HCP lamina: bond family out of range");
  const double third = std::numbers::pi / 3.0;
  return is_inclined(family) ? lattice_angle_ + third / 2.0 + (family - 3) * third
                             : lattice_angle_ + family * third;
}

Eigen::Vector3d HcpLamina::family_direction(int family) const {
  const double angle = family_angle(family);
  if (!is_inclined(family)) return {std::cos(angle), std::sin(angle), 0.0};
  const double projection = spacing_ / std::sqrt(3.0);
  return Eigen::Vector3d(projection * std::cos(angle), projection * std::sin(angle),
                         layer_spacing_) /
         inclined_bond_length();
}

Eigen::Vector3d HcpLamina::a1() const {
  return spacing_ * Eigen::Vector3d(std::cos(lattice_angle_), std::sin(lattice_angle_), 0.0);
}

Eigen::Vector3d HcpLamina::a2() const {
  const double angle = lattice_angle_ + std::numbers::pi / 3.0;
  return spacing_ * Eigen::Vector3d(std::cos(angle), std::sin(angle), 0.0);
}

Eigen::Vector3d HcpLamina::layer_offset(int layer) const {
  require(layer >= 0 && layer < kLayerCount, "HCP lamina: layer out of range");
  const Eigen::Vector3d up(0, 0, layer_spacing_ * layer);
  return layer == 1 ? Eigen::Vector3d((a1() + a2()) / 3.0 + up) : up;
}

int HcpLamina::family_of(const Eigen::Vector3d& branch, int layer_i, int layer_j) const {
  const double tol = 1e-6;
  if (layer_i == layer_j) {
    if (std::abs(branch.norm() / spacing_ - 1.0) < tol) {
      for (int f = 0; f < kInPlaneFamilyCount; ++f) {
        if (std::abs(std::abs(branch.normalized().dot(family_direction(f))) - 1.0) < tol) return f;
      }
    }
  } else if (std::abs(layer_i - layer_j) == 1 &&
             std::abs(branch.norm() / inclined_bond_length() - 1.0) < tol) {
    const Eigen::Vector3d projection(branch.x(), branch.y(), 0.0);
    for (int f = kInPlaneFamilyCount; f < kFamilyCount; ++f) {
      const double angle = family_angle(f);
      const Eigen::Vector3d axis(std::cos(angle), std::sin(angle), 0.0);
      if (std::abs(std::abs(projection.normalized().dot(axis)) - 1.0) < tol) return f;
    }
  }
  throw Error(fmt::format(
      "a pair {:.4g} x {:.4g} x {:.4g} diameters apart between layers {} and {} is not a bond of "
      "the HCP lamina",
      branch.x() / spacing_, branch.y() / spacing_, branch.z() / spacing_, layer_i, layer_j));
}

UnitCell HcpLamina::unit_cell(double thickness) const {
  require(std::isfinite(thickness) && thickness > 0,
          fmt::format("HCP lamina: thickness must be positive, got {}", thickness));
  UnitCell cell;
  cell.lattice_vectors.col(0) = a1();
  cell.lattice_vectors.col(1) = a2();
  cell.lattice_vectors.col(2) = Eigen::Vector3d(0, 0, thickness);
  for (int layer = 0; layer < kLayerCount; ++layer) {
    cell.basis.push_back(layer_offset(layer));
    cell.radius.push_back(0.5 * spacing_);
  }
  cell.volume = cell_area() * thickness;
  cell.family_count = kFamilyCount;
  for (int layer = 0; layer < kLayerCount; ++layer) {
    // Family 2 (+120 deg) = a2 - a1.
    cell.bonds.push_back({layer, layer, Eigen::Vector3i(1, 0, 0), 0});
    cell.bonds.push_back({layer, layer, Eigen::Vector3i(0, 1, 0), 1});
    cell.bonds.push_back({layer, layer, Eigen::Vector3i(-1, 1, 0), 2});
  }
  // The three B particles above an A particle, and the three A' particles above a B particle
  // (the nearest images of the next layer's basis particle).
  const Eigen::Vector3i images[3] = {{0, 0, 0}, {-1, 0, 0}, {0, -1, 0}};
  const Eigen::Vector3i images_up[3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  for (int k = 0; k < 3; ++k) {
    cell.bonds.push_back({0, 1, images[k], 0});
    cell.bonds.push_back({1, 2, images_up[k], 0});
  }
  for (size_t b = 9; b < cell.bonds.size(); ++b) {
    UnitCell::Bond& bond = cell.bonds[b];
    bond.family = family_of(cell.branch(static_cast<int>(b)), bond.first, bond.second);
  }
  return cell;
}

UnitCell HcpLamina::bulk_unit_cell() const {
  UnitCell cell;
  cell.lattice_vectors.col(0) = a1();
  cell.lattice_vectors.col(1) = a2();
  cell.lattice_vectors.col(2) = Eigen::Vector3d(0, 0, 2.0 * layer_spacing_);
  cell.basis = {layer_offset(0), layer_offset(1)};
  cell.radius = {0.5 * spacing_, 0.5 * spacing_};
  cell.volume = 2.0 * cell_area() * layer_spacing_;  // 2 sqrt(3) R^2 c per particle
  cell.family_count = kFamilyCount;
  for (int p = 0; p < 2; ++p) {
    cell.bonds.push_back({p, p, Eigen::Vector3i(1, 0, 0), 0});
    cell.bonds.push_back({p, p, Eigen::Vector3i(0, 1, 0), 1});
    cell.bonds.push_back({p, p, Eigen::Vector3i(-1, 1, 0), 2});
  }
  // B above A, and A of the next period above B.
  const Eigen::Vector3i images[3] = {{0, 0, 0}, {-1, 0, 0}, {0, -1, 0}};
  const Eigen::Vector3i images_up[3] = {{0, 0, 1}, {1, 0, 1}, {0, 1, 1}};
  for (int k = 0; k < 3; ++k) {
    cell.bonds.push_back({0, 1, images[k], 0});
    cell.bonds.push_back({1, 0, images_up[k], 0});
  }
  for (size_t b = 6; b < cell.bonds.size(); ++b) {
    // Layers 0 and 1 are adjacent in either order; family_of needs only that.
    cell.bonds[b].family = family_of(cell.branch(static_cast<int>(b)), 0, 1);
  }
  return cell;
}

HcpLamina::Sites HcpLamina::fill_rectangle(double length, double width) const {
  const double r = 0.5 * spacing_;
  require(length >= spacing_ && width >= spacing_,
          fmt::format("a {} x {} m rectangle cannot hold a particle of diameter {} m", length,
                      width, spacing_));
  Eigen::Matrix2d basis;
  basis << a1().head<2>(), a2().head<2>();
  const Eigen::Matrix2d inverse = basis.inverse();
  const double tol = 1e-9 * spacing_;
  struct Site {
    Eigen::Vector3d x;
    int layer;
  };
  std::vector<Site> sites;
  for (int layer = 0; layer < kLayerCount; ++layer) {
    const Eigen::Vector3d offset = layer_offset(layer);
    const Eigen::Vector2d origin = Eigen::Vector2d(r, r) + offset.head<2>();
    // Lattice-index bounds from the rectangle's corners.
    double lo[2] = {1e300, 1e300}, hi[2] = {-1e300, -1e300};
    for (double x : {0.0, length}) {
      for (double y : {0.0, width}) {
        const Eigen::Vector2d ij = inverse * (Eigen::Vector2d(x, y) - origin);
        for (int k = 0; k < 2; ++k) {
          lo[k] = std::min(lo[k], ij(k));
          hi[k] = std::max(hi[k], ij(k));
        }
      }
    }
    const double count = 3.0 * (hi[0] - lo[0] + 3) * (hi[1] - lo[1] + 3);
    require(count < 5e8, fmt::format("the coupon would need about {:.3g} lattice sites", count));
    const size_t first = sites.size();
    const long first_row = static_cast<long>(std::floor(lo[0])) - 1;
    const long last_row = static_cast<long>(std::ceil(hi[0])) + 1;
    ProgressMeter meter("building the coupon: packing",
                        static_cast<double>(last_row - first_row + 1), "lattice rows");
    for (long i = first_row; i <= last_row; ++i) {
      meter.update(static_cast<double>(i - first_row));
      for (long j = static_cast<long>(std::floor(lo[1])) - 1;
           j <= static_cast<long>(std::ceil(hi[1])) + 1; ++j) {
        const Eigen::Vector2d p =
            origin + static_cast<double>(i) * basis.col(0) + static_cast<double>(j) * basis.col(1);
        if (p.x() >= r - tol && p.x() <= length - r + tol && p.y() >= r - tol &&
            p.y() <= width - r + tol) {
          sites.push_back({Eigen::Vector3d(p.x(), p.y(), offset.z()), layer});
        }
      }
    }
    // Row-major order along x within rows of y: neighbours stay close in memory.
    std::sort(sites.begin() + static_cast<long>(first), sites.end(),
              [&](const Site& a, const Site& b) {
                if (std::abs(a.x.y() - b.x.y()) > tol) return a.x.y() < b.x.y();
                return a.x.x() < b.x.x();
              });
  }
  Sites result;
  result.position = PositionArray::Zero(static_cast<long>(sites.size()), 3);
  result.layer = Eigen::ArrayXi::Zero(static_cast<long>(sites.size()));
  for (size_t k = 0; k < sites.size(); ++k) {
    result.position.row(static_cast<long>(k)) = sites[k].x.transpose().array();
    result.layer(static_cast<long>(k)) = sites[k].layer;
  }
  return result;
}

HcpLamina::Graph HcpLamina::bond_graph(const Sites& sites) const {
  require(sites.layer.size() == sites.position.rows(),
          "HCP lamina: one layer index per particle is needed");
  // Every bond is at most max(l, sqrt(l^2/3 + c^2)) long; the next shell is at least 1% farther
  // (layer_spacing_limits), so a cutoff just above the longest bond finds exactly the bonds.
  const double longest = std::max(spacing_, inclined_bond_length());
  const Eigen::ArrayXd radius = Eigen::ArrayXd::Constant(sites.position.rows(), 0.5 * spacing_);
  Graph graph;
  graph.pairs = find_contact_pairs(sites.position, radius, longest / spacing_ * (1.0 + 1e-6));
  graph.family.reserve(graph.pairs.size());
  for (const auto& [i, j] : graph.pairs) {
    const Eigen::Vector3d d = (sites.position.row(j) - sites.position.row(i)).matrix().transpose();
    graph.family.push_back(family_of(d, sites.layer(i), sites.layer(j)));
  }
  return graph;
}

}  // namespace plydem
