#pragma once
/// \file
/// How a tension test is shown: a table for people (GPa at the edge, labelled) and a JSON object
/// for scripts (SI units, Pa). The JSON keys Ex, Ey, nu_xy, nu_yx, theory, particles, bonds and
/// wall_seconds are a contract.

#include <nlohmann/json.hpp>
#include <string>

#include "experiments/protocols/tension.hpp"
#include "strategies/calibration.hpp"

namespace plydem {

std::string format_tension_table(const TensionResult& result, const TensionSettings& settings);
nlohmann::json tension_json(const TensionResult& result, const TensionSettings& settings);

/// A second model of the very coupon the DEM pulled (CalculiX of the same coupon:
/// experiments/fem fem_twin_tension_test), shown beside the DEM and CLT.
struct SameCouponReference {
  std::string name;            ///< e.g. "CalculiX"
  std::string description;     ///< one line: elements, mesh, how strains were measured
  InPlaneConstants constants;  ///< Ex, Ey, nu_xy, nu_yx, shear_coupling_x (Gxy unused)
  double wall_seconds = 0;
};

/// The table of the DEM beside the same-coupon reference and CLT: each of Ex, Ey, nu_xy, nu_yx
/// with DEM vs reference (the particle model's own error) and reference vs CLT (what the coupon's
/// free edges and grips do, by physics).
std::string format_same_coupon_table(const TensionResult& result,
                                     const SameCouponReference& reference);
/// The same as JSON (SI): the reference's constants, "description", "wall_seconds", and
/// "dem_error" (DEM vs reference: moduli as relative errors, Poisson's ratios as differences).
nlohmann::json same_coupon_json(const TensionResult& result, const SameCouponReference& reference);

/// The calibration as JSON (SI units): method, lattice orientation, every family's stiffnesses,
/// the target, affine and relaxed 3x3 stiffness and the relaxed relative error.
nlohmann::json calibration_json(const Calibration& calibration);

/// A refused ply (strategies/calibration.hpp) as JSON (SI units): strategy, reason, frame, the
/// components that cannot be reached, target and nearest reachable 3x3 stiffness, the nearest's
/// relative error and the strategies that represent the ply. `plydem calibrate --json` and
/// `plydem tension --json` print it under "refused" when the strategy refuses.
nlohmann::json refusal_json(const Unreachable& refusal);

/// The calibration as a table for `plydem calibrate`.
std::string format_calibration(const Calibration& calibration, const std::string& strategy,
                               const Material& material, double ply_angle);

}  // namespace plydem
