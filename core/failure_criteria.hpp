#pragma once
/// \file
/// The classical failure criteria of a unidirectional ply under in-plane stress, computed from the
/// lamina strengths alone (closed forms, independent of any particle model): the references the
/// model's strengths are reported beside (../shared/DAMAGE_NOTES.md §5).
///  - max-stress: each of sigma1, sigma2, tau12 against its own strength;
///  - Tsai-Hill: (s1/X)^2 - s1 s2 / X^2 + (s2/Y)^2 + (t/S)^2 = 1, X and Y by the signs of s1, s2;
///  - Tsai-Wu (Tsai & Wu, J. Compos. Mater. 5 (1971) 58) with F12* = -1/2:
///    F1 s1 + F2 s2 + F11 s1^2 + F22 s2^2 + F66 t^2 + 2 F12 s1 s2 = 1, F12 = -1/2 sqrt(F11 F22);
///  - Hashin (J. Appl. Mech. 47 (1980) 329), plane stress, its four modes; the transverse shear
///    strength S23 of the matrix-compression mode is taken as YC / 2 (no S23 in the material).
/// Strengths are magnitudes; compression is negative stress.

#include <vector>

#include "core/material.hpp"

namespace plydem {

/// In-plane stress in the ply's axes (1 along the fibre) [Pa].
struct PlyStress {
  double sigma1 = 0;
  double sigma2 = 0;
  double tau12 = 0;
};

/// (sigma_x, sigma_y, tau_xy) in the coupon's axes, expressed in the axes of a ply whose fibre lies
/// at `ply_angle` [rad] from x.
PlyStress to_ply_axes(double sigma_x, double sigma_y, double tau_xy, double ply_angle);

enum class FailureCriterion { kMaxStress, kTsaiHill, kTsaiWu, kHashin };

/// "max_stress", "tsai_hill", "tsai_wu", "hashin" (the keys of `plydem strength --json`).
const char* criterion_name(FailureCriterion criterion);
/// The four, in that order.
std::vector<FailureCriterion> all_criteria();

/// The factor lambda > 0 by which `stress` must be scaled to reach the criterion's failure surface
/// (+inf if never: e.g. max-stress with a zero stress). Throws plydem::Error if a strength the
/// criterion needs for this stress is missing (0).
double failure_load_factor(FailureCriterion criterion, const PlyStress& stress,
                           const LaminaStrength& strength);

/// The uniaxial tensile strength sigma_x [Pa] of a coupon of one ply at `ply_angle` [rad] (fibre
/// from the load axis) under the criterion: failure_load_factor of the unit sigma_x.
double off_axis_strength(FailureCriterion criterion, const LaminaStrength& strength,
                         double ply_angle);

}  // namespace plydem
