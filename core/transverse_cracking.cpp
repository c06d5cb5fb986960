#include "core/transverse_cracking.hpp"

#include <fmt/format.h>

#include <cmath>

#include "core/error.hpp"

namespace plydem {

namespace {

void require_thicknesses(double b, double d) {
  require(std::isfinite(b) && b > 0 && std::isfinite(d) && d > 0,
          fmt::format("transverse cracking: the 0° sublaminate thickness b and the 90° half "
                      "thickness d must be positive, got b = {} m, d = {} m",
                      b, d));
}

}  // namespace

double shear_lag_stiffness_ratio(const Material& m, double b, double d, double density) {
  require_thicknesses(b, d);
  require(std::isfinite(density) && density >= 0,
          fmt::format("transverse cracking: the crack density must be finite and >= 0, got {} "
                      "1/m",
                      density));
  if (density == 0) return 1.0;
  const double lambda = std::sqrt(m.G23() * (b * m.E1 + d * m.E2) / (b * d * d * m.E1 * m.E2));
  const double ls = lambda / (2.0 * density);
  return 1.0 / (1.0 + d * m.E2 / (b * m.E1) * std::tanh(ls) / ls);
}

double ply_discount_stiffness_ratio(const Material& m, double b, double d) {
  require_thicknesses(b, d);
  return b * m.E1 / (b * m.E1 + d * m.E2);
}

}  // namespace plydem
