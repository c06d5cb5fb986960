#pragma once
/// \file
/// The virtual tension test to failure (`plydem strength`): the tension test's coupon
/// (experiments/protocols/coupon.hpp: the same build, grips, gauge section and strain fit) with
/// breakable bonds, pulled until it fails.
///
/// Strengths. Each distinct ply is given its bond strengths by calibrate_strengths
/// (strategies/strength_calibration.hpp: the relaxed bulk without scatter first breaks exactly at
/// XT, YT and S12 in the ply's axes), and every bond of the built coupon its own by
/// assign_bond_strengths (edge bonds scaled with their stiffness weights, Weibull scatter when a
/// modulus is given, interface bonds from the interface strengths).
///
/// Grips (StrengthGrips). By default (`uniform`) the grip particles are held at the relaxed
/// bulk's uniform state under sigma_x: the displacement E (x - centre) of the strain E that the
/// plies' relaxed stiffness (their calibrations as simulated, summed as CLT sums them) gives under
/// sigma_x alone, and each ply's bulk spin (core/homogenizer.hpp relaxed_motion on the strategy's
/// unit cell; zero for a cell of several particles). The gauge between them then carries the
/// uniform uniaxial stress the classical criteria assume, up to the grips, so that a coupon
/// without scatter first breaks at the calibrated targets (XT at 0 deg, YT at 90 deg). `free` and
/// `clamped` are the tension test's grips (rigid along x: the left grip's ux held, the right
/// grip's moved), which restrain the ply's Poisson contraction and shear and so break it first
/// next to them (E-glass on square at 0 deg: at about a third of XT).
///
/// Loading, method `events` (sequentially linear analysis, solvers/bond_events.hpp): the grips'
/// prescribed values move in proportion to the load factor (unit: a nominal strain of 1e-3); both
/// grips are held in z and against tilting; the rigid modes left are pinned. The reaction is the
/// sum of the right grip's ux reactions. Each critical state is one point of the curve: the gauge
/// strain fitted as the tension test fits it (at the critical state, which is the unit state's
/// strain times the load factor) against the reaction over the gauge cross-section. The strength
/// is the peak stress; the first-failure stress is the first event's.
///
/// Theory: each classical criterion (core/failure_criteria.hpp) at the coupon's load: for one ply
/// the off-axis strength at its angle; for a laminate the first-ply failure of classical
/// lamination theory (the plies' stresses from the A matrix under the mean stress sigma_x, the
/// smallest failure_load_factor over the plies).
///
/// Method `explicit` (solvers/explicit_failure.hpp): the same grips move from rest at a constant
/// rate, in proportion to the same unit load, and the damped integrator carries the coupon; bonds
/// break in the kernels by their own law, and at the material point the sites are judged every
/// StrengthExplicitLoading::check_cycles cycles, the first to fail opening its crack (brittle).
/// The rate: the grips reach the classical criteria's smallest strength of the coupon (theory, at
/// the bulk's modulus along x) after cycles_to_failure cycles; it sets only how fast the coupon is
/// loaded, not where it fails. Each point of the curve is a check at which something broke, or a
/// sample after the first; the result's `events` counts these points. No checkpoints.

#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/bond_failure.hpp"
#include "core/elasticity.hpp"
#include "core/failure_criteria.hpp"
#include "experiments/protocols/coupon.hpp"
#include "experiments/protocols/plate_hole.hpp"
#include "experiments/protocols/resource_estimate.hpp"
#include "solvers/bond_events.hpp"
#include "solvers/explicit_failure.hpp"
#include "solvers/explicit_integrator.hpp"
#include "strategies/laminate.hpp"
#include "strategies/strategy.hpp"
#include "strategies/strength_calibration.hpp"

