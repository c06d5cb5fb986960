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
///
/// Details (solvers/bond_events.cpp says why):
/// - Teeth. A softening bond (ductility kappa_u > 1) of stiffness fraction s = 1 - damage fails at
///   kappa = softening_ratio(damage, kappa_u), on the softening line, and keeps s r of its
///   stiffness (r = EventSettings::tooth_stiffness_ratio), until its next tooth would fall below
///   EventSettings::last_tooth_stiffness: that tooth is its last, it fails at kappa = kappa_u, the
///   end of the softening line, and breaks. A brittle bond (kappa_u = 1) breaks at kappa = 1.
/// - Ties. Critical load factors within a relative kTieTolerance of the smallest are a tie: the
///   lowest bond index fails first, whatever the round-off of the solve.
/// - Pieces that come loose. When a break splits the intact bonds into more clusters, a particle
///   left alone has its free dofs fixed where the unit solution put it (it then moves with the
///   load factor, carrying nothing), a cluster with no prescribed dof is fixed at its mean
///   translation (rigidly: its intact bonds stay unloaded), and the free rigid-body modes of the
///   other clusters are pinned at zero (rigid_mode_pins on the intact bonds), all of which carries
///   no force. The free set changes, so the stiffness is factored afresh.
/// - Failure. The run stops as "failed" when the strain energy at unit load has fallen to
///   kCollapsedEnergy of its first value or the reaction at unit load to kCollapsedReaction of its
///   first (the grips are no longer connected), when after the peak
///   the reaction falls below stop_fraction of the peak (at the material point, where a crack's
///   run through a ply dips the critical states' reaction far below the peak and back, and the
///   reaction at unit load, the coupon's stiffness, below stop_fraction of its first value as
///   well), or when a factorization finds a mechanism
///   (EventsResult::message says where).
/// - Breaks are logged with the bond's contact point in the reference configuration.
/// - Energy. When a bond fails at load factor lambda at fixed grips, the structure releases
///   lambda^2 (E_1 - E_1'), E_1 and E_1' the strain energies of the unit solutions before and
///   after; dissipated_energy sums these, which is the work of the grips along the saw-tooth path
///   minus the strain energy at its end.
/// - Failure at the material point (EventSettings::material_point, issue 32): each equilibrium also
///   judges every particle's site stress at unit load (contacts/site_failure.hpp) by a lamina
///   criterion in its ply's axes (a particle whose translation is prescribed, in a grip, is not
///   judged). When a site's load factor is the smallest (below every bond's),
///   its crack opens: every intact bond across its crack plane breaks in that one event (tension
///   modes as kBrokenTension, compression modes as kBrokenShear). A site whose
///   crack is open on its normal's side and that fails again opens on the other side; open on
///   both, it is passed over. Bonds with a
///   finite strength (interfaces) still fail by their own law in the same run; bonds given none
///   (+inf) fail only with their sites.
/// - Softening sites (MaterialPointFailure::softening): the bonds across a site's crack lose their
///   stiffness together, tooth by tooth (tooth_stiffness_ratio, last_tooth_stiffness), as a
///   softening bond's do, with kappa = sqrt(W / W_peak), W the crack's bonds' strain energy at
///   their intact stiffness and W_peak its value when the site failed. A linear softening of
///   kappa_u = G A / W_peak would dissipate G (G_fibre in a fibre mode, G_matrix in a matrix mode)
///   over the crack's area A; the teeth sit on that line stretched so that they dissipate exactly
///   as much (core/bond_failure_law.hpp saw_tooth_ductility: Rots' energy-equivalent saw-tooth),
///   the first at the strength and none above it. A site's area
///   is its share of a crack plane through a lattice of such sites: V sum(e_b) / sum(|l_b . n| e_b)
///   over its crack's bonds (V the particle's volume, l_b the branch vector from the site, n the
///   normal, e_b the bond's energy), which is V / a for a lattice of spacing a along the normal. A
///   site whose kappa_u would be at most 1 (larger than 2 E G / sigma^2 across the crack: it
///   cannot soften without snap-back) opens brittle, and EventsResult::brittle_sites counts it.
///   While its crack softens a site is not judged again; the sites beside it read their strain
///   without the softening bonds (contacts/site_failure.hpp).
/// - Cracks through a layer (MaterialPointFailure::coupled, issue 33; Leguillon, Eur. J. Mech. A
///   21 (2002) 61, the coupled stress and energy criterion of finite fracture mechanics). A
///   matrix crack opens through its whole layer at once: the sites joined to the failing site by
///   intact bonds, in plies of its ply's angle, on its crack plane (within a quarter of its radius
///   along the normal), each opening bonds_across_crack on the same side, and the interface bonds
///   between those plies that cross the plane; its area is the sites' shares. It opens at the
///   larger of two load factors: its weakest site's (the stress criterion), and the one at which
///   opening it at fixed grips releases G_matrix times its area (the energy criterion): the strain
///   energy of the equilibrium less that of the equilibrium without its bonds, a quadratic in the
///   load factor (a factorization of the stiffness without them). So a thin layer, which releases
///   less than a thick one at the same stress, cracks later (the in-situ effect), and a new crack
///   between two forms when it releases G_matrix (crack multiplication). A layer's crack that
///   would leave a mechanism is not opened. Fibre modes open site by site as above. A layer's
///   energy factor found at an earlier event is kept as a lower bound of its later ones (a
///   crack shields its neighbours), and found again when it would come first: a few
///   factorizations per event rather than one per layer. The bound is not exact. The shipped
///   crossply's runs with every layer found again at every event (uncured and cured, 0.1 mm)
///   took the same path to the peak: while only layer cracks opened, a layer's factor fell from
///   one event to the next by at most 3.5% (layers that were not the next to crack), but once
///   fibre sites broke by up to 54%, so the path after the peak differs: the broken bonds at the
///   end by up to 21% ([0/90_2]s 1,153 against 1,459; dropping every kept factor after each
///   fibre break, as an earlier rule did, gave 1,211 there, and at 0.05 mm made every event
///   after the peak find every layer's factor again). The onsets, the densities and the
///   strengths were the same to the last digit. Brittle cracks only (not with softening).
/// - Preload (cure stresses, issue 33). Where the model's bonds carry free offsets
///   (Bonds::free_offset) or EventSettings::preload prescribes non-zero values, the state at load
///   factor lambda is u_p + lambda u_1: u_p the equilibrium under the offsets and the preload's
///   prescribed values (the cured specimen held in the grips), u_1 that under the unit prescribed
///   values alone; both come from one factor and its updates. Each bond's and each site's
///   critical load factor is then the smallest lambda >= 0 at which its state reaches its
///   strength (core/preloaded_failure.hpp: 0 where the preload alone fails it), a softening
///   crack's next tooth the root of its bonds' energy, a quadratic in lambda; the reactions, the
///   energies and the states the path reports are those of u_p + lambda u_1. A mixed-mode bond
///   softens with the ductility of its unit solution's mix, as without a preload. The stop rules
///   read the unit solution (the coupon's stiffness), as without.
/// - Damage energy. EventsResult::crack_energy sums, over the events, the strain energy that the
///   bonds changed in each event lose at its critical state (at fixed displacements): the energy
///   their damage dissipates, whatever the rest of the coupon releases as it re-equilibrates.

