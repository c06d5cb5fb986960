#include "core/transverse_cracking.hpp"

#include <fmt/format.h>

#include <cmath>
#include <numbers>

#include "core/error.hpp"

namespace plydem {

namespace {

void require_thicknesses(double b, double d) {
  require(std::isfinite(b) && b > 0 && std::isfinite(d) && d > 0,
          fmt::format("transverse cracking: the 0° sublaminate thickness b and the 90° half "
                      "thickness d must be positive, got b = {} m, d = {} m",
                      b, d));
}

double require_fracture_energy(const Material& m) {
  require(
      m.strength.G_matrix > 0,
      fmt::format("transverse cracking: material '{}' has no G_matrix (the fracture energy of a "
                  "crack along the fibres, G_Ic), which the in-situ strength and the energy "
                  "of a new crack need",
                  m.name));
  return m.strength.G_matrix;
}

}  // namespace

double shear_lag_parameter(const Material& m, double b, double d) {
  require_thicknesses(b, d);
  return std::sqrt(m.G23() * (b * m.E1 + d * m.E2) / (b * d * d * m.E1 * m.E2));
}

double shear_lag_stiffness_ratio(const Material& m, double b, double d, double density) {
  require_thicknesses(b, d);
  require(std::isfinite(density) && density >= 0,
          fmt::format("transverse cracking: the crack density must be finite and >= 0, got {} "
                      "1/m",
                      density));
  if (density == 0) return 1.0;
  const double lambda = shear_lag_parameter(m, b, d);
  const double ls = lambda / (2.0 * density);
  return 1.0 / (1.0 + d * m.E2 / (b * m.E1) * std::tanh(ls) / ls);
}

double HashinCrossPly::chi(double rho) const {
  require(std::isfinite(rho) && rho > 0,
          fmt::format("Hashin's cross-ply: rho (half the crack spacing over half the 90° layer) "
                      "must be positive, got {}",
                      rho));
  const double a2 = alpha * alpha, b2 = beta * beta;
  // For large rho, cosh and sinh share their growth: chi -> 2 alpha (alpha^2 + beta^2).
  if (2 * alpha * rho > 700) return 2 * alpha * (a2 + b2);
  // cosh x - cos y as 2 sinh^2(x/2) + 2 sin^2(y/2): no cancellation at small rho.
  const double sh = std::sinh(alpha * rho), sn = std::sin(beta * rho);
  return 2 * alpha * beta * (a2 + b2) * (2 * sh * sh + 2 * sn * sn) /
         (alpha * std::sin(2 * beta * rho) + beta * std::sinh(2 * alpha * rho));
}

HashinCrossPly hashin_cross_ply(const Material& m, double b, double d) {
  require_thicknesses(b, d);
  const double lambda = b / d;
  const double ea = m.E1, et = m.E2, nua = m.nu12, nut = m.nu23, ga = m.G12, gt = m.G23();
  const double c00 = 1 / et + 1 / (lambda * ea);
  const double c02 = nut / et * (lambda + 2.0 / 3.0) - lambda * nua / (3 * ea);
  const double c11 = (1 / gt + lambda / ga) / 3;
  const double eta = (3 * lambda * lambda + 12 * lambda + 8) / 60;
  const double c22 = (lambda + 1) * eta / et;
  HashinCrossPly h;
  h.p = (c02 - c11) / c22;
  h.q = c00 / c22;
  h.eta = eta;
  require(4 * h.q > h.p * h.p,
          fmt::format("Hashin's cross-ply: 4q <= p^2 (p = {:.4g}, q = {:.4g}) for material '{}' "
                      "with 0° sublaminates {:g} mm and a 90° layer {:g} mm thick: the closed "
                      "form covers oscillating perturbations only",
                      h.p, h.q, m.name, b * 1e3, 2 * d * 1e3));
  const double root_q = std::sqrt(h.q);
  h.alpha = std::sqrt((root_q - h.p / 2) / 2);
  h.beta = std::sqrt((root_q + h.p / 2) / 2);
  return h;
}

double hashin_stiffness_ratio(const Material& m, double b, double d, double density) {
  const HashinCrossPly h = hashin_cross_ply(m, b, d);
  require(std::isfinite(density) && density >= 0,
          fmt::format("transverse cracking: the crack density must be finite and >= 0, got {} "
                      "1/m",
                      density));
  if (density == 0) return 1.0;
  const double e0 = (b * m.E1 + d * m.E2) / (b + d);
  const double k1 = m.E2 / e0;
  const double rho = 1 / (2 * density * d);
  return 1 / (1 + e0 * k1 * k1 * h.eta * h.chi(rho) / (m.E2 * rho));
}

double ply_discount_stiffness_ratio(const Material& m, double b, double d) {
  require_thicknesses(b, d);
  return b * m.E1 / (b * m.E1 + d * m.E2);
}

InSituStrength in_situ_transverse_strength(const Material& m, double t, PlyPlacement placement) {
  require(std::isfinite(t) && t > 0,
          fmt::format("in-situ strength: the 90° layer's thickness must be positive, got {} m", t));
  require(m.strength.YT > 0, fmt::format("in-situ strength: material '{}' has no YT", m.name));
  const double g = require_fracture_energy(m);
  const double lambda22 = 2.0 * (1.0 / m.E2 - m.nu21() * m.nu21() / m.E1);
  // Y_thin = c / sqrt(t): c^2 = 8 G / (pi Lambda22) embedded, 1.79^2 G / (pi Lambda22) outer.
  const bool embedded = placement == PlyPlacement::kEmbedded;
  const double c2 = (embedded ? 8.0 : 1.79 * 1.79) * g / (std::numbers::pi * lambda22);
  InSituStrength s;
  s.thick = embedded ? 1.12 * std::sqrt(2.0) * m.strength.YT : m.strength.YT;
  s.thin = std::sqrt(c2 / t);
  s.transition_thickness = c2 / (s.thick * s.thick);
  s.value = t < s.transition_thickness ? s.thin : s.thick;
  return s;
}

double new_crack_energy_release_rate(const Material& m, double b, double d, double sigma90,
                                     double interval) {
  const double lambda = shear_lag_parameter(m, b, d);
  require(std::isfinite(sigma90),
          fmt::format("transverse cracking: the 90° stress must be finite, got {} Pa", sigma90));
  require(
      interval > 0 && !std::isnan(interval),
      fmt::format("transverse cracking: the crack interval must be positive, got {} m", interval));
  const double shape = std::isinf(interval) ? 1.0
                                            : 2.0 * std::tanh(lambda * interval / 4) -
                                                  std::tanh(lambda * interval / 2);
  return sigma90 * sigma90 * lambda * d * d / m.G23() * shape;
}

double isolated_crack_stress(const Material& m, double b, double d) {
  const double g = require_fracture_energy(m);
  const double lambda = shear_lag_parameter(m, b, d);
  return std::sqrt(g * m.G23() / (lambda * d * d));
}

double crack_multiplication_interval(const Material& m, double b, double d, double sigma90) {
  const double g = require_fracture_energy(m);
  const double isolated = new_crack_energy_release_rate(m, b, d, sigma90, INFINITY);
  if (isolated <= g) return INFINITY;
  // G(L) / G(inf) = 2 tanh(x / 4) - tanh(x / 2), x = lambda L, rises from 0 to 1: bisect on x
  // (to the last bit: the bracket halves until it stops shrinking).
  const double lambda = shear_lag_parameter(m, b, d);
  const double target = g / isolated;
  auto shape = [](double x) { return 2.0 * std::tanh(x / 4) - std::tanh(x / 2); };
  double low = 0, high = 1;
  while (shape(high) < target) high *= 2;
  for (int k = 0; k < 200; ++k) {
    const double mid = 0.5 * (low + high);
    if (mid <= low || mid >= high) break;
    (shape(mid) < target ? low : high) = mid;
  }
  return high / lambda;
}

}  // namespace plydem
