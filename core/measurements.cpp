#include "core/measurements.hpp"

#include <algorithm>
#include <cmath>

#include "core/error.hpp"

namespace plydem {

GaugeStrain fit_gauge_strain(const Particles& particles, const std::vector<int>& selection) {
  const auto n = static_cast<Eigen::Index>(selection.size());
  Eigen::Array<double, Eigen::Dynamic, 2> position(n, 2), displacement(n, 2);
  for (Eigen::Index k = 0; k < n; ++k) {
    position.row(k) = particles.reference_position.row(selection[k]).head<2>();
    displacement.row(k) = particles.displacement.row(selection[k]).head<2>();
  }
  return fit_plane_strain(position, displacement);
}

GaugeStrain fit_plane_strain(const Eigen::Array<double, Eigen::Dynamic, 2>& position,
                             const Eigen::Array<double, Eigen::Dynamic, 2>& displacement) {
  const Eigen::Index n = position.rows();
  require(n >= 3, "the gauge section holds fewer than three particles");
  require(displacement.rows() == n, "gauge strain fit: positions and displacements differ in size");
  // Centre the coordinates: better conditioned normal equations.
  const Eigen::Array<double, 1, 2> mean = position.colwise().mean();
  Eigen::MatrixXd design(n, 3);
  design.col(0).setOnes();
  design.col(1) = (position.col(0) - mean(0)).matrix();
  design.col(2) = (position.col(1) - mean(1)).matrix();
  const Eigen::MatrixXd rhs = displacement.matrix();
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
