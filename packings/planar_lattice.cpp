#include "packings/planar_lattice.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/error.hpp"
#include "core/progress.hpp"

namespace plydem {

PositionArray fill_rectangle(const Eigen::Vector2d& a1, const Eigen::Vector2d& a2, double spacing,
                             double length, double width) {
  const double r = 0.5 * spacing;
  require(length >= spacing && width >= spacing,
          fmt::format("a {} x {} m rectangle cannot hold a particle of diameter {} m", length,
                      width, spacing));
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
  const double tol = 1e-9 * spacing;
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

}  // namespace plydem
