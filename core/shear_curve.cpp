#include "core/shear_curve.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "core/error.hpp"

namespace plydem {
namespace {

// gamma G = tau + alpha' scale (tau / scale)^eta, with stresses in units of `scale` (the curve's
// largest stress) so that no power overflows: t + a t^eta = G gamma / scale, solved for t by
// Newton's method from the linear response (h(t) is increasing and convex for t > 0: from above the
// root every step stays above it and converges).
double normalised_stress(double a, double eta, double target) {
  double t = target;
  for (int i = 0; i < 200; ++i) {
    const double step = (t + a * std::pow(t, eta) - target) / (1 + a * eta * std::pow(t, eta - 1));
    t -= step;
    if (std::abs(step) <= 1e-15 * t) break;
  }
  return t;
}

// The sum of squared relative stress errors of the law (a, eta) at the curve's strains.
double stress_error(const std::vector<ShearCurvePoint>& curve, double g12, double scale, double a,
                    double eta) {
  double sum = 0;
  for (const ShearCurvePoint& p : curve) {
    const double r = normalised_stress(a, eta, g12 * p.strain / scale) * scale / p.stress - 1;
    sum += r * r;
  }
  return sum;
}

// The minimum of f on [lo, hi] by golden-section search (f unimodal there); returns the argument.
template <class F>
double golden_minimum(F f, double lo, double hi, double tolerance) {
  const double phi = (std::sqrt(5.0) - 1) / 2;
  double x1 = hi - phi * (hi - lo), x2 = lo + phi * (hi - lo);
  double f1 = f(x1), f2 = f(x2);
  while (hi - lo > tolerance) {
    if (f1 < f2) {
      hi = x2, x2 = x1, f2 = f1;
      x1 = hi - phi * (hi - lo);
      f1 = f(x1);
    } else {
      lo = x1, x1 = x2, f1 = f2;
      x2 = lo + phi * (hi - lo);
      f2 = f(x2);
    }
  }
  return 0.5 * (lo + hi);
}

}  // namespace

RambergOsgoodShear::RambergOsgoodShear(const Material& material) : g12_(material.G12) {
  const std::vector<ShearCurvePoint>& curve = material.shear_curve;
  require(curve.size() >= 2,
          fmt::format("material '{}': a Ramberg-Osgood shear law needs a shear_curve of at least "
                      "two [gamma12, tau12] points, got {}",
                      material.name, curve.size()));
  for (const ShearCurvePoint& p : curve) scale_ = std::max(scale_, p.stress);
  // For each eta the best alpha' (golden section on log alpha'), then the best eta: the least
  // squared relative errors of the stresses at the curve's strains.
  const auto best_log_alpha = [&](double eta) {
    return golden_minimum(
        [&](double log_a) { return stress_error(curve, g12_, scale_, std::exp(log_a), eta); },
        -30.0, 10.0, 1e-9);
  };
  eta_ = golden_minimum(
      [&](double eta) {
        return stress_error(curve, g12_, scale_, std::exp(best_log_alpha(eta)), eta);
      },
      1.0, 40.0, 1e-9);
  alpha_ = std::exp(best_log_alpha(eta_));
  require(alpha_ > 1e-6 && eta_ > 1 + 1e-9,
          fmt::format("material '{}': no Ramberg-Osgood law gamma = (tau + alpha tau^eta) / G12 "
                      "with alpha > 0 and eta > 1 follows the shear_curve (is it linear?)",
                      material.name));
  for (const ShearCurvePoint& p : curve) {
    worst_error_ = std::max(worst_error_, std::abs(stress_at(p.strain) / p.stress - 1));
  }
}

double RambergOsgoodShear::alpha() const {
  return alpha_ * std::pow(scale_, 1 - eta_);
}

double RambergOsgoodShear::strain_at(double stress) const {
  return (stress + alpha_ * scale_ * std::pow(stress / scale_, eta_)) / g12_;
}

double RambergOsgoodShear::stress_at(double strain) const {
  require(
      std::isfinite(strain) && strain >= 0,
      fmt::format("Ramberg-Osgood shear law: the strain must be finite and >= 0, got {}", strain));
  if (strain == 0) return 0;
  return normalised_stress(alpha_, eta_, g12_ * strain / scale_) * scale_;
}

}  // namespace plydem
