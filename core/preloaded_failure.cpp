#include "core/preloaded_failure.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace plydem {

double first_failure_factor(const std::function<double(double)>& utilisation, double guess) {
  constexpr double never = std::numeric_limits<double>::infinity();
  const double u0 = utilisation(0.0);
  if (u0 >= 1) return 0.0;
  // The bracket: lo below the surface, hi on or beyond it.
  double lo = 0, f_lo = u0 - 1;
  double hi = std::isfinite(guess) && guess > 0 ? guess : 1.0;
  double f_hi = utilisation(hi) - 1;
  for (int k = 0; !(f_hi >= 0); ++k) {
    if (k == 60) return never;
    if (!std::isnan(f_hi)) {
      lo = hi;
      f_lo = f_hi;
    }
    hi *= 2;
    f_hi = utilisation(hi) - 1;
  }
  int side = 0;  // the end kept last (Illinois: halve the kept end's value when kept twice)
  for (int k = 0; k < 200 && hi - lo > 1e-14 * hi; ++k) {
    double mid = std::isfinite(f_hi) && f_hi > f_lo ? lo - f_lo * (hi - lo) / (f_hi - f_lo)
                                                    : 0.5 * (lo + hi);
    if (!(mid > lo && mid < hi) || k % 8 == 7) mid = 0.5 * (lo + hi);  // stalled: bisect
    const double f = utilisation(mid) - 1;
    if (f >= 0) {
      hi = mid;
      f_hi = f;
      if (side == -1) f_lo *= 0.5;
      side = -1;
    } else {
      lo = mid;
      f_lo = f;
      if (side == 1) f_hi *= 0.5;
      side = 1;
    }
  }
  return hi;
}

double first_quadratic_crossing(double a, double b, double c, double target) {
  constexpr double never = std::numeric_limits<double>::infinity();
  if (a >= target) return 0.0;
  const double d = a - target;  // < 0: c x^2 + b x + d = 0 has one positive root if c > 0
  if (c > 0) {
    const double disc = b * b - 4 * c * d;
    // The positive root, in the form that does not cancel: 2 |d| / (b + sqrt(disc)) for b >= 0.
    const double root = std::sqrt(std::max(0.0, disc));
    return b >= 0 ? -2 * d / (b + root) : (-b + root) / (2 * c);
  }
  return b > 0 ? -d / b : never;
}

}  // namespace plydem