namespace plydem {

enum class StrengthMethod { kEvents, kExplicit };

/// How the strength test's grips hold the coupon (see the file comment).
enum class StrengthGrips {
  kUniform,  ///< at the relaxed bulk's uniform state under sigma_x (ux, uy, spin)
  kFree,     ///< the tension test's free grips: rigid along x, laterally free
  kClamped,  ///< the tension test's clamped grips: rigid along x, held laterally
};
/// "uniform", "free" or "clamped".
const char* strength_grips_name(StrengthGrips grips);
/// The inverse; throws plydem::Error naming anything else.
StrengthGrips parse_strength_grips(const std::string& name);
/// Which way the grips move: apart (tension), together (compression), or (shear) in in-plane
/// shear with a frame (see StrengthSettings::load).
enum class StrengthLoad { kTension, kCompression, kShear };
/// "tension", "compression" or "shear".
const char* strength_load_name(StrengthLoad load);
/// The inverse; throws plydem::Error naming anything else.
StrengthLoad parse_strength_load(const std::string& name);
/// "events" or "explicit".
const char* strength_method_name(StrengthMethod method);
/// "events" -> kEvents, "explicit" -> kExplicit; throws plydem::Error naming anything else.
StrengthMethod parse_strength_method(const std::string& name);

/// The explicit method's loading (solvers/explicit_failure.hpp; see the file comment).
struct StrengthExplicitLoading {
  long cycles_to_failure = 20000;  ///< cycles to the classical first failure (>= 100)
  long check_cycles = 10;          ///< cycles between the sites' judgements (>= 1)
  long max_cycles = 2000000;       ///< give up after this many cycles
};

struct StrengthSettings {
  /// square meets E-glass's XT, YT and S12 at any angle; hex2d's layer cannot give E-glass YT
  /// with S12 (strategies/strength_calibration.hpp says which it can, and who can).
  std::string strategy = "square";
  /// Strategy options (Strategy::set_option), applied in order before calibration.
  std::vector<std::pair<std::string, double>> strategy_options;
  /// Material (with strengths XT, YT, S12), ply angle and the coupon's size (thickness: per ply).
  CouponSpec coupon;
  /// Ply angles of a laminate, bottom to top [rad]; empty = the single ply at coupon.ply_angle.
  std::vector<double> layup;
  InterfaceStiffness interface;          ///< between the plies of a laminate
  InterfaceStrength interface_strength;  ///< not given: the interfaces do not break
  StrengthMethod method = StrengthMethod::kEvents;
  /// Tension (the grips move apart) or compression (`--load compression`: together; failure at
  /// the material point only, with XC and YC given). A compression test's stresses and strains
  /// are reported along the load, positive in compression, as compression tests report them.
  /// Shear (`--load shear`: failure at the material point, uniform grips, no hole): a frame holds
  /// the coupon at the relaxed bulk's uniform state under tau_xy alone, the grips along x and
  /// bands of the grips' depth (two diameters by default) along the y edges, so that no edge is
  /// free; the stress is the right grip's y reaction over the cross-section (tau_xy), the strain
  /// the gauge's gamma_xy. A 0 deg ply's peak is its in-plane shear strength S12.
  StrengthLoad load = StrengthLoad::kTension;
  /// Weibull modulus of the bonds' strength scatter; unset = the material's
  /// (LaminaStrength::weibull_modulus), 0 = no scatter.
  std::optional<double> weibull_modulus;
  std::uint64_t seed = 1;  ///< random stream of the scatter (the same seed, the same strengths)
  /// The plies (0-based, bottom to top) whose bonds get the scatter; empty = every ply. A
  /// cross-ply's transverse cracking: the 90° plies only, the 0° plies at their calibrated
  /// strengths.
  std::vector<int> scatter_plies;
  /// Draw the scatter per crack site (a band between particle rows along the fibre, shared by the
  /// bonds that cross it; assign_bond_strengths) instead of per bond: transverse cracks that run
  /// through their band, as a cross-ply's 90° cracks do.
  bool scatter_per_crack_site = false;
  /// thermal.delta_T, `--delta-T`: the temperature change from stress-free to test [K] (cure
  /// cooling: negative; 0 = none). Each bond's free offset is its plies' thermal strain
  /// (strategies/cure_stress.hpp), the grips hold the coupon where its free cure left it
  /// (cured_preload), and the load adds to that state (solvers/bond_events.hpp, "Preload"); the
  /// strains are measured from it. The events method only; the material's alpha1, alpha2 needed.
  double delta_T = 0;
  StrengthOptions strength_options;  ///< friction coefficient, softening
  /// `--coupled-criterion`: matrix cracks by Leguillon's coupled criterion at the material point
  /// (MaterialPointFailure::coupled): each opens through its whole layer at once, when its
  /// weakest site meets the lamina criterion and the layer's crack releases G_matrix per unit
  /// area at fixed grips (finite fracture mechanics: the in-situ effect). Brittle sites only.
  bool coupled_criterion = false;
  /// How the ply fails (`--failure-criterion`); unset = the material's failure_criterion. `bond`:
  /// bond by bond with the parallel-bond law; a lamina criterion: at the material point
  /// (EventSettings::material_point): each site's stress judged by the criterion in its ply's
  /// axes, its crack opening every bond across it at once (brittle, without scatter, by the events
  /// method; the interfaces keep their own strengths).
  std::optional<PlyFailureModel> failure_criterion;
  /// [m]; 0 = two particle diameters, at the material point (failure_criterion other than bond)
  /// the edge strips' depth plus the longest bond (strength.cpp, default_grip_length).
  double grip_length = 0;
  /// A central circular hole of this diameter [m] (0 = none), centred in the coupon's extent:
  /// the particles inside it are removed with their bonds and the free edges, the hole's
  /// included, completed as boundary cells after the cut (experiments/protocols/plate_hole.hpp).
  /// The edge pass of `consistent_edges` leaves the bonds within one hole diameter of the hole's
  /// edge as assigned: their concentration is the notch's own. Must be narrower than 0.9 of the
  /// width, at least one particle diameter, and clear of the grips.
  double hole_diameter = 0;
  double gauge_fraction = 0.5;       ///< central fraction of the length used as gauge section
  double edge_band_diameters = 2.0;  ///< gauge particles at least this far from a free edge
  StrengthGrips grips = StrengthGrips::kUniform;
  LinearSolverKind linear_solver = LinearSolverKind::kAuto;
  /// The events solver's settings (its static settings get the grips' rigid-mode pins and
  /// `linear_solver`; its on_progress and on_event are the test's own: leave them empty). Teeth of
  /// softening bonds keep 0.8 of their stiffness (EventSettings' 0.5 makes the dissipated energy
  /// depend on the particle size by more than 5%).
  EventSettings events = [] {
    EventSettings e;
    e.tooth_stiffness_ratio = 0.8;
    return e;
  }();
  /// The explicit method's integrator settings and its loading.
  ExplicitSettings explicit_settings;
  StrengthExplicitLoading explicit_loading;
  /// Keep copies of the model at selected critical states (StrengthResult::snapshots), for VTU
  /// series.
  bool record_snapshots = false;
  /// Free edges consistent with the bulk (uniform grips only): before the run, the coupon is
  /// solved at unit load with the strengths as assigned (no scatter), and every bond that would
  /// fail before the first bond of the relaxed bulk under the same uniform stress gets its
  /// strengths raised to fail with it (never lowered; bonds that fail later are left alone, so
  /// the damage that follows the first failure is the model's own). Edges that cut a turned lattice
  /// carry more than the bulk (their completion is exact along lattice lines only: issue 14), so
  /// without this the coupon breaks at its edges first, 28-44% early for square at 15-75 deg.
  /// Scatter then multiplies the raised strengths as it does the others. false: strengths from the
  /// stiffness weights alone.
  bool consistent_edges = true;
  /// Build even when the coupon's estimate (experiments/protocols/resource_estimate.hpp) exceeds
  /// the machine's available memory; run() refuses it otherwise, before building.
  bool force = false;
  /// Checkpoint and restart (core/checkpoint.hpp; docs/restart.md, "Checkpoint and restart"):
  /// every `checkpoint.every` events the run's state goes to `checkpoint.file`; with
  /// `checkpoint.restart` the run continues from that file (which must be of a run with the same
  /// settings: a checkpoint of another is a plydem::Error naming the setting that differs) to the
  /// result, bit for bit, of the run that was not stopped. Not itself part of the settings a
  /// checkpoint matches.
  CheckpointOptions checkpoint;

