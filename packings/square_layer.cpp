#include "packings/square_layer.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/error.hpp"
#include "packings/planar_lattice.hpp"

namespace plydem {

SquareLayer::SquareLayer(double spacing, double lattice_angle)
    : spacing_(spacing), lattice_angle_(lattice_angle) {
  require(std::isfinite(spacing) && spacing > 0,
          fmt::format("square layer: particle spacing must be positive, got {}", spacing));
  require(std::isfinite(lattice_angle), "square layer: lattice angle is not finite");
}

double SquareLayer::cell_area() const {
  return spacing_ * spacing_;
}

double SquareLayer::family_offset(int family) {
  constexpr double kQuarter = std::numbers::pi / 4.0;
  constexpr double offsets[kFamilyCount] = {0.0, 2 * kQuarter, kQuarter, 3 * kQuarter};
  require(family >= 0 && family < kFamilyCount,
          fmt::format("square layer: no bond family {}", family));
  return offsets[family];
}

Eigen::Vector3d SquareLayer::family_direction(int family) const {
  const double angle = lattice_angle_ + family_offset(family);
  return {std::cos(angle), std::sin(angle), 0.0};
}

double SquareLayer::family_length(int family) const {
  return family < 2 ? spacing_ : std::numbers::sqrt2 * spacing_;
}

int SquareLayer::family_of(const Eigen::Vector3d& direction) const {
  for (int f = 0; f < kFamilyCount; ++f) {
    if (std::abs(std::abs(direction.normalized().dot(family_direction(f))) - 1.0) < 1e-9) return f;
  }
  throw Error(fmt::format("direction ({}, {}, {}) is not a bond direction of the square layer",
                          direction.x(), direction.y(), direction.z()));
}

UnitCell SquareLayer::unit_cell(double thickness) const {
  UnitCell cell;
  cell.lattice_vectors.col(0) = spacing_ * family_direction(0);
  cell.lattice_vectors.col(1) = spacing_ * family_direction(1);
  cell.lattice_vectors.col(2) = Eigen::Vector3d(0, 0, thickness);
  cell.basis = {Eigen::Vector3d::Zero()};
  cell.radius = {0.5 * spacing_};
  cell.volume = cell_area() * thickness;
  cell.family_count = kFamilyCount;
  // Diagonals: family 2 (+45 deg) = a1 + a2, family 3 (135 deg) = a2 - a1.
  cell.bonds = {{0, 0, Eigen::Vector3i(1, 0, 0), 0},
                {0, 0, Eigen::Vector3i(0, 1, 0), 1},
                {0, 0, Eigen::Vector3i(1, 1, 0), 2},
                {0, 0, Eigen::Vector3i(-1, 1, 0), 3}};
  return cell;
}

PositionArray SquareLayer::fill_rectangle(double length, double width) const {
  return plydem::fill_rectangle(spacing_ * family_direction(0).head<2>(),
                                spacing_ * family_direction(1).head<2>(), spacing_, length, width);
}

SquareLayer::Graph SquareLayer::bond_graph(const PositionArray& position) const {
  // Axial neighbours are at l, diagonal ones at l sqrt(2) (contact radius sqrt(2) on the sum of
  // radii l); the next shell is at 2 l.
  const Eigen::ArrayXd radius = Eigen::ArrayXd::Constant(position.rows(), 0.5 * spacing_);
  Graph graph;
  graph.pairs = find_contact_pairs(position, radius, std::numbers::sqrt2 * (1.0 + 1e-6));
  graph.family.reserve(graph.pairs.size());
  for (const auto& [i, j] : graph.pairs) {
    const Eigen::Vector3d d = (position.row(j) - position.row(i)).matrix().transpose();
    graph.family.push_back(family_of(d));
  }
  return graph;
}

}  // namespace plydem
