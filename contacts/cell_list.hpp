#pragma once
/// \file
/// Contact detection with a uniform cell list: finds every pair of particles whose centre distance
/// is at most contact_radius * (r_i + r_j) (eq. 10, I_R = contact_radius). Used to find the bonded
/// pairs when a packing is built and, later, unbonded contacts. Free functions over arrays.

#include <Eigen/Dense>
#include <utility>
#include <vector>

namespace plydem {

using PositionArray = Eigen::Array<double, Eigen::Dynamic, 3>;

/// All pairs (i, j), i < j, with |x_i - x_j| <= contact_radius * (r_i + r_j), sorted by (i, j).
/// O(N) for bounded radius ratios: the cell edge is contact_radius * 2 * max(r).
/// Throws plydem::Error on a non-finite position or radius, a non-positive radius, or a
/// contact_radius <= 0.
std::vector<std::pair<int, int>> find_contact_pairs(const PositionArray& position,
                                                    const Eigen::ArrayXd& radius,
                                                    double contact_radius);

/// The O(N^2) reference with the same contract, for tests.
std::vector<std::pair<int, int>> find_contact_pairs_brute_force(const PositionArray& position,
                                                                const Eigen::ArrayXd& radius,
                                                                double contact_radius);

}  // namespace plydem
