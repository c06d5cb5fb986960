#pragma once
/// \file
/// A central hole cut into a built plate: the particles inside a circle taken out with their
/// bonds, and the free edge that leaves (the hole's, and the plate's own) completed as boundary
/// cells of the strategy's layer. Shared by the elastic hole-in-plate experiment
/// (experiments/runner/hole_plate.hpp, paper Fig. 16) and the strength test of a notched plate
/// (strength.hpp, StrengthSettings::hole_diameter).

#include <string>

#include "core/model.hpp"
#include "strategies/boundary_cells.hpp"
#include "strategies/strategy.hpp"

namespace plydem {

/// What remove_hole took out of a model.
struct HoleRemoval {
  int particles = 0;  ///< particles removed
  int bonds = 0;      ///< bonds removed with them
};

/// Removes every particle whose centre lies inside the circle of `diameter` centred at
/// (centre_x, centre_y) in the x-y plane (|x - c| < D/2), together with its bonds; the rest keep
/// their order. Then checks that every ply is still one piece through its own bonds (in-ply
/// bonds; interface bonds do not count): throws plydem::Error, leaving the model unchanged, if the
/// hole removes no particle or every particle, leaves a loose particle (no in-ply bond), or cuts a
/// ply apart (a hole as wide as the plate).
HoleRemoval remove_hole(Model& model, double centre_x, double centre_y, double diameter);

/// How `strategy` (registered as `name`) completes the boundary cells of its layer, to be redone
/// once a hole is cut (Strategy::boundary_completion). Throws plydem::Error naming the strategy
/// when it completes its edges its own way (hcp, lattice), which cannot be redone on a cut plate.
BoundaryCompletion hole_boundary_completion(const Strategy& strategy, const std::string& name);

/// Completes the boundary cells (strategies/boundary_cells.hpp) of every ply of `model` from its
/// in-ply bonds; interface bonds keep their stiffness. For a plate built without completion
/// (CouponSpec::complete_boundary_cells = false) whose hole has been cut.
void complete_ply_boundary_cells(Model& model, const BoundaryCompletion& completion);

}  // namespace plydem