#include <functional>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "contacts/site_failure.hpp"
#include "core/bond_failure.hpp"
#include "core/checkpoint.hpp"
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
  /// Failure at the material point: the particle whose site cracked at this state (-1: a bond
  /// failed by its own law), the mode it failed in and its fracture plane's inclination from the
  /// ply's thickness direction [rad] (PlyFailure::fracture_angle).
  int site = -1;
  PlyFailureMode site_mode = PlyFailureMode::kMatrixTension;
  double site_fracture_angle = 0;
  /// A softening site's tooth: 0 when its crack opens (or opens brittle), k for its k-th tooth
  /// after that.
  int site_tooth = 0;
  /// A load step of a path that is not a failure (solvers/plastic_shear.hpp: the plastic shear
  /// run's steps before its crack), not a critical state.
  bool load_step = false;
  /// The strain energy the event's bonds lost as they changed at this state (what their damage
  /// dissipated: EventsResult::crack_energy sums these) [J]; set after EventSettings::on_event.
  double crack_energy = 0;
};

struct EventProgress {
  long events = 0;
  int broken = 0;
  double load_factor = 0;
  double peak_reaction = 0;
  double elapsed_seconds = 0;
};

struct EventsState;

/// Failure decided at the material point (see the file comment): the lamina criterion, the ply's
/// material (its stiffness gives each site's stress from its strain, its strengths the criterion's)
/// and the fibre angle of each ply (by Particles::ply) [rad].
struct MaterialPointFailure {
  FailureCriterion criterion = FailureCriterion::kPuck;
  Material material;
  std::vector<double> ply_angles;
  /// The sites' cracks soften to dissipate the material's G_fibre or G_matrix per unit area (see
  /// the file comment); false: they open brittle.
  bool softening = false;
  /// Matrix cracks by Leguillon's coupled criterion (see the file comment, "Cracks through a
  /// layer"): a matrix crack opens across its whole layer at once, when its weakest site meets the
  /// stress criterion and the layer's crack releases G_matrix times its area at fixed grips.
  bool coupled = false;
  /// Each site's strengths times its factor (by particle; empty: 1): strength scatter.
  std::vector<double> strength_factors = {};
};

