#include "strategies/boundary_cells.hpp"

#include <vector>

#include "core/error.hpp"

namespace plydem {

int complete_boundary_cells(const Particles& particles, Bonds& bonds, int family_count,
                            int bulk_count) {
  require(family_count > 0 && bulk_count > 0, "boundary-cell completion needs families");
  const int n = particles.size();
  std::vector<int> count(static_cast<size_t>(n) * family_count, 0);
  for (int b = 0; b < bonds.size(); ++b) {
    const int f = bonds.family(b);
    require(f >= 0 && f < family_count, "bond family out of range");
    ++count[static_cast<size_t>(bonds.first(b)) * family_count + f];
    ++count[static_cast<size_t>(bonds.second(b)) * family_count + f];
  }
  int changed = 0;
  for (int b = 0; b < bonds.size(); ++b) {
    const int f = bonds.family(b);
    const double share_i = static_cast<double>(bulk_count) /
                           count[static_cast<size_t>(bonds.first(b)) * family_count + f];
    const double share_j = static_cast<double>(bulk_count) /
                           count[static_cast<size_t>(bonds.second(b)) * family_count + f];
    const double factor = 0.5 * (share_i + share_j);
    if (factor == 1.0) continue;
    bonds.normal_stiffness(b) *= factor;
    bonds.shear_stiffness(b) *= factor;
    bonds.bending_stiffness(b) *= factor;
    bonds.twisting_stiffness(b) *= factor;
    ++changed;
  }
  return changed;
}

}  // namespace plydem
