#pragma once
/// \file
/// A random packing of equal spheres in a box, for the paper's 3D discrete lattice (Sec. 3.1):
/// geometry only, i.e. where the particles sit and which pairs are bonded.
///
/// Placement is random sequential addition (RSA): centres are drawn uniformly in the box, one at
/// a time, and a candidate is kept only if it lies at least one diameter from every centre kept
/// so far (hard spheres that never overlap), until the requested number of spheres is placed.
/// The process is statistically homogeneous and isotropic; its jamming limit is a packing
/// fraction of about 0.38, so fractions up to kMaxPackingFraction are reached in a few attempts
/// per sphere. Centres fill the whole box, [0, L] along every axis (a periodic axis: [0, L)), so
/// that each sphere stands for box volume / count, whatever the boundaries.
///
/// Randomness is std::mt19937_64 with a fixed conversion to doubles (not the
/// implementation-defined std::uniform_real_distribution): the same seed gives bit for bit the
/// same packing on every platform.
///
/// Bonds join every pair whose centre distance is at most contact_radius * (r_i + r_j), eq. (10)
/// with I_R = contact_radius; across a periodic face a bond joins a sphere to the nearest image
/// of the other.

#include <array>
#include <cstdint>
#include <utility>
#include <vector>

#include "contacts/cell_list.hpp"

namespace plydem {

/// The densest packing fraction random sequential addition is asked to reach.
inline constexpr double kMaxPackingFraction = 0.35;

struct RandomPackingSpec {
  Eigen::Vector3d box = Eigen::Vector3d::Ones();  ///< edge lengths [m]
  std::array<bool, 3> periodic{false, false, false};
  double diameter = 1;             ///< sphere diameter, the minimum centre distance [m]
  double packing_fraction = 0.29;  ///< sphere volume / box volume, in (0, kMaxPackingFraction]
  std::uint64_t seed = 1;

  /// Number of spheres: the packing fraction times box volume over sphere volume, rounded.
  int count() const;
  /// Throws plydem::Error naming the first bad value: non-finite or non-positive sizes, a
  /// packing fraction out of range, a box that holds fewer than two spheres, a periodic edge
  /// shorter than the bond search needs (3 diameters).
  void validate() const;
};

struct RandomPacking {
  PositionArray position;  ///< centres [m], inside the box
  Eigen::Vector3d box = Eigen::Vector3d::Zero();
  std::array<bool, 3> periodic{false, false, false};
  double diameter = 0;
  long attempts = 0;  ///< candidates drawn, kept or not
};

/// Random sequential addition (file comment). Throws plydem::Error for a bad spec or when the
/// spheres cannot be placed within 1000 attempts per sphere (a packing fraction near jamming in a
/// box only a few diameters wide).
RandomPacking random_sequential_addition(const RandomPackingSpec& spec);

/// Bonded pairs within the contact radius (eq. 10), i < j, each pair once, sorted by (i, j);
/// image(b) is the period (in box edges, zero along non-periodic axes) holding the image of
/// `second` that the bond reaches: branch = x_j + image * box - x_i.
struct PackingBonds {
  std::vector<std::pair<int, int>> pairs;
  Eigen::Array<int, Eigen::Dynamic, 3> image;
  int size() const { return static_cast<int>(pairs.size()); }
};

/// Bonds of `packing` with I_R = contact_radius, found with the cell list
/// (contacts/cell_list.hpp); periodic faces through ghost copies of the spheres near them.
/// Throws plydem::Error for contact_radius <= 0, or a periodic edge shorter than 3 cutoffs
/// (a sphere could then bond to two images of another).
PackingBonds bonds_within(const RandomPacking& packing, double contact_radius);

/// The O(N^2) reference, trying every pair and every image in {-1, 0, 1} along periodic axes.
PackingBonds bonds_within_brute_force(const RandomPacking& packing, double contact_radius);

/// Keeps the spheres of the largest bonded cluster (loose spheres and detached groups go),
/// renumbering bonds. Returns how many spheres were removed.
int keep_largest_cluster(RandomPacking& packing, PackingBonds& bonds);

}  // namespace plydem
