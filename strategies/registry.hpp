#pragma once
/// \file
/// Strategies registered by name at run time. The built-in ones are added by a CMake-generated
/// function (register_builtin_strategies) that calls each strategy file's register_<name>(), so
/// registration survives static linking; a user adds their own with registry.add() in their main:
///
///   plydem::Registry& registry = plydem::default_registry();
///   registry.add("my-packing", "my own packing", [] { return std::make_unique<MyStrategy>(); });

#include <string>
#include <vector>

#include "core/registry.hpp"
#include "strategies/strategy.hpp"

namespace plydem {

using StrategyFactory = FactoryRegistry<Strategy>::Factory;

/// Strategies by name (core/registry.hpp): add() throws plydem::Error if the name is empty or
/// taken, create() lists the registered names if `name` is unknown.
class Registry : public FactoryRegistry<Strategy> {
 public:
  Registry();
};

/// The names of the strategies in `registry` (but `except`) whose calibrate(), with their default
/// options, reaches the ply exactly: no refusal, and a relaxed stiffness within 1e-6 (relative,
/// Frobenius) of the target. The "-paper" strategies, which report an error rather than refuse,
/// count only where they are exact. A refusal inside this lookup does not look up again (no
/// recursion). Remembered per registry and ply for the life of the process: the random lattice
/// takes seconds to refuse.
std::vector<std::string> strategies_representing(const Registry& registry, const Material& material,
                                                 double ply_angle, double thickness,
                                                 const std::string& except = "");

/// True while strategies_representing() is calibrating on this thread.
bool inside_representation_lookup();

/// Calls every built-in strategy's register_<name>() (generated from CMakeLists.txt).
void register_builtin_strategies(Registry& registry);

/// The process-wide registry, filled with the built-in strategies on first use.
Registry& default_registry();

}  // namespace plydem
