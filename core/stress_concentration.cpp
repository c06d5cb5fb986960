#include "core/stress_concentration.hpp"

#include <fmt/format.h>

#include <cmath>
#include <utility>

#include "core/error.hpp"
#include "core/units.hpp"

namespace plydem {

double orthotropic_hole_stress_concentration(const InPlaneConstants& c) {
  const std::pair<const char*, double> moduli[] = {{"Ex", c.Ex}, {"Ey", c.Ey}, {"Gxy", c.Gxy}};
  for (const auto& [name, value] : moduli) {
    require(std::isfinite(value) && value > 0,
            fmt::format("the hole's stress concentration needs a positive, finite {}, got {} Pa",
                        name, value));
  }
  require(std::isfinite(c.nu_xy), "the hole's stress concentration needs a finite nu_xy");
  const double radicand = 2.0 * (std::sqrt(c.Ex / c.Ey) - c.nu_xy) + c.Ex / c.Gxy;
  require(radicand >= 0,
          fmt::format("2 (sqrt(Ex/Ey) - nu_xy) + Ex/Gxy = {} is negative: no orthotropic "
                      "stress concentration for these constants",
                      radicand));
  return 1.0 + std::sqrt(radicand);
}

double heywood_finite_width_factor(double diameter, double width) {
  require(std::isfinite(diameter) && std::isfinite(width) && diameter >= 0 && diameter < width,
          fmt::format("the finite-width factor needs a hole narrower than its strip (0 <= D < W), "
                      "got D = {} mm, W = {} mm",
                      diameter * kMmPerMetre, width * kMmPerMetre));
  const double r = 1.0 - diameter / width;
  return (2.0 + r * r * r) / (3.0 * r);
}

}  // namespace plydem
