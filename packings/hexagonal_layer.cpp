#include "packings/hexagonal_layer.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/error.hpp"
#include "packings/planar_lattice.hpp"

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
  return plydem::fill_rectangle(spacing_ * family_direction(0).head<2>(),
                                spacing_ * family_direction(1).head<2>(), spacing_, length, width);
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