  /// The Weibull modulus the run uses: weibull_modulus or the material's.
  double effective_weibull_modulus() const;
  /// The failure criterion the run uses: failure_criterion or the material's.
  PlyFailureModel effective_failure_criterion() const;
  /// Throws plydem::Error naming the material and what it lacks for this run (`purpose` names
  /// the run): XT, YT, S12, and with softening the fracture energies (require_strengths), under
  /// whichever failure criterion the run uses; in compression also XC and YC.
  void require_strengths_for(const std::string& purpose) const;
  /// Throws plydem::Error naming the first bad setting: the coupon, the hole, the layup, the
  /// interfaces (stiffness and strength; interface strengths without a laminate), a NaN or negative
  /// Weibull modulus, the gauge, the events and explicit settings.
  void validate() const;
};

/// Bonds broken in one family and mode.
struct BrokenBonds {
  std::string family;  ///< the family's label ("1 (fibre)", ...) or "interface k-(k+1)"
  bool interface = false;
  int tension = 0;
  int shear = 0;
};

/// A classical criterion's strength of the coupon: nullopt with the reason when the criterion
/// needs a strength the material does not give.
struct CriterionStrength {
  FailureCriterion criterion = FailureCriterion::kMaxStress;
  std::optional<double> strength;  ///< [Pa]
  std::string missing;             ///< why there is no value, else ""
};

/// A copy of the model at one critical state (before its bond fails), or after the last event.
struct StrengthSnapshot {
  long event = 0;     ///< the event number; the final state (after the last bond broke): last + 1
  std::string label;  ///< "first failure", "peak", "event N", "final"
  std::shared_ptr<const Model> model;
};

/// A point of the material's shear_curve beside the shear test's curve at the same strain.
struct ShearCurveCheck {
  double strain = 0;    ///< gamma12 of the material file's point
  double measured = 0;  ///< its tau12 [Pa]
  double law = 0;       ///< the fitted Ramberg-Osgood law's tau12 there [Pa]
  /// The gauge's |tau_xy| at |gamma_xy| = strain on the simulated curve (linear between its
  /// points) [Pa]; NaN beyond the peak (the coupon cracked before it).
  double simulated = std::numeric_limits<double>::quiet_NaN();
};

struct StrengthResult {
  std::string strategy;
  Material material;
  double ply_angle = 0;       ///< [rad]
  std::vector<double> layup;  ///< ply angles as built [rad]; empty for one ply
  StrengthMethod method = StrengthMethod::kEvents;
  StrengthLoad load = StrengthLoad::kTension;
  double weibull_modulus = 0;  ///< as used (0 = no scatter)
  std::uint64_t seed = 1;
  double delta_T = 0;  ///< the cure's temperature change [K] (StrengthSettings::delta_T; 0: none)

