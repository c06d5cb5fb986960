#pragma once
/// \file
/// How a tension test is shown: a table for people (GPa at the edge, labelled) and a JSON object
/// for scripts (SI units, Pa). The JSON keys Ex, Ey, nu_xy, nu_yx, theory, particles, bonds and
/// wall_seconds are a contract.

#include <nlohmann/json.hpp>
#include <string>

#include "experiments/tension_test.hpp"

namespace plydem {

std::string format_tension_table(const TensionResult& result, const TensionSettings& settings);
nlohmann::json tension_json(const TensionResult& result, const TensionSettings& settings);

}  // namespace plydem
