#pragma once
/// \file
/// What a virtual test measures on a specimen: the homogeneous in-plane strain of a gauge section
/// (least-squares fit of the displacements, away from the grips) and the section's cross-section.

#include <vector>

#include "core/model.hpp"

namespace plydem {

/// Least-squares fit of u_x = a + e_xx x + c y and u_y = b + d x + e_yy y over the selected
/// particles; gamma_xy = c + d.
struct GaugeStrain {
  double exx = 0, eyy = 0, gamma_xy = 0;
};
/// Throws plydem::Error if fewer than 3 particles are selected or they are collinear.
GaugeStrain fit_gauge_strain(const Particles& particles, const std::vector<int>& selection);
/// The same fit over points given by their in-plane positions and displacements (row k: point k),
/// e.g. a FEM field sampled where a DEM coupon's gauge particles sit. Same errors.
GaugeStrain fit_plane_strain(const Eigen::Array<double, Eigen::Dynamic, 2>& position,
                             const Eigen::Array<double, Eigen::Dynamic, 2>& displacement);

/// Indices of particles whose reference x lies in [x_begin, x_end].
std::vector<int> particles_between(const Particles& particles, double x_begin, double x_end);

/// Mean cross-section area [m^2] of the material between x_begin and x_end: the particles' volumes
/// summed with a trapezoidal window (linear ramps of width `ramp` at both ends, so that lattice
/// rows cut by the window count fractionally) over the window's effective length.
double cross_section_area(const Particles& particles, double x_begin, double x_end, double ramp);

/// y = slope x + intercept by least squares, with the coefficient of determination.
struct LinearFit {
  double slope = 0, intercept = 0, r_squared = 0;
};
LinearFit linear_fit(const std::vector<double>& x, const std::vector<double>& y);

}  // namespace plydem