  /// The failure criterion the run used (StrengthSettings::effective_failure_criterion).
  PlyFailureModel failure_criterion = PlyFailureModel::kBond;
  /// At the material point: the mode of the site that cracked at the peak ("matrix tension",
  /// ...); empty where a bond failed there by its own law.
  std::string peak_mode;
  /// At the material point: the inclination of the peak site's fracture plane from the ply's
  /// thickness direction [rad] (Puck's, about 50 degrees in transverse compression); NaN where a
  /// bond failed there by its own law.
  double peak_fracture_angle = std::numeric_limits<double>::quiet_NaN();
  int cracked_sites = 0;  ///< sites whose crack opened (failure at the material point)
  /// At the material point (EventsResult): the energy the cracks' bonds dissipated [J], the area
  /// of the cracks that opened [m^2], G_fibre or G_matrix times each one's area [J], and with
  /// softening the sites that opened brittle, too large to soften.
  double crack_energy = 0;
  double crack_area = 0;
  double crack_fracture_energy = 0;
  int brittle_sites = 0;
  int softening_sites = 0;  ///< still softening at the stop (EventsResult::softening_sites)
  /// The events method's: the coupon's stiffness after the last event over the intact coupon's
  /// (EventsResult::final_stiffness_ratio); NaN by the explicit method.
  double final_stiffness_ratio = std::numeric_limits<double>::quiet_NaN();
  /// In-plane shear of a material with a shear_curve (solvers/plastic_shear.hpp): its points
  /// beside the simulated curve (a ply at 0 or 90 deg, where gamma_xy is gamma12; empty
  /// otherwise), the fitted law's exponent eta and the sites' plastic work [J].
  bool plastic_shear = false;
  std::vector<ShearCurveCheck> shear_curve;
  double shear_law_eta = 0;
  double plastic_work = 0;

