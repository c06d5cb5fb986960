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
///    strength S23 of the matrix-compression mode is taken as YC / 2 (no S23 in the material);
///  - Puck (Puck & Schuermann, Compos. Sci. Technol. 58 (1998) 1045 and 62 (2002) 1633), plane
///    stress: fibre failure sigma1 = XT or -XC, and inter-fibre fracture on its action plane in the
///    closed forms of modes A (sigma2 >= 0), B and C (sigma2 < 0), with the inclination parameters
///    p12+ and p12- of LaminaStrength; mode C breaks on a plane inclined by the fracture angle
///    (puck_fracture_plane).
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

enum class FailureCriterion { kMaxStress, kTsaiHill, kTsaiWu, kHashin, kPuck };

/// "max_stress", "tsai_hill", "tsai_wu", "hashin", "puck" (the keys of `plydem strength --json`).
const char* criterion_name(FailureCriterion criterion);
/// The five, in that order.
std::vector<FailureCriterion> all_criteria();

/// Which of Puck's inter-fibre fracture modes a ply stress is in (plane stress).
enum class PuckMode { kA, kB, kC };

/// The mode, and the inclination of the fracture plane from the ply's thickness direction [rad]:
/// 0 in modes A and B; in mode C, cos^2(theta) = (1 / (2 (1 + p23-))) ((R23A / S12)^2 (tau12 /
/// sigma2)^2 + 1), about 50 degrees in transverse compression of glass/epoxy. Throws plydem::Error
/// if a strength it needs (YT, YC, S12) is missing.
struct PuckFracturePlane {
  PuckMode mode = PuckMode::kA;
  double angle = 0;  ///< [rad]
};
PuckFracturePlane puck_fracture_plane(const PlyStress& stress, const LaminaStrength& strength);

/// The factor lambda > 0 by which `stress` must be scaled to reach the criterion's failure surface
/// (+inf if never: e.g. max-stress with a zero stress). Throws plydem::Error if a strength the
/// criterion needs for this stress is missing (0).
double failure_load_factor(FailureCriterion criterion, const PlyStress& stress,
                           const LaminaStrength& strength);

/// How a ply fails at a material point: across the fibres (fibre modes, a crack normal to the
/// fibre) or along them (inter-fibre or matrix modes, a crack parallel to the fibre), in tension
/// or compression of that direction.
enum class PlyFailureMode { kFibreTension, kFibreCompression, kMatrixTension, kMatrixCompression };

/// "fibre tension", "fibre compression", "matrix tension", "matrix compression".
const char* failure_mode_name(PlyFailureMode mode);

/// A ply's failure under a stress: the load factor (failure_load_factor's), the mode that reaches
/// the surface first, and, for a matrix mode, the inclination of the fracture plane from the ply's
/// thickness direction [rad] (0 for a fibre mode).
///  - max-stress: the stress component whose ratio to its strength governs (tau12: the matrix
///    mode, tension or compression by the sign of sigma2);
///  - Hashin, Puck: the mode whose own condition governs (fibre or inter-fibre fracture; a tie, as
///    Hashin's two tension modes make of pure in-plane shear, is the matrix mode);
///  - Tsai-Wu, Tsai-Hill: one interactive surface with no modes of its own; the mode of the larger
///    of its fibre part (the sigma1 terms) and its matrix part (the sigma2 and tau12 terms) at
///    failure, the usual reading (Reddy & Pandey 1987), the sigma1 sigma2 interaction left out.
/// The fracture angle is Puck's (puck_fracture_plane) whatever the criterion: about 50 degrees in
/// transverse compression (mode C), 0 otherwise; a criterion without an action plane has no angle
/// of its own. Throws plydem::Error as failure_load_factor does, and in matrix compression also if
/// the material lacks S12 or YC (which Puck's angle needs).
struct PlyFailure {
  double load_factor = 0;
  PlyFailureMode mode = PlyFailureMode::kMatrixTension;
  double fracture_angle = 0;  ///< [rad]
};
PlyFailure ply_failure(FailureCriterion criterion, const PlyStress& stress,
                       const LaminaStrength& strength);

/// A ply's failure as its stress grows from `preload` along `unit` (preload + lambda unit: a cure
/// stress, then the test's load): the smallest lambda >= 0 at which the stress reaches the
/// criterion's surface (core/preloaded_failure.hpp first_failure_factor; 0 when the preload alone
/// does, +inf if never) as the load factor, with ply_failure's mode and fracture angle at that
/// stress. Throws plydem::Error as ply_failure does.
PlyFailure preloaded_ply_failure(FailureCriterion criterion, const PlyStress& preload,
                                 const PlyStress& unit, const LaminaStrength& strength);

/// The uniaxial tensile strength sigma_x [Pa] of a coupon of one ply at `ply_angle` [rad] (fibre
/// from the load axis) under the criterion: failure_load_factor of the unit sigma_x.
double off_axis_strength(FailureCriterion criterion, const LaminaStrength& strength,
                         double ply_angle);
/// The uniaxial compressive strength of the same coupon, a magnitude [Pa]: failure_load_factor of
/// the unit sigma_x = -1.
double off_axis_compressive_strength(FailureCriterion criterion, const LaminaStrength& strength,
                                     double ply_angle);

}  // namespace plydem
