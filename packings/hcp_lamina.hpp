#pragma once
/// \file
/// A hexagonal close packed (HCP) lamina of equal spheres (paper Sec. 3.2, Figs. 7-8): three
/// hexagonal layers A, B, A' stacked along z at heights 0, c, 2c. Layer B sits over the centroids
/// of the A triangles, A' sits over A. In-plane neighbours are one spacing l apart (l = particle
/// diameter); a particle of B touches three particles below and three above along inclined bonds of
/// length sqrt(l^2/3 + c^2) (ERRATA §2: the true bond length; equal to l only at the close-packed
/// spacing c = l sqrt(2/3)). Interior particles of B have 12 neighbours, of A and A' 9 (the
/// lamina's faces are free); in the infinite crystal ABAB... every particle has 12.
///
/// Six bond families, by direction in the lattice frame (turned by `lattice_angle` from +x):
///   0, 1, 2: in-plane bonds along 0, +60, +120 deg;
///   3, 4, 5: inclined bonds (both between A and B and between B and A') whose in-plane projection
///            lies along 30, 90, 150 deg.
/// An inclined bond of A-B and its mirror image in B-A' share a family: they have the same
/// in-plane projection and so the same in-plane stiffness. Geometry only: where particles sit and
/// which pairs are bonded.

#include <utility>
#include <vector>

#include "contacts/cell_list.hpp"
#include "core/homogenizer.hpp"

namespace plydem {

class HcpLamina {
 public:
  /// `spacing` l = in-plane centre distance = particle diameter [m]; `layer_spacing` c between the
  /// layers along z [m]; `lattice_angle` of family 0 from +x [rad]. Throws plydem::Error unless
  /// both lengths are positive and bonded neighbours are clearly the nearest pairs (see
  /// layer_spacing_limits).
  HcpLamina(double spacing, double layer_spacing, double lattice_angle);

  static constexpr int kLayerCount = 3;
  static constexpr int kFamilyCount = 6;
  static constexpr int kInPlaneFamilyCount = 3;

  /// The close-packed layer spacing c = l sqrt(2/3), at which every bond is l long.
  static double close_packed_layer_spacing(double spacing);
  /// The open interval of layer spacings c / l for which the bonded pairs (in-plane at l, inclined
  /// at sqrt(l^2/3 + c^2)) are at least 1% closer than any other pair: the A and A' particles
  /// stacked 2c apart, and the second in-plane shell at sqrt(3) l.
  static std::pair<double, double> layer_spacing_limits();

  double spacing() const { return spacing_; }
  double layer_spacing() const { return layer_spacing_; }
  double lattice_angle() const { return lattice_angle_; }
  /// Length of an inclined bond, sqrt(l^2/3 + c^2).
  double inclined_bond_length() const;
  /// Area per particle of one layer, (sqrt(3)/2) l^2.
  double cell_area() const;
  /// True for families 3, 4, 5.
  static bool is_inclined(int family) { return family >= kInPlaneFamilyCount; }
  /// Angle from +x of a family's direction (for inclined families, of its in-plane projection).
  double family_angle(int family) const;
  /// Unit vector of an in-plane family; for an inclined family, its bond going up (+z) whose
  /// in-plane projection points along family_angle.
  Eigen::Vector3d family_direction(int family) const;
  /// Position of layer 0, 1, 2's lattice origin relative to layer 0's: B is shifted in-plane by
  /// (a1 + a2)/3 and up by c, A' up by 2c.
  Eigen::Vector3d layer_offset(int layer) const;

  /// The periodic layer cell (periodic in x and y only): three basis particles, one per layer, and
  /// fifteen bonds, each once: three in-plane bonds per layer and three inclined bonds between
  /// each pair of adjacent layers. volume = cell_area * thickness (the ply thickness the lamina
  /// stands for).
  UnitCell unit_cell(double thickness) const;
  /// The infinite crystal ABAB...: two basis particles, periodic along z with period 2c, twelve
  /// neighbours each, twelve bonds per cell; volume = 2 sqrt(3) R^2 c per particle (ERRATA §2).
  UnitCell bulk_unit_cell() const;

  /// The lamina's particles.
  struct Sites {
    PositionArray position;  ///< [m]
    Eigen::ArrayXi layer;    ///< 0 (A), 1 (B), 2 (A')
  };
  /// Lattice sites of the three layers whose centres lie at least one radius inside the rectangle
  /// [0, L] x [0, W], layer A's first site at (R, R, 0); ordered by layer, then row-major.
  Sites fill_rectangle(double length, double width) const;

  /// Bonded pairs among `sites` (cell-list contact detection at the longest bond length) and their
  /// families. Throws plydem::Error if a detected pair is not a lattice bond.
  struct Graph {
    std::vector<std::pair<int, int>> pairs;
    std::vector<int> family;
  };
  Graph bond_graph(const Sites& sites) const;

 private:
  // In-plane lattice vectors a1 (family 0) and a2 (family 1) in the specimen frame.
  Eigen::Vector3d a1() const;
  Eigen::Vector3d a2() const;
  // The family of a bond vector (either sense) joining layers `layer_i` and `layer_j`; throws if
  // it is not a lattice bond.
  int family_of(const Eigen::Vector3d& branch, int layer_i, int layer_j) const;

  double spacing_;
  double layer_spacing_;
  double lattice_angle_;
};

}  // namespace plydem
