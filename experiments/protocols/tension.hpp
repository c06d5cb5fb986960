#pragma once
/// \file
/// The virtual uniaxial tension test (paper Secs. 3.4 and 4).
///
/// A coupon long along x is built by a strategy. Grips are the particle groups within
/// `grip_length` of either end; they move apart along x at constant velocity. Stress is the grip
/// reaction force over the cross-section of the central gauge section; strain and lateral
/// contraction are least-squares fits of the gauge particles' displacements, away from the grips.
///
/// Loading runs in stages: the grips move at constant velocity to the stage's displacement, stop,
/// and the model relaxes until it is quasi-static: the mean unbalanced force on the free particles
/// is below `tolerance` times the mean bond force (PFC's ratio). Each stage gives one (strain,
/// stress) point; E and nu come from a linear least-squares fit through them and the unloaded
/// origin. With `fixed_cycles` > 0 the run instead moves the grips for exactly that many cycles
/// (the paper used 200,000) and fits the second half of the sampled history.
///
/// Loading along x of the ply at angle theta gives Ex and nu_xy; Ey and nu_yx come from loading
/// along the long axis of the same ply turned by -90 deg (the paper's x <-> y swap).
/// Grips `free` prescribe only the axial velocity (uniaxial stress: the ends may contract and
/// shear); `clamped` also hold the ends laterally.

#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "core/elasticity.hpp"
#include "experiments/protocols/coupon.hpp"
#include "experiments/protocols/resource_estimate.hpp"
#include "experiments/protocols/stiffness.hpp"
#include "solvers/explicit_integrator.hpp"
#include "solvers/linear_solver.hpp"
#include "strategies/laminate.hpp"
#include "strategies/specimen.hpp"
#include "strategies/strategy.hpp"

namespace plydem {

/// explicit: damped central differences to quasi-static (above); static: one sparse linear solve
/// of the same bonds with the grips displaced to the target strain (solvers/static_solver.hpp).
enum class TensionSolver { kExplicit, kStatic };

struct TensionSettings {
  std::string strategy = "hex2d";
  /// Strategy options (Strategy::set_option), applied in order before calibration.
  std::vector<std::pair<std::string, double>> strategy_options;
  CouponSpec coupon;  ///< material, ply angle and the coupon's size (thickness: per ply)
  /// Ply angles of a laminate, bottom to top [rad] (strategies/laminate.hpp parse_layup); empty =
  /// the single ply at coupon.ply_angle. A laminate's theory is CLT from its A matrix.
  std::vector<double> layup;
  InterfaceStiffness interface;  ///< between the plies of a laminate
  double grip_length = 0;        ///< [m]; 0 = two particle diameters
  double gauge_fraction = 0.5;   ///< central fraction of the length used as gauge section
  /// Strains are fitted on gauge particles at least this many diameters from a free edge.
  double edge_band_diameters = 2.0;
  double target_strain = 1e-3;  ///< nominal strain of the last stage
  int load_stages = 2;
  long ramp_cycles = 2000;      ///< cycles to move the grips through one stage
  double grip_velocity = 0;     ///< [m/s] per grip; 0 = from ramp_cycles
  double tolerance = 1e-5;      ///< unbalanced-force ratio that counts as quasi-static
  long max_cycles = 5'000'000;  ///< per coupon; exceeding it is an error
  long fixed_cycles = 0;        ///< > 0: the paper's fixed-cycle mode
  GripCondition grips = GripCondition::kFree;
  /// Static by default: elasticity is linear, and one sparse solve gives the state an explicit run
  /// converges to.
  TensionSolver solver = TensionSolver::kStatic;
  /// Also measure the specimen's membrane stiffness (and Gxy) with affine boundary displacements
  /// (experiments/protocols/stiffness.hpp): three more static solves on the ply's coupon.
  bool measure_specimen_stiffness = true;
  /// The static solves' factorization (solvers/linear_solver.hpp): by size, the hand-written
  /// supernodal Cholesky or CHOLMOD.
  LinearSolverKind linear_solver = LinearSolverKind::kAuto;
  ExplicitSettings explicit_settings;
  /// Build even when the coupon's estimate (experiments/protocols/resource_estimate.hpp) exceeds
  /// the machine's available memory; run() refuses it otherwise, before building.
  bool force = false;
  /// Checkpoint and restart of explicit runs (core/checkpoint.hpp; docs/restart.md,
  /// "Checkpoint and restart"): at the first check at or past every `checkpoint.every` cycles of
  /// a pull, the run's state (the pull and its stage, the integrator, the points so far, the
  /// finished pull along x) goes to `checkpoint.file`; with `checkpoint.restart` the run continues
  /// from that file to the
  /// result, bit for bit, of the run that was not stopped. A checkpoint of a run with other
  /// settings is a plydem::Error naming the setting that differs. Static solves refuse it.
  CheckpointOptions checkpoint;

