#pragma once
/// \file
/// Quasi-static failure event by event: sequentially linear analysis (Rots & Invernizzi 2004;
/// ../shared/DAMAGE_NOTES.md §3). The prescribed dofs move in proportion to a load factor. After
/// each linear solve at unit load, the load factor is scaled so that exactly one bond reaches its
/// strength (or, for a softening bond, the next tooth of its saw-tooth: core/bond_failure.hpp
/// softening_ratio); that bond breaks (or loses a tooth of stiffness), and the next solve starts.
/// The sequence of these critical states is the load-displacement path, snap-backs included, with
/// no damping, no loading rate and no Newton iteration.
///
/// A re-solve does not refactor: the factor of the intact stiffness is kept, and the bonds changed
/// since are a low-rank correction (Woodbury: at most 12 columns per changed bond), until the
/// correction's rank passes EventSettings::max_update_rank, when the current stiffness is
/// factored afresh. A particle left without any bond is fixed where it is (it carries nothing).

#include <functional>
#include <string>
#include <vector>

#include "core/bond_failure.hpp"
#include "core/model.hpp"
#include "solvers/static_solver.hpp"

namespace plydem {

/// One critical state: the load factor at which the next bond fails, before it does.
struct EventPoint {
  long event = 0;            ///< 1, 2, ...
  double load_factor = 0;    ///< times the unit prescribed values
  double reaction = 0;       ///< sum of the reactions on the reaction dofs at that state [N, N m]
  int bond = 0;              ///< the bond that fails (or softens) at this state
  int broken = 0;            ///< bonds broken after this event
  double strain_energy = 0;  ///< at the critical state [J]
};

struct EventProgress {
  long events = 0;
  int broken = 0;
  double load_factor = 0;
  double peak_reaction = 0;
  double elapsed_seconds = 0;
};

struct EventSettings {
  long max_events = 200000;
  /// Stop when, after the peak, the reaction at the critical state falls below this fraction of
  /// the peak reaction (the specimen has failed).
  double stop_fraction = 0.02;
  /// Softening bonds: each tooth keeps this fraction of the bond's current stiffness.
  double tooth_stiffness_ratio = 0.5;
  /// Low-rank updates of the last factorization up to this rank; then refactor.
  int max_update_rank = 600;
  /// The benchmark's baseline: factor the stiffness afresh for every event.
  bool refactor_every_event = false;
  StaticSettings static_settings;
  std::function<void(const EventProgress&)> on_progress;
  double progress_seconds = 2.0;
  /// Called at every critical state, the model holding that state (before the bond fails).
  std::function<void(const Model&, const EventPoint&)> on_event;
  /// Throws plydem::Error naming the first bad setting.
  void validate() const;
};

struct EventsResult {
  std::vector<EventPoint> path;   ///< the critical states, in order
  std::vector<BondBreak> breaks;  ///< bonds broken (at = event number, load = load factor)
  int peak = -1;                  ///< index into path of the largest reaction
  std::string stop;               ///< why it stopped: "failed", "event limit", "no bond loaded"
  int factorizations = 0;
  long solves = 0;
  double dissipated_energy = 0;  ///< energy released by broken and softened bonds [J]
  double wall_seconds = 0;
};

/// Runs events on `model` (its bonds must be breakable: Bonds::breakable) with the prescribed dofs
/// of `unit` (their values at load factor 1), the reaction summed over the dofs flagged in
/// `reaction_dofs` (one row per particle, Dof columns). Changes model.bonds (damage, state and
/// stiffnesses of the bonds that failed) and leaves the model's particles at the last critical
/// state. Throws plydem::Error for bad settings, unbreakable bonds, or constraints the static
/// solver refuses.
EventsResult run_events(Model& model, const DofConstraints& unit, const DofFlags& reaction_dofs,
                        const EventSettings& settings = {});

}  // namespace plydem
