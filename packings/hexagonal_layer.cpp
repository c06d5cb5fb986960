#include "packings/hexagonal_layer.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/error.hpp"
#include "core/progress.hpp"

namespace plydem {

HexagonalLayer::HexagonalLayer(double spacing, double lattice_angle)
    : spacing_(spacing), lattice_angle_(lattice_angle) {
  require(std::isfinite(spacing) && spacing > 0,
          fmt::format("hexagonal layer: particle spacing must be positive, got {}", spacing));
  require(std::isfinite(lattice_angle), "hexagonal layer: lattice angle is not finite");
}

double HexagonalLayer::cell_area() const {
  return std::sqrt(3.0) / 2.0 * spacing_ * spacing_;
}

Eigen::Vector3d HexagonalLayer::family_direction(int family) const {
  const double angle = lattice_angle_ + family * std::numbers::pi / 3.0;
  return {std::cos(angle), std::sin(angle), 0.0};
}

int HexagonalLayer::family_of(const Eigen::Vector3d& direction) const {
  for (int f = 0; f < kFamilyCount; ++f) {
    if (std::abs(std::abs(direction.normalized().dot(family_direction(f))) - 1.0) < 1e-9) return f;
  }
  throw Error(fmt::format("direction ({}, {}, {}) is not a bond direction of the hexagonal layer",
                          direction.x(), direction.y(), direction.z()));
}

UnitCell HexagonalLayer::unit_cell(double thickness) const {
  UnitCell cell;
  cell.lattice_vectors.col(0) = spacing_ * family_direction(0);
  cell.lattice_vectors.col(1) = spacing_ * family_direction(1);
  cell.lattice_vectors.col(2) = Eigen::Vector3d(0, 0, thickness);
  cell.basis = {Eigen::Vector3d::Zero()};
  cell.radius = {0.5 * spacing_};
  cell.volume = cell_area() * thickness;
  cell.family_count = kFamilyCount;
  // Family 2 (+120 deg) = a2 - a1.
  cell.bonds = {{0, 0, Eigen::Vector3i(1, 0, 0), 0},
                {0, 0, Eigen::Vector3i(0, 1, 0), 1},
                {0, 0, Eigen::Vector3i(-1, 1, 0), 2}};
  return cell;
}

PositionArray HexagonalLayer::fill_rectangle(double length, double width) const {
  const double r = 0.5 * spacing_;
  require(length >= spacing_ && width >= spacing_,
          fmt::format("a {} x {} m rectangle cannot hold a particle of diameter {} m", length,
                      width, spacing_));
  const Eigen::Vector2d a1 = spacing_ * family_direction(0).head<2>();
  const Eigen::Vector2d a2 = spacing_ * family_direction(1).head<2>();
  Eigen::Matrix2d basis;
  basis << a1, a2;
  const Eigen::Matrix2d inverse = basis.inverse();
  const Eigen::Vector2d origin(r, r);
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
  const double count = (hi[0] - lo[0] + 3) * (hi[1] - lo[1] + 3);
  require(count < 5e8, fmt::format("the coupon would need about {:.3g} lattice sites", count));
  const double tol = 1e-9 * spacing_;
  std::vector<Eigen::Vector2d> sites;
  const long first_row = static_cast<long>(std::floor(lo[0])) - 1;
  const long last_row = static_cast<long>(std::ceil(hi[0])) + 1;
  ProgressMeter meter("building the coupon: packing", static_cast<double>(last_row - first_row + 1),
                      "lattice rows");
  for (long i = first_row; i <= last_row; ++i) {
    meter.update(static_cast<double>(i - first_row));
    for (long j = static_cast<long>(std::floor(lo[1])) - 1;
         j <= static_cast<long>(std::ceil(hi[1])) + 1; ++j) {
      const Eigen::Vector2d p = origin + static_cast<double>(i) * a1 + static_cast<double>(j) * a2;
      if (p.x() >= r - tol && p.x() <= length - r + tol && p.y() >= r - tol &&
          p.y() <= width - r + tol) {
        sites.push_back(p);
      }
    }
  }
  // Row-major order along x within rows of y: neighbours stay close in memory.
  std::sort(sites.begin(), sites.end(), [&](const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    if (std::abs(a.y() - b.y()) > tol) return a.y() < b.y();
    return a.x() < b.x();
  });
  PositionArray position = PositionArray::Zero(static_cast<long>(sites.size()), 3);
  for (size_t k = 0; k < sites.size(); ++k) {
    position(static_cast<long>(k), 0) = sites[k].x();
    position(static_cast<long>(k), 1) = sites[k].y();
  }
  return position;
}

HexagonalLayer::Graph HexagonalLayer::bond_graph(const PositionArray& position) const {
  // Touching neighbours are at exactly one spacing; the next shell is at sqrt(3) spacings.
  const Eigen::ArrayXd radius = Eigen::ArrayXd::Constant(position.rows(), 0.5 * spacing_);
  Graph graph;
  graph.pairs = find_contact_pairs(position, radius, 1.0 + 1e-6);
  graph.family.reserve(graph.pairs.size());
  for (const auto& [i, j] : graph.pairs) {
    const Eigen::Vector3d d = (position.row(j) - position.row(i)).matrix().transpose();
    graph.family.push_back(family_of(d));
  }
  return graph;
}

}  // namespace plydem