  /// Throws plydem::Error naming the first bad setting.
  void validate() const;
};

/// What a tension test's checkpoint must match (without the coupon's fingerprint, which run()
/// adds): kind "tension/explicit", the coupon (add_coupon_settings), the loading and the
/// integrator's settings.
CheckpointHeader tension_checkpoint_header(const TensionSettings& settings);

/// One coupon pulled along x.
struct PullResult {
  double ply_angle = 0;       ///< [rad]
  double modulus = 0;         ///< [Pa]
  double poisson = 0;         ///< -eps_yy / eps_xx
  double shear_coupling = 0;  ///< gamma_xy / eps_xx
  double fit_r_squared = 0;
  std::vector<double> strain, lateral_strain, shear_strain, stress;  ///< fitted points [-, Pa]
  int particles = 0, bonds = 0;
  long cycles = 0;
  double final_ratio = 0;  ///< unbalanced-force ratio at the last point
  /// The static solve's linear solver (StaticResult::method_name) and its Krylov iterations (0
  /// for a direct factor); empty and 0 for explicit dynamics.
  std::string linear_solver;
  int linear_iterations = 0;
  /// --linear-solver auto: what it chose and why (StaticResult::linear_solver_choice).
  std::string linear_solver_choice;
  double time_step = 0;      ///< [s]
  double grip_velocity = 0;  ///< [m/s] per grip
  double cross_section = 0;  ///< [m^2]
  /// Explicit runs: the loading time of one stage (or of the fixed-cycle run) in units of the time
  /// a longitudinal wave takes to cross the coupon; 0 for static solves. A fixed-cycle run below
  /// kQuasiStaticTransits, or a staged run below 1 (a shock), logs a warning that the grips move
  /// too fast for the coupon to follow quasi-statically.
  double loading_transits = 0;
  /// Building the coupon (its calibrations included where they were computed for it) [s].
  double build_seconds = 0;
  double wall_seconds = 0;  ///< building and loading [s]
  /// The coupon at the end of the pull: grips assigned, displaced (static: solved at the target
  /// strain), for VTU files, figures and field maps without building or solving it again.
  std::shared_ptr<const Model> model;
};

/// A fixed-cycle loading slower than this many wave transits counts as quasi-static.
inline constexpr double kQuasiStaticTransits = 10.0;

struct TensionResult {
  std::string strategy;
  Material material;
  double ply_angle = 0;  ///< [rad]
  /// Ex, Ey, nu_xy, nu_yx from the two pulls; Gxy from the specimen stiffness (if measured).
  InPlaneConstants dem;
  InPlaneConstants theory;  ///< CLT of the ply (Q-bar)
  PullResult along_x, along_y;
  /// The ply coupon's membrane stiffness under affine boundary displacements (empty if not
  /// measured: stiffness all zero).
  SpecimenStiffness specimen;
  /// The calibration the coupon pulled along x got: its ply's (for a laminate, its bottom ply's;
  /// for lattice, that of the coupon's own packing).
  Calibration calibration;
  std::vector<Calibration> ply_calibrations;  ///< of the coupon along x, bottom to top
  /// The coupon along x as built, unloaded: further pulls of it need no new build.
  std::shared_ptr<const Specimen> coupon_x;
  /// What run() calibrated and built (each ply calibrated once, each coupon built once).
  BuildStatistics build_statistics;
  double wall_seconds = 0;
};

/// Progress of a long run, reported every few seconds.
struct TensionProgress {
  std::string phase;
  long cycles = 0;
  double ratio = 0;
  double elapsed_seconds = 0;  ///< on this coupon
  /// Estimated seconds left on this coupon: exact cycle counts while loading, the observed
  /// exponential decay of the ratio towards the tolerance while relaxing; negative when unknown.
  double seconds_left = -1;
};

class TensionTest {
 public:
  explicit TensionTest(TensionSettings settings);
  void on_progress(std::function<void(const TensionProgress&)> callback);
  /// Both loadings; the strategy is taken from the default registry and given the settings'
  /// strategy options. Each distinct ply is calibrated once and each coupon built once (the
  /// coupon along x also gives the specimen stiffness).
  TensionResult run() const;
  /// The same with `builder`'s strategy and calibrations (a builder shared by several tests
  /// calibrates each ply once over all of them); the settings' strategy options are not applied
  /// to it (set them on the strategy before making the builder).
  TensionResult run(SpecimenBuilder& builder) const;
  /// One coupon pulled along x by `strategy`: the ply at `ply_angle`, or for a laminate every ply
  /// turned by `ply_angle` - coupon.ply_angle.
  PullResult pull(const Strategy& strategy, double ply_angle) const;
  /// A copy of `specimen` pulled along x (build_specimen at `ply_angle`: no new build); the
  /// result's wall_seconds count the specimen's build_seconds.
  PullResult pull(const Specimen& specimen, double ply_angle) const;
  /// What run() will need (particles, bonds, memory), estimated before building; run() refuses
  /// it, unless settings.force, when it exceeds the machine's available memory.
  ResourceEstimate estimate(const Strategy& strategy) const;
  /// The specimen pull() loads, before grips are assigned.
  Specimen build_specimen(SpecimenBuilder& builder, double ply_angle) const;
  Specimen build_specimen(const Strategy& strategy, double ply_angle) const;
  /// The grip length at each end [m]: settings.grip_length, or two particle diameters.
  double grip_length() const;

 private:
  struct Checkpointing;
  struct PullRun;  // one pull in progress, split into its steps
  PullResult pull(const Specimen& specimen, double ply_angle, Checkpointing* checkpointing) const;
  TensionSettings settings_;
  std::function<void(const TensionProgress&)> progress_;
};

}  // namespace plydem
