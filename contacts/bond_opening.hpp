#pragma once
/// \file
/// How every solver keeps a broken bond: its state says how it broke (kBrokenTension or
/// kBrokenShear), its damage is 1 and it has no stiffness left, so that a static solve, the events
/// solver and the explicit kernels all see it open. The explicit integrator, the events solver, the
/// pre-cracks of solvers/cracks.hpp and a site's crack (contacts/site_failure.hpp) open bonds
/// through these.

#include <span>

#include "core/bond_state.hpp"
#include "core/model.hpp"

namespace plydem {

/// Opens bond b in `mode` (kBrokenTension or kBrokenShear). Throws plydem::Error for a bond out of
/// range, one broken already, or another mode.
void open_bond(Bonds& bonds, int b, BondState mode);

/// Opens each of `bonds_to_open` as open_bond does (same errors).
void open_bonds(Bonds& bonds, std::span<const int> bonds_to_open, BondState mode);

}  // namespace plydem