/// A site's crack while its bonds soften together (see the file comment).
struct SofteningCrack {
  int site = -1;
  std::vector<int> bonds;  ///< across its plane, in increasing index
  Eigen::Vector3d normal = Eigen::Vector3d::UnitX();
  PlyFailureMode mode = PlyFailureMode::kMatrixTension;
  double fracture_angle = 0;  ///< [rad]
  double ductility = 1;       ///< kappa_u' of its teeth's line (saw_tooth_ductility)
  double peak_energy = 0;     ///< W_peak: its bonds' strain energy when the site failed [J]
  double area = 0;            ///< its share of the crack plane [m^2]
  int teeth = 0;              ///< teeth taken
};

struct EventSettings {
  long max_events = 200000;
  /// Stop when, after the peak, the reaction at the critical state falls below this fraction of
  /// the peak reaction (the specimen has failed); at the material point, when its reaction at unit
  /// load (its stiffness) has fallen below this fraction of the intact one's as well.
  double stop_fraction = 0.02;
  /// Softening bonds: each tooth keeps this fraction of the bond's current stiffness.
  double tooth_stiffness_ratio = 0.5;
  /// Softening bonds: the smallest stiffness fraction (1 - damage) a tooth may have, between 0 and
  /// tooth_stiffness_ratio. The tooth whose next one would fall below it is the last: it fails at
  /// kappa_u and breaks (see the file comment).
  double last_tooth_stiffness = 1e-3;
  /// Low-rank updates of the last factorization up to this rank; then refactor (0: refactor after
  /// every change, as refactor_every_event). An equilibrium costs O(active dofs x rank) and the
  /// correction keeps that many columns: on the paper's coupon (3,791 particles, 3 columns per
  /// changed bond) 100 to 300 gave the most events per CPU second (bench/events_bench.cpp), 600
  /// 30% fewer.
  int max_update_rank = 200;
  /// The benchmark's baseline: factor the stiffness afresh for every event.
  bool refactor_every_event = false;
  /// The static solver's settings for each factorization. The events solver needs a factor:
  /// StaticMethod::kAuto means kDirect here, and kIterative is refused.
  StaticSettings static_settings;
  std::function<void(const EventProgress&)> on_progress;
  double progress_seconds = 2.0;
  /// Called at every critical state, the model holding that state (before the bond fails).
  std::function<void(const Model&, const EventPoint&)> on_event;
  /// Called after every event, the model's bonds changed by it: a non-empty return ends the run
  /// with that text as EventsResult::stop (an experiment's own end, such as a crack length).
  std::function<std::string(const Model&, const EventPoint&)> stop_after;
  /// Checkpoints: after every `checkpoint_every` events (0 = never), on_checkpoint gets the model
  /// (its bonds after the event's bond failed) and the run's state, from which run_events
  /// continues (EventsState). Neither changes the run.
  long checkpoint_every = 0;
  std::function<void(const Model&, const EventsState&)> on_checkpoint;
  /// Failure at the material point besides the bonds' own (none: bond by bond only).
  std::optional<MaterialPointFailure> material_point;
  /// The prescribed dofs' values at load factor 0 (one row per particle, Dof columns, read where
  /// the unit load fixes a dof; empty: zero): with the bonds' free offsets, the state before the
  /// load (see the file comment, "Preload"), such as the grips holding a cured coupon where its
  /// cure left it.
  DofArray preload;
  /// Throws plydem::Error naming the first bad setting.
  void validate() const;
};

/// Critical load factors within this relative distance of the smallest are a tie.
inline constexpr double kTieTolerance = 1e-9;
/// The strain energy at unit load, relative to its first value, below which the grips are taken
/// as disconnected (the specimen has failed).
inline constexpr double kCollapsedEnergy = 1e-12;
/// The |reaction| at unit load, relative to its first value, below which the grips are taken to be
/// disconnected too: grips that strain the particles they hold (uniform grips) keep a
/// self-equilibrated strain energy in the pieces after the coupon has come apart, but transmit
/// nothing.
inline constexpr double kCollapsedReaction = 1e-9;

