#include "core/measurements.hpp"

#include <algorithm>
#include <cmath>

#include "core/error.hpp"

namespace plydem {

GaugeStrain fit_gauge_strain(const Particles& particles, const std::vector<int>& selection) {
  const int n = static_cast<int>(selection.size());
  require(n >= 3, "the gauge section holds fewer than three particles");
  // Centre the coordinates: better conditioned normal equations.
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (int i : selection)
    mean += particles.reference_position.row(i).head<2>().matrix().transpose();
  mean /= n;
  Eigen::MatrixXd design(n, 3);
  Eigen::MatrixXd rhs(n, 2);
  for (int k = 0; k < n; ++k) {
    const int i = selection[k];
    design(k, 0) = 1.0;
    design(k, 1) = particles.reference_position(i, 0) - mean.x();
    design(k, 2) = particles.reference_position(i, 1) - mean.y();
    rhs(k, 0) = particles.displacement(i, 0);
    rhs(k, 1) = particles.displacement(i, 1);
  }
  const auto qr = design.colPivHouseholderQr();
  require(qr.rank() == 3, "the gauge-section particles are collinear: no in-plane strain fit");
  const Eigen::MatrixXd coef = qr.solve(rhs);
  GaugeStrain strain;
  strain.exx = coef(1, 0);
  strain.eyy = coef(2, 1);
  strain.gamma_xy = coef(2, 0) + coef(1, 1);
  return strain;
}

std::vector<int> particles_between(const Particles& particles, double x_begin, double x_end) {
  std::vector<int> selection;
  for (int i = 0; i < particles.size(); ++i) {
    const double x = particles.reference_position(i, 0);
    if (x >= x_begin && x <= x_end) selection.push_back(i);
  }
  return selection;
}

double cross_section_area(const Particles& particles, double x_begin, double x_end, double ramp) {
  require(x_end - x_begin > 2 * ramp && ramp >= 0, "cross-section window shorter than its ramps");
  double weighted_volume = 0;
  for (int i = 0; i < particles.size(); ++i) {
    const double x = particles.reference_position(i, 0);
    const double w = ramp > 0 ? std::clamp(std::min(x - x_begin, x_end - x) / ramp, 0.0, 1.0)
                              : (x >= x_begin && x <= x_end ? 1.0 : 0.0);
    weighted_volume += w * particles.volume(i);
  }
  return weighted_volume / (x_end - x_begin - ramp);
}

LinearFit linear_fit(const std::vector<double>& x, const std::vector<double>& y) {
  require(x.size() == y.size() && x.size() >= 2, "a linear fit needs at least two points");
  const double n = static_cast<double>(x.size());
  double mx = 0, my = 0;
  for (size_t k = 0; k < x.size(); ++k) {
    mx += x[k];
    my += y[k];
  }
  mx /= n;
  my /= n;
  double sxx = 0, sxy = 0, syy = 0;
  for (size_t k = 0; k < x.size(); ++k) {
    sxx += (x[k] - mx) * (x[k] - mx);
    sxy += (x[k] - mx) * (y[k] - my);
    syy += (y[k] - my) * (y[k] - my);
  }
  require(sxx > 0, "a linear fit needs at least two distinct abscissae");
  LinearFit fit;
  fit.slope = sxy / sxx;
  fit.intercept = my - fit.slope * mx;
  fit.r_squared = syy > 0 ? sxy * sxy / (sxx * syy) : 1.0;
  return fit;
}

}  // namespace plydem
