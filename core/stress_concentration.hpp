#pragma once
/// \file
/// Closed forms for the stress at the edge of a circular hole in an orthotropic plate under
/// uniaxial tension along x (../shared/DAMAGE_NOTES.md gives the context; the reference for the
/// notched-plate experiment, experiments/runner/hole_failure_experiment.cpp).
///
/// Infinite plate (Lekhnitskii, Anisotropic Plates, 1968): the hoop stress at the hole's edge
/// where it crosses the y axis is Kt_inf times the remote stress,
///   Kt_inf = 1 + sqrt(2 (sqrt(Ex / Ey) - nu_xy) + Ex / Gxy),
/// with the laminate's in-plane constants (classical lamination theory, A / h); 3 for an
/// isotropic plate. At that point the edge is traction-free and the state is uniaxial sigma_x, as
/// far away: the plies' stresses there are Kt_inf times their far-field ones, so the laminate
/// first fails at the hole's edge at its unnotched first-ply failure over Kt_inf.
///
/// Finite width (the isotropic Heywood factor, in its gross-section form; Heywood, Designing by
/// Photoelasticity, 1952; used for composites by Tan, Stress Concentrations in Laminated
/// Composites, 1994, as the isotropic finite-width correction): for a hole of diameter D centred
/// in a strip of width W,
///   Kt / Kt_inf = (2 + (1 - D/W)^3) / (3 (1 - D/W)),
/// Kt the peak over the gross remote stress. It is exact for D/W -> 0 and within a few percent of
/// the orthotropic correction for D/W below about 0.3 (Tan 1994).

#include "core/elasticity.hpp"

namespace plydem {

/// Kt_inf of Lekhnitskii's infinite orthotropic plate (file comment) from the in-plane constants
/// (Ex, Ey, nu_xy, Gxy). Throws plydem::Error naming the constant if a modulus is not positive
/// and finite, or if 2 (sqrt(Ex/Ey) - nu_xy) + Ex/Gxy is negative.
double orthotropic_hole_stress_concentration(const InPlaneConstants& constants);

/// Heywood's finite-width factor Kt / Kt_inf (gross section) for a hole of diameter D centred in
/// a strip of width W. Throws plydem::Error unless 0 <= D < W.
double heywood_finite_width_factor(double diameter, double width);

/// Notched strength over unnotched strength of an infinite orthotropic plate with a circular hole
/// of `radius` R under uniaxial tension, by Whitney & Nuismer's criteria (J. Compos. Mater. 8
/// (1974) 253) on Konish and Whitney's approximation of the stress ahead of the hole,
///   sigma_y(x) / sigma = 1 + xi^2 / 2 + 3 xi^4 / 2 - (Kt_inf - 3) (5 xi^6 - 7 xi^8) / 2,
///   xi = R / x (x from the hole's centre along the section):
///  - point stress: sigma_y at a characteristic distance d0 ahead of the edge reaches the
///    unnotched strength, sigma_N / sigma_0 = 2 / (2 + xi^2 + 3 xi^4 - (Kt_inf - 3)(5 xi^6 -
///    7 xi^8)), xi = R / (R + d0);
///  - average stress: its mean over a0 ahead of the edge does, sigma_N / sigma_0 = 2 (1 - xi) /
///    (2 - xi^2 - xi^4 + (Kt_inf - 3)(xi^6 - xi^8)), xi = R / (R + a0).
/// Both tend to 1 / Kt_inf as the distance shrinks and to 1 as it grows. A finite plate's ratio
/// is this over the finite-width factor (Kt / Kt_inf). Throws plydem::Error for a Kt_inf below 1
/// or a radius or distance that is not positive and finite.
double point_stress_notched_ratio(double kt_inf, double radius, double distance);
double average_stress_notched_ratio(double kt_inf, double radius, double distance);

}  // namespace plydem
