#pragma once
/// \file
/// How a tension test is shown: a table for people (GPa at the edge, labelled) and a JSON object
/// for scripts (SI units, Pa). The JSON keys Ex, Ey, nu_xy, nu_yx, theory, particles, bonds and
/// wall_seconds are a contract.

#include <nlohmann/json.hpp>
#include <string>

#include "experiments/protocols/tension_test.hpp"
#include "strategies/calibration.hpp"

namespace plydem {

std::string format_tension_table(const TensionResult& result, const TensionSettings& settings);
nlohmann::json tension_json(const TensionResult& result, const TensionSettings& settings);

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
