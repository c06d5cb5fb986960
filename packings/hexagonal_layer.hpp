#pragma once
/// \file
/// A single hexagonal layer of touching equal spheres in the x-y plane (paper Sec. 3.3, Fig. 9):
/// six neighbours each, three bond families: family 0 along `lattice_angle`, family 1 at +60 deg,
/// family 2 at +120 deg (ERRATA §2 geometry; the paper's families 1, 2, 3). Geometry only: where
/// particles sit and which pairs are bonded.

#include <utility>
#include <vector>

#include "contacts/cell_list.hpp"
#include "core/homogenizer.hpp"

namespace plydem {

class HexagonalLayer {
 public:
  /// `spacing` = centre distance = particle diameter [m]; `lattice_angle` from +x [rad].
  HexagonalLayer(double spacing, double lattice_angle);

  static constexpr int kFamilyCount = 3;
  double spacing() const { return spacing_; }
  double lattice_angle() const { return lattice_angle_; }
  /// Area per particle, (sqrt(3)/2) l^2.
  double cell_area() const;
  /// Unit direction of a bond family in the specimen frame.
  Eigen::Vector3d family_direction(int family) const;
  /// The family of a bond direction (either sense); throws if it is not a lattice direction.
  int family_of(const Eigen::Vector3d& direction) const;

  /// The periodic cell: one particle, one bond per family; volume = cell_area * thickness.
  UnitCell unit_cell(double thickness) const;

  /// Lattice sites whose centres lie at least one radius inside the rectangle [0, L] x [0, W]
  /// (z = 0), the first site at (R, R).
  PositionArray fill_rectangle(double length, double width) const;

  /// Bonded pairs of nearest neighbours among `position` (cell-list search) and their families.
  struct Graph {
    std::vector<std::pair<int, int>> pairs;
    std::vector<int> family;
  };
  Graph bond_graph(const PositionArray& position) const;

 private:
  double spacing_;
  double lattice_angle_;
};

}  // namespace plydem
