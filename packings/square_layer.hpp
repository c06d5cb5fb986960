#pragma once
/// \file
/// A single square layer of equal spheres in the x-y plane (paper Sec. 3.4, Fig. 14a: the
/// "nine-ball" cell): one particle per cell of side l = particle diameter, eight neighbours each.
/// Four bond families: family 0 along the lattice x axis (`lattice_angle`), family 1 along the
/// lattice y axis, both at distance l (touching); family 2 along the +45 deg diagonal and family 3
/// along the 135 deg diagonal, at distance l sqrt(2) (not touching: the bond's contact point sits
/// midway in the gap). Geometry only: where particles sit and which pairs are bonded.

#include <utility>
#include <vector>

#include "contacts/cell_list.hpp"
#include "core/homogenizer.hpp"

namespace plydem {

class SquareLayer {
 public:
  /// `spacing` = axial centre distance = particle diameter [m]; `lattice_angle` from +x [rad].
  SquareLayer(double spacing, double lattice_angle);

  static constexpr int kFamilyCount = 4;
  double spacing() const { return spacing_; }
  double lattice_angle() const { return lattice_angle_; }
  /// Area per particle, l^2.
  double cell_area() const;
  /// Angle of a bond family from the lattice x axis: 0, 90, 45, 135 deg [rad].
  static double family_offset(int family);
  /// Unit direction of a bond family in the specimen frame.
  Eigen::Vector3d family_direction(int family) const;
  /// Centre distance of a bond family: l for the axial families, l sqrt(2) for the diagonals.
  double family_length(int family) const;
  /// The family of a bond direction (either sense); throws if it is not a lattice direction.
  int family_of(const Eigen::Vector3d& direction) const;

  /// The periodic cell: one particle, one bond per family; volume = cell_area * thickness.
  UnitCell unit_cell(double thickness) const;

  /// Lattice sites whose centres lie at least one radius inside the rectangle [0, L] x [0, W]
  /// (z = 0), the first site at (R, R).
  PositionArray fill_rectangle(double length, double width) const;

  /// Bonded pairs of axial and diagonal neighbours among `position` (cell-list search) and their
  /// families.
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