struct EventsResult {
  std::vector<EventPoint> path;   ///< the critical states, in order
  std::vector<BondBreak> breaks;  ///< bonds broken (at = event number, load = load factor)
  int peak = -1;                  ///< index into path of the largest |reaction|
  std::string stop;               ///< why it stopped: "failed", "event limit", "no bond loaded"
  std::string message;            ///< where a factorization found a mechanism ("failed"), else ""
  int factorizations = 0;         ///< of the stiffness (the first one included)
  long solves = 0;                ///< equilibrium solutions at unit load
  double dissipated_energy = 0;   ///< energy released by broken and softened bonds [J]
  /// The energy the changed bonds' damage dissipated (see the file comment, "Damage energy") [J].
  double crack_energy = 0;
  /// Failure at the material point: the area of the sites' cracks that are open (brittle, or
  /// softened to the end), each site's share of its plane (see the file comment) [m^2], and
  /// G_fibre or G_matrix (by the site's mode) times each one's share: what they should dissipate
  /// [J].
  double crack_area = 0;
  double crack_fracture_energy = 0;
  /// Sites that opened brittle although softening was asked (too large to soften).
  int brittle_sites = 0;
  /// Sites whose crack was still softening when the run stopped (their energy so far is in
  /// crack_energy, their area not in crack_area).
  int softening_sites = 0;
  /// The coupon's stiffness after the last event (its reaction at unit load) over the intact
  /// coupon's: how far the run followed the damage (0 where a factorization found a mechanism,
  /// NaN before the first solve).
  double final_stiffness_ratio = std::numeric_limits<double>::quiet_NaN();
  double wall_seconds = 0;
};

/// A bond's stiffness change since the last factorization, for the replay of a restart.
struct EventChange {
  int bond = 0;
  double before[6] = {0, 0, 0, 0, 0, 0};  ///< k_n, k_s, k_b, k_t, damage, state before
  double after[6] = {0, 0, 0, 0, 0, 0};   ///< and after the change
  double removed[4] = {0, 0, 0, 0};       ///< the stiffness taken away (k_n, k_s, k_b, k_t)
  /// Applied in one update with the change before it (the bonds of one site's crack share one
  /// solve with the factor for all their columns).
  bool joins_previous = false;
};

/// An events run between two events (EventSettings::on_checkpoint): with the model's bonds as
/// they were then, run_events(..., &state) continues to the events, bit for bit, that the run
/// would have given. The factor is rebuilt, not stored: the stiffness of the last factorization
/// (the bonds with the changes since undone) is factored again and the changes since are applied
/// again as the same low-rank updates, in the same order.
struct EventsState {
  long events = 0;
  int broken = 0;
  int clusters = 0;
  Eigen::VectorXd critical_u;
  DofArray critical_force;
  /// With a preload: its state and forces at the last critical state (empty without).
  Eigen::VectorXd critical_preload_u;
  DofArray critical_preload_force;
  double critical_lambda = 1, first_energy = -1, previous_energy = 0, peak_reaction = 0;
  /// With a preload: the preload's and the cross term of the energy before the last event
  /// (previous_energy is the unit load's).
  double previous_preload_energy = 0, previous_cross_energy = 0;
  double first_reaction = 0;
  std::string pending_stop;
  /// The path, breaks, peak, solves, factorizations and dissipated energy so far.
  EventsResult result;
  // The unit-load solver.
  DofConstraints constraints;      ///< the current constraints
  DofConstraints factored_from;    ///< those given to the last factorization
  DofArray preload;                ///< the current prescribed values at load factor 0
  DofArray preload_factored_from;  ///< those of the last factorization
  bool stale = true;               ///< the next solve factors afresh
  bool active_stale = true;        ///< and finds the active dofs again
  std::vector<int> active_dofs;
  long capacity = 0;  ///< columns of the update's arrays after the last factorization
  std::vector<EventChange> changes;       ///< since the last factorization (none when stale)
  std::vector<SofteningCrack> softening;  ///< the sites' cracks still softening
  /// The coupled criterion's layer cracks' energy factors found so far, each with its layer (its
  /// first site and its normal's side: +-(axis + 1)) and the event it was found at (see the file
  /// comment, "Cracks through a layer").
  struct LayerEnergyFactor {
    int site = 0, side = 0;
    double factor = 0;
    long event = 0;
  };
  std::vector<LayerEnergyFactor> layer_energy_factors;
};

void write_events_state(CheckpointWriter& out, const EventsState& state);
/// Throws plydem::Error for a corrupt state.
EventsState read_events_state(CheckpointReader& in);

/// Runs events on `model` (its bonds must be breakable: Bonds::breakable) with the prescribed dofs
/// of `unit` (their values at load factor 1), the reaction summed over the dofs flagged in
/// `reaction_dofs` (one row per particle, Dof columns). Changes model.bonds (damage, state and
/// stiffnesses of the bonds that failed) and leaves the model's particles at the last critical
/// state (at the unit-load solution if no bond was loaded). Throws plydem::Error for bad settings,
/// unbreakable bonds, bad strength fields (Model::check_consistency), a reaction dof that is not
/// prescribed, or constraints the static solver refuses.
/// With `resume` (a state of EventSettings::on_checkpoint of a run with the same model, unit
/// load, reaction dofs and settings; the model's bonds as they were then), continues that run.
EventsResult run_events(Model& model, const DofConstraints& unit, const DofFlags& reaction_dofs,
                        const EventSettings& settings = {}, const EventsState* resume = nullptr);

}  // namespace plydem
