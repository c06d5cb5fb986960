#pragma once
/// \file
/// A bond's state, apart from the model's arrays so that the failure law
/// (core/bond_failure_law.hpp) can name it in code compiled for a device.

namespace plydem {

/// Whether a bond still holds, or how it broke (core/bond_failure.hpp). Stored as int in
/// Bonds::state. A broken bond keeps its row (its identity: family, kind, ends) with zero
/// stiffness.
enum class BondState : int { kIntact = 0, kBrokenTension = 1, kBrokenShear = 2 };

}  // namespace plydem
