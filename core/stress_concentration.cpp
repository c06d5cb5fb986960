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

namespace {

// xi = R / (R + distance) of the Whitney-Nuismer criteria, after checking their inputs.
double characteristic_xi(double kt_inf, double radius, double distance, const char* criterion) {
  require(std::isfinite(kt_inf) && kt_inf >= 1,
          fmt::format("the {} criterion needs Kt_inf >= 1, got {}", criterion, kt_inf));
  require(std::isfinite(radius) && radius > 0,
          fmt::format("the {} criterion needs a positive hole radius, got {} mm", criterion,
                      radius * kMmPerMetre));
  require(std::isfinite(distance) && distance > 0,
          fmt::format("the {} criterion needs a positive characteristic distance, got {} mm",
                      criterion, distance * kMmPerMetre));
  return radius / (radius + distance);
}

}  // namespace

double point_stress_notched_ratio(double kt_inf, double radius, double distance) {
  const double x = characteristic_xi(kt_inf, radius, distance, "point-stress");
  const double x2 = x * x, x4 = x2 * x2, x6 = x4 * x2, x8 = x4 * x4;
  return 2.0 / (2.0 + x2 + 3.0 * x4 - (kt_inf - 3.0) * (5.0 * x6 - 7.0 * x8));
}

double average_stress_notched_ratio(double kt_inf, double radius, double distance) {
  const double x = characteristic_xi(kt_inf, radius, distance, "average-stress");
  const double x2 = x * x, x4 = x2 * x2, x6 = x4 * x2, x8 = x4 * x4;
  return 2.0 * (1.0 - x) / (2.0 - x2 - x4 + (kt_inf - 3.0) * (x6 - x8));
}

}  // namespace plydem
