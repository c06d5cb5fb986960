#pragma once
/// \file
/// The ply's non-linear in-plane shear response as a Ramberg-Osgood law,
///   gamma12 = (tau12 + alpha tau12^eta) / G12,
/// fitted to the points of the material's shear_curve (../shared/DAMAGE_NOTES.md §9: Soden et al.
/// 1998 for E-glass/MY750). The fit minimises the squared relative errors of the stresses at the
/// curve's strains (nested golden-section searches: alpha for each trial eta, then eta). SI units
/// (Pa).

#include <vector>

#include "core/material.hpp"

namespace plydem {

class RambergOsgoodShear {
 public:
  /// Fits the law to `material.shear_curve` (at least two points; throws plydem::Error naming the
  /// material otherwise, or if no law with alpha > 0, eta > 1 follows the points).
  explicit RambergOsgoodShear(const Material& material);

  double alpha() const;  ///< [Pa^(1 - eta)]
  double eta() const { return eta_; }
  double shear_modulus() const { return g12_; }  ///< G12 [Pa]
  /// gamma12 at tau12 >= 0.
  double strain_at(double stress) const;
  /// tau12 at gamma12 >= 0 (Newton's method on the monotonic law; exact to rounding).
  double stress_at(double strain) const;
  /// The largest relative error of the fitted stress at the curve's strains.
  double worst_stress_error() const { return worst_error_; }

 private:
  // Internally gamma G12 = tau + alpha_ scale_ (tau / scale_)^eta, scale_ the curve's largest
  // stress, so that no power overflows.
  double g12_ = 0, scale_ = 0, alpha_ = 0, eta_ = 1, worst_error_ = 0;
};

}  // namespace plydem