  /// Stresses and strains along the load (StrengthSettings::load): positive in compression.
  double strength = 0;              ///< peak stress [Pa]
  double strain_at_peak = 0;        ///< gauge strain at the peak
  double first_failure_stress = 0;  ///< stress of the first event [Pa]
  double first_failure_strain = 0;
  /// The stress-strain curve: the unloaded origin, then one point per critical state.
  std::vector<double> strain, stress;
  /// The same points' nominal strain: the grips' separation over their initial distance.
  std::vector<double> nominal_strain;
  /// Broken bonds by family and mode (families with no broken bond are listed with zeros).
  std::vector<BrokenBonds> broken;
  int broken_tension = 0, broken_shear = 0;
  int damaged = 0;                        ///< softening bonds with 0 < damage < 1 at the end
  std::vector<CriterionStrength> theory;  ///< max-stress, Tsai-Hill, Tsai-Wu, Hashin
  /// The calibrated bulk's first failure under this load (StrengthCalibration::
  /// first_failure_factor of each ply's CLT stress; no edges, no scatter) [Pa].
  double model_first_failure = 0;
  /// StrengthSettings::consistent_edges: bonds whose strengths were raised, and the largest
  /// factor (1 if none).
  int edge_strengthened_bonds = 0;
  double edge_strength_factor = 1;
  std::vector<StrengthCalibration> ply_strengths;  ///< bottom to top
  Calibration calibration;                         ///< of the bottom ply

  long events = 0;
  std::string stop;  ///< why the run stopped (EventsResult::stop)
  int factorizations = 0;
  long solves = 0;
  double dissipated_energy = 0;  ///< [J]
  std::vector<EventPoint> path;
  std::vector<BondBreak> breaks;
  int peak = -1;  ///< index into path (the curve's point peak + 1)

  int particles = 0, bonds = 0;
  /// StrengthSettings::hole_diameter > 0: what the hole took out, and its centre (x, y) [m].
  HoleRemoval hole;
  Eigen::Vector2d hole_centre = Eigen::Vector2d::Zero();
  double cross_section = 0;  ///< [m^2]
  double span = 0;           ///< grip-to-grip length along x [m]
  /// The relaxed bulk's uniform state under sigma_x (what uniform grips hold), per unit strain
  /// eps_xx: its strain (xx, yy, gamma_xy) and each ply's spin [rad], bottom to top.
  Eigen::Vector3d uniform_strain = Eigen::Vector3d::Zero();
  std::vector<double> uniform_spin;
  double build_seconds = 0;
  double wall_seconds = 0;
  /// The coupon after the run: bonds broken and softened, particles at the last critical state.
  std::shared_ptr<const Model> model;
  /// With StrengthSettings::record_snapshots: first failure, events 2^k, the peak and the final
  /// state, in event order.
  std::vector<StrengthSnapshot> snapshots;
};

class StrengthTest {
 public:
  explicit StrengthTest(StrengthSettings settings);
  /// Progress of long runs, every EventSettings::progress_seconds.
  void on_progress(std::function<void(const EventProgress&)> callback);
  /// Builds, calibrates strengths and runs to failure. Throws plydem::Error: a material without
  /// the strengths (XT, YT, S12), a strategy without a unit cell or a target it cannot reach (the
  /// strength calibration's errors), the explicit method with checkpoints or softening sites.
  StrengthResult run() const;
  /// The same with `builder`'s strategy and stiffness calibrations (shared by several tests).
  StrengthResult run(SpecimenBuilder& builder) const;
  /// What run() will need (particles, bonds, memory), estimated before building; run() refuses
  /// it, unless settings.force, when it exceeds the machine's available memory.
  ResourceEstimate estimate(const Strategy& strategy) const;
  const StrengthSettings& settings() const { return settings_; }

 private:
  StrengthSettings settings_;
  std::function<void(const EventProgress&)> progress_;
};

/// What a strength test's checkpoint must match (without the model's fingerprint, which run()
/// adds): kind "strength/events", the coupon (add_coupon_settings), the strengths, grips, gauge,
/// events settings and whether snapshots are recorded.
CheckpointHeader strength_checkpoint_header(const StrengthSettings& settings);

/// The mean stress sigma_x [Pa] at which the first ply of `plies` reaches `criterion` under
/// uniaxial membrane load along x (classical lamination theory: ply stresses Q-bar_k A^-1 N with
/// N = (sigma_x h, 0, 0)), in tension or, a magnitude, in compression; in shear the mean tau_xy
/// under N = (0, 0, tau_xy h). One ply in tension or compression: its off-axis strength. Throws
/// plydem::Error like failure_load_factor.
double first_ply_failure_stress(FailureCriterion criterion, const std::vector<Ply>& plies,
                                const LaminaStrength& strength,
                                StrengthLoad load = StrengthLoad::kTension);

}  // namespace plydem
