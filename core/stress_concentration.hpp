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

}  // namespace plydem
