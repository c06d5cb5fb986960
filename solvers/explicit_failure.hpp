#pragma once
/// \file
/// Failure by explicit dynamics (the strength test's method `explicit`, issue 32): the run of
/// run_events (solvers/bond_events.hpp) with damped dynamics in place of its linear solves. The
/// prescribed dofs move from rest at a constant rate, in proportion to their unit-load values as
/// the events solver's load factor moves them, and the integrator (solvers/explicit_integrator.hpp,
/// any backend) carries the specimen. Failure is decided by the events solver's laws:
/// - bonds with a strength of their own break in the kernels by the parallel-bond law
///   (core/bond_failure.hpp, brittle or softening);
/// - at the material point (ExplicitFailureSettings::material_point), every `check_cycles` cycles
///   while the prescribed dofs move (and at rest after a break, below) the sites are judged at the
///   state of that cycle's forces (contacts/site_failure.hpp site_failures; a particle whose
///   translation is prescribed is not judged). The site that fails first (next_opening_site, the
///   events solver's choice) opens its crack when its load factor is at most 1: every bond across
///   its plane breaks at once (ExplicitIntegrator:: break_bond). One site per check: a crack grows
///   from its first site as the load it sheds reaches the next, where a uniform stress would
///   otherwise fail every site of the coupon at the same check. Softening sites are the events
///   solver's only (refused here).
///
/// After every check at which something broke, the prescribed dofs stand still until the specimen
/// is at rest again (the unbalanced-force ratio at most rest_ratio, or rest_cycles at most); the
/// sites are judged there, and the next one that fails opens at the standstill; when none does,
/// the prescribed dofs move on. Each break meets the state the last one left, as in the events
/// method, not the waves it sent out: without the standstill, or with sites judged during it, a
/// uniform T300 90 deg coupon cracked in two places 2 mm apart, where the events method cracks it
/// once.
///
/// The prescribed dofs reach `failure_load_factor` (the caller's estimate of the first failure,
/// which sets only the loading rate) after `cycles_to_failure` cycles. The path's points
/// (EventPoint): every check at which a site opened or a bond broke, at the state before the
/// site's bonds opened (before bonds the kernels broke: the last check's state, within
/// check_cycles of the break, so that a brittle coupon's peak is not the state after its cascade),
/// and a sample every cycles_to_failure / 200 cycles after the first of them; load_factor = the
/// prescribed motion so far over the unit's, reaction = minus the bonds' forces on the reaction
/// dofs. The run stops "failed" when after the peak the reaction falls below stop_fraction of the
/// peak, "past the peak" when the load factor passes past_peak_travel times the peak's, and at
/// "cycle limit" after max_cycles.

#include <functional>
#include <optional>

#include "solvers/bond_events.hpp"
#include "solvers/explicit_integrator.hpp"
#include "solvers/static_solver.hpp"

namespace plydem {

struct ExplicitFailureSettings {
  ExplicitSettings integrator;
  /// The load factor the prescribed dofs reach after cycles_to_failure cycles (> 0): the
  /// caller's estimate of the first failure (the strength test: the classical criteria's).
  double failure_load_factor = 1;
  long cycles_to_failure = 20000;  ///< sets the loading rate (>= 100)
  long check_cycles = 10;          ///< cycles between the sites' judgements and the checks (>= 1)
  long max_cycles = 2000000;       ///< give up after this many cycles
  /// After a break the prescribed dofs stand still until the unbalanced-force ratio falls to
  /// rest_ratio (> 0), or for rest_cycles cycles at most (>= check_cycles).
  double rest_ratio = 1e-4;
  long rest_cycles = 20000;
  /// After the peak, the specimen has failed when the reaction falls below this fraction of it.
  double stop_fraction = 0.02;
  /// And the run ends "past the peak" when the load factor passes this multiple (> 1) of the
  /// peak's: a specimen held all round (a shear frame) keeps a residual load that never falls.
  double past_peak_travel = 2.0;
  /// Failure at the material point besides the bonds' own (none: bond by bond only); brittle.
  std::optional<MaterialPointFailure> material_point;
  /// Called at every point of the path, the model holding that state (its bonds before the
  /// point's site opened).
  std::function<void(const Model&, const EventPoint&)> on_point;
  std::function<void(const EventProgress&)> on_progress;
  double progress_seconds = 2.0;
  /// Throws plydem::Error naming the first bad setting.
  void validate() const;
};

/// Runs `model` to failure under the prescribed motion `unit` (its fixed dofs move at a constant
/// rate, rate x value; every other dof is free) and returns the path as run_events does:
/// EventsResult's path, breaks (at = the point's number, load = its load factor; the kernels'
/// breaks and the sites' bonds), peak, stop, dissipated_energy (the integrator's released energy
/// and the sites' bonds' strain energy as they opened), crack_energy (the latter), crack_area
/// and crack_fracture_energy (the opened sites' shares, site_failure.hpp crack_share). The model
/// ends at the last cycle's state with its bonds broken. Throws plydem::Error for bad settings,
/// constraints of another model, no prescribed motion, or softening sites.
EventsResult run_explicit_failure(Model& model, const DofConstraints& unit,
                                  const DofFlags& reaction_dofs,
                                  const ExplicitFailureSettings& settings);

}  // namespace plydem
