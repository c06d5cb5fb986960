#include "experiments/protocols/tension.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>
#include <optional>

#include "contacts/bond_kernel.hpp"
#include "core/error.hpp"
#include "core/measurements.hpp"
#include "core/progress.hpp"
#include "core/stopwatch.hpp"
#include "experiments/protocols/coupon.hpp"
#include "solvers/static_solver.hpp"
#include "strategies/registry.hpp"

namespace plydem {
namespace {

using Clock = Stopwatch::Clock;

// Cycles between the explicit run's checks where only progress reports need them (a check costs
// about one cycle), and while relaxing, where the stage ends at the first cycle within the
// tolerance.
constexpr long kProgressCheckCycles = 1000;
constexpr long kRelaxationCheckCycles = 1;

// The specimen's response at the current state: gauge strain and grip stress.
struct Sample {
  GaugeStrain strain;
  double stress = 0;
};

}  // namespace

void TensionSettings::validate() const {
  coupon.validate();
  if (!layup.empty()) interface.validate();
  for (double angle : layup)
    require(std::isfinite(angle), "a ply angle of the layup is not finite");
  require(std::isfinite(grip_length) && grip_length >= 0, "grip length must be >= 0");
  require(std::isfinite(gauge_fraction) && gauge_fraction > 0 && gauge_fraction < 1,
          fmt::format("gauge fraction must lie in (0, 1), got {}", gauge_fraction));
  require(std::isfinite(target_strain) && target_strain > 0 && target_strain < 0.05,
          fmt::format("target strain must lie in (0, 0.05) (small-strain model), got {}",
                      target_strain));
  require(load_stages >= 1 && load_stages <= 100, "load stages must lie in [1, 100]");
  require(ramp_cycles >= 1, "ramp cycles must be >= 1");
  require(std::isfinite(grip_velocity) && grip_velocity >= 0, "grip velocity must be >= 0");
  require(std::isfinite(tolerance) && tolerance > 0 && tolerance < 1,
          fmt::format("quasi-static tolerance must lie in (0, 1), got {}", tolerance));
  require(max_cycles >= 1, "max cycles must be >= 1");
  require(fixed_cycles >= 0, "fixed cycles must be >= 0");
  plydem::validate(explicit_settings);  // checked even when a static solve will not use them
  checkpoint.validate();
  require(
      solver == TensionSolver::kExplicit || (!checkpoint.writes() && checkpoint.restart.empty()),
      "--checkpoint-every, --checkpoint and --restart need the explicit solver (--solver "
      "explicit): a static solve is one step, with nothing to continue");
}

CheckpointHeader tension_checkpoint_header(const TensionSettings& s) {
  CheckpointHeader h;
  h.kind = s.solver == TensionSolver::kExplicit ? "tension/explicit" : "tension/static";
  add_coupon_settings(h, s.strategy, s.strategy_options, s.coupon, s.layup, s.interface,
                      s.grip_length, s.gauge_fraction);
  h.add("edge_band_diameters", exact(s.edge_band_diameters));
  h.add("target_strain", exact(s.target_strain));
  h.add("stages", fmt::format("{}", s.load_stages));
  h.add("ramp_cycles", fmt::format("{}", s.ramp_cycles));
  h.add("grip_velocity", exact(s.grip_velocity));
  h.add("tolerance", exact(s.tolerance));
  h.add("max_cycles", fmt::format("{}", s.max_cycles));
  h.add("cycles (fixed)", fmt::format("{}", s.fixed_cycles));
  h.add("grips", s.grips == GripCondition::kClamped ? "clamped" : "free");
  h.add("measure_specimen_stiffness", s.measure_specimen_stiffness ? "true" : "false");
  h.add("linear_solver", fmt::format("{}", static_cast<int>(s.linear_solver)));
  const ExplicitSettings& e = s.explicit_settings;
  h.add("damping", exact(e.local_damping));
  h.add("safety", exact(e.safety_factor));
  h.add("time_step", exact(e.time_step));
  // A run gives the same bits on any number of MPI ranks, so a checkpoint continues on any number
  // of ranks with the kernel that wrote it, the reference loops or the fused kernel.
  h.add("kernel", e.backend == ExplicitBackend::kReference ? "reference" : "fused");
  h.add("particle_order", fmt::format("{}", static_cast<int>(e.particle_order)));
  h.add("energy_account", e.energy_account ? "true" : "false");
  h.add("contacts", e.contacts ? "true" : "false");
  h.add("contact.skin", exact(e.contact.skin));
  h.add("contact.check_interval", fmt::format("{}", e.contact.check_interval));
  h.add("contact.friction", exact(e.contact.friction));
  h.add("strength_storage", fmt::format("{}", static_cast<int>(e.strength_storage)));
  h.add("settings_hash", fmt::format("{:016x}", h.settings_hash()));
  return h;
}

// The state of a checkpointed run: the header, the pull running, the finished pull along x, when
// the next checkpoint is due, and the file a restart continues from (until its pull has read it).
struct TensionTest::Checkpointing {
  CheckpointHeader header;
  int pull = 0;  // 0 along x, 1 along y
  const PullResult* along_x = nullptr;
  long next = 0;
  std::optional<CheckpointFile> resume;
};

namespace {

void write_pull_result(CheckpointWriter& w, const PullResult& r) {
  w.section("pull result");
  for (double v : {r.ply_angle, r.modulus, r.poisson, r.shear_coupling, r.fit_r_squared,
                   r.final_ratio, r.time_step, r.grip_velocity, r.cross_section, r.loading_transits,
                   r.build_seconds, r.wall_seconds})
    w.f64(v);
  for (const std::vector<double>* v : {&r.strain, &r.lateral_strain, &r.shear_strain, &r.stress})
    w.doubles(*v);
  w.i64(r.particles);
  w.i64(r.bonds);
  w.i64(r.cycles);
  w.boolean(r.model != nullptr);
  if (r.model) write_model(w, *r.model);
}

PullResult read_pull_result(CheckpointReader& in) {
  in.section("pull result");
  PullResult r;
  for (double* v : {&r.ply_angle, &r.modulus, &r.poisson, &r.shear_coupling, &r.fit_r_squared,
                    &r.final_ratio, &r.time_step, &r.grip_velocity, &r.cross_section,
                    &r.loading_transits, &r.build_seconds, &r.wall_seconds})
    *v = in.f64();
  for (std::vector<double>* v : {&r.strain, &r.lateral_strain, &r.shear_strain, &r.stress})
    *v = in.doubles();
  r.particles = static_cast<int>(in.i64());
  r.bonds = static_cast<int>(in.i64());
  r.cycles = in.i64();
  if (in.boolean()) {
    auto model = std::make_shared<Model>();
    read_model(in, *model);
    r.model = std::move(model);
  }
  return r;
}

}  // namespace

TensionTest::TensionTest(TensionSettings settings) : settings_(std::move(settings)) {
  settings_.validate();
}

void TensionTest::on_progress(std::function<void(const TensionProgress&)> callback) {
  progress_ = std::move(callback);
}

TensionResult TensionTest::run() const {
  const std::unique_ptr<Strategy> strategy = default_registry().create(settings_.strategy);
  for (const auto& [name, value] : settings_.strategy_options) strategy->set_option(name, value);
  SpecimenBuilder builder(*strategy);
  return run(builder);
}

TensionResult TensionTest::run(SpecimenBuilder& builder) const {
  const auto start = Clock::now();
  const BuildStatistics before = builder.statistics();
  check_resources(estimate(builder.strategy()), settings_.force, "--force");
  TensionResult result;
  result.strategy = settings_.strategy;
  result.material = settings_.coupon.material;
  result.ply_angle = settings_.coupon.ply_angle;
  if (settings_.layup.empty()) {
    result.theory = in_plane_constants(
        rotate_reduced_stiffness(reduced_stiffness(settings_.coupon.material), result.ply_angle));
  } else {
    result.theory = laminate_constants(
        laminate_plies({settings_.coupon, settings_.layup, settings_.interface}));
  }
  auto coupon_x = std::make_shared<const Specimen>(build_specimen(builder, result.ply_angle));
  result.calibration = coupon_x->ply_calibrations.front();
  result.ply_calibrations = coupon_x->ply_calibrations;
  // Checkpoints: the settings and the coupon as built must match.
  std::optional<Checkpointing> checkpointing;
  std::optional<PullResult> restored_x;
  const CheckpointOptions& ck = settings_.checkpoint;
  if (ck.writes() || !ck.restart.empty()) {
    checkpointing.emplace();
    checkpointing->header = tension_checkpoint_header(settings_);
    add_model_fingerprint(checkpointing->header, coupon_x->model, "coupon_x");
    if (!ck.restart.empty()) {
      CheckpointFile f = read_checkpoint(ck.restart);
      check_same_run(f.header, checkpointing->header, ck.restart.string());
      f.payload.section("tension");
      const std::int64_t pull_index = f.payload.i64();
      if (pull_index != 0 && pull_index != 1)
        f.payload.corrupt(fmt::format("pull {} (0 along x, 1 along y)", pull_index));
      if (pull_index == 1) restored_x = read_pull_result(f.payload);
      checkpointing->pull = static_cast<int>(pull_index);
      checkpointing->resume.emplace(std::move(f));
      spdlog::info("restarting from {} (the pull along {})", ck.restart.string(),
                   pull_index == 0 ? "x" : "y");
    }
  }
  if (restored_x) {
    result.along_x = std::move(*restored_x);
  } else {
    result.along_x = pull(*coupon_x, result.ply_angle, checkpointing ? &*checkpointing : nullptr);
  }
  if (checkpointing) {
    checkpointing->pull = 1;
    checkpointing->along_x = &result.along_x;
    checkpointing->next = 0;
  }
  const double angle_y = result.ply_angle - std::numbers::pi / 2;
  result.along_y =
      pull(build_specimen(builder, angle_y), angle_y, checkpointing ? &*checkpointing : nullptr);
  result.dem.Ex = result.along_x.modulus;
  result.dem.nu_xy = result.along_x.poisson;
  result.dem.shear_coupling_x = result.along_x.shear_coupling;
  result.dem.Ey = result.along_y.modulus;
  result.dem.nu_yx = result.along_y.poisson;
  if (settings_.measure_specimen_stiffness) {
    // The coupon along x, as built: measure_specimen_stiffness works on a copy.
    result.specimen =
        measure_specimen_stiffness(coupon_x->model, 0, settings_.linear_solver, 0, settings_.force);
    result.dem.Gxy = result.specimen.constants.Gxy;
  }
  result.coupon_x = std::move(coupon_x);
  result.build_statistics.calibrations = builder.statistics().calibrations - before.calibrations;
  result.build_statistics.builds = builder.statistics().builds - before.builds;
  result.wall_seconds = seconds_since(start);
  return result;
}

ResourceEstimate TensionTest::estimate(const Strategy& strategy) const {
  // Both coupons, the built one kept, and the specimen stiffness' copy.
  return estimate_resources(
      strategy, settings_.coupon, settings_.layup, settings_.interface,
      settings_.solver == TensionSolver::kStatic ? SolverUse::kStatic : SolverUse::kExplicit,
      settings_.measure_specimen_stiffness ? 4 : 3, 0, settings_.linear_solver);
}

Specimen TensionTest::build_specimen(SpecimenBuilder& builder, double ply_angle) const {
  return build_coupon(builder, settings_.coupon, settings_.layup, settings_.interface, ply_angle);
}

Specimen TensionTest::build_specimen(const Strategy& strategy, double ply_angle) const {
  SpecimenBuilder builder(strategy);
  return build_specimen(builder, ply_angle);
}

double TensionTest::grip_length() const {
  return settings_.grip_length > 0 ? settings_.grip_length
                                   : 2.0 * settings_.coupon.particle_diameter;
}

PullResult TensionTest::pull(const Strategy& strategy, double ply_angle) const {
  return pull(build_specimen(strategy, ply_angle), ply_angle);
}

PullResult TensionTest::pull(const Specimen& specimen, double ply_angle) const {
  return pull(specimen, ply_angle, nullptr);
}

// One pull in progress (TensionTest::pull runs its steps in order): the loaded coupon with its
// grips and gauge section, the integrator of an explicit run, the points measured so far, the
// progress reports' history and where the loading is for checkpoints.
struct TensionTest::PullRun {
  // Where the loading is (`at`, kept by the loading steps), written with each checkpoint; a
  // restart reads it back (`resumed`).
  struct LoadingState {
    long stage = 1;
    long phase = 0;  // 0 moving the grips, 1 relaxing
    long stage_start = 0;
    long relax_max = 0;
  };

  PullRun(const TensionTest& test, const Specimen& specimen, double ply_angle,
          Checkpointing* checkpointing);

  // Setup: the grips, the gauge section and what a sample reads; the integrator.
  void grip_and_gauge(double grip_length);
  // The grips of an explicit run moving apart along x at `velocity` each (0: held still).
  void grips_moving(double velocity);
  Sample sample(const Particles& state) const {
    return Sample{fit_gauge_strain(state, section.particles), grip_stress(state, area)};
  }
  // Each point goes straight into the result.
  void record(const Sample& smp);
  void report(const char* phase, const CycleReport& cycle, long planned_left);
  double loading_transits(double loading_time) const;

  // Checkpoints of explicit runs: written at the first check at or past each `checkpoint.every`
  // cycles, read back by a restart.
  long next_due() const { return (integrator->cycles() / every + 1) * every; }
  void save(long run_cycles);
  void resume();

  // The loadings.
  void start_from_uniform_state();
  void solve_at_target_strain();
  void load_fixed_cycles();
  void load_in_stages();
  void move_grips_through_stage(bool resume_here, long stage_start, double velocity, long ramp);
  void relax_stage(bool resume_here, long stage_start);

  // The fits of the points and the run's figures.
  PullResult finish(const Specimen& specimen);

  const TensionSettings& s;
  const std::function<void(const TensionProgress&)>& progress;
  Checkpointing* checkpointing;
  const Clock::time_point start;
  CouponSpec spec;
  std::shared_ptr<Model> loaded;
  Model& model;
  Particles& p;

  CouponGrips grips;
  double span = 0;
  GaugeSection section;
  std::vector<int> sampled;  // the gauge particles and the grips'
  double area = 0;
  // Only explicit runs need the integrator (and its critical time step over every bond).
  std::optional<ExplicitIntegrator> integrator;
  double dt = 0;
  PullResult result;
  double total_grip_travel = 0;

  // Progress every progress_interval() (two seconds), with an estimate of the time left: `planned`
  // cycles are known (loading), relaxation is extrapolated from the ratio's decay since the last
  // report.
  Clock::time_point last_report;
  long last_cycles = 0;
  double last_ratio = 0;
  long cycles_per_finished_stage = 0;
  int stages_left = 0;

  LoadingState at, resumed;
  long resumed_cycles = 0;  // of the phase's run, done before the checkpoint
  bool resuming = false;
  long every = 0;
};

TensionTest::PullRun::PullRun(const TensionTest& test, const Specimen& specimen, double ply_angle,
                              Checkpointing* checkpointing)
    : s(test.settings_),
      progress(test.progress_),
      checkpointing(checkpointing),
      start(Clock::now()),
      spec(test.settings_.coupon),
      loaded(std::make_shared<Model>(specimen.model)),
      model(*loaded),
      p(model.particles) {
  spec.ply_angle = ply_angle;
  grip_and_gauge(test.grip_length());
  if (s.solver == TensionSolver::kExplicit) integrator.emplace(model, s.explicit_settings);
  dt = integrator ? integrator->time_step() : 0.0;

  result.ply_angle = ply_angle;
  result.particles = p.size();
  result.bonds = model.bonds.size();
  result.time_step = dt;
  result.cross_section = area;
  total_grip_travel = 0.5 * s.target_strain * span;
  last_report = Clock::now();
  // Staged and static runs start from the unloaded origin, which is an exact equilibrium point.
  if (s.fixed_cycles == 0 || s.solver == TensionSolver::kStatic) record(Sample{});

  every = s.checkpoint.every;
  if (integrator && checkpointing && every > 0) checkpointing->next = every;
  if (integrator && checkpointing && checkpointing->resume) resume();
}

void TensionTest::PullRun::grip_and_gauge(double grip_length) {
  // Grips at both ends, gauge section in the middle.
  grips = assign_grips(p, grip_length);
  span = grips.span;
  section =
      gauge_section(p, grips, s.gauge_fraction, s.edge_band_diameters, spec.particle_diameter);
  // What a sample reads (sample()): the gauge particles' displacements, the grips' forces.
  sampled = section.particles;
  for (int i = 0; i < p.size(); ++i)
    if (p.group(i) != static_cast<int>(BoundaryGroup::kFree)) sampled.push_back(i);
  std::sort(sampled.begin(), sampled.end());
  sampled.erase(std::unique(sampled.begin(), sampled.end()), sampled.end());
  area = section.cross_section;
}

void TensionTest::PullRun::grips_moving(double velocity) {
  PrescribedMotion motion[2];
  motion[0].group = BoundaryGroup::kLeftGrip;
  motion[1].group = BoundaryGroup::kRightGrip;
  motion[0].velocity = Eigen::Vector3d(-velocity, 0, 0);
  motion[1].velocity = Eigen::Vector3d(velocity, 0, 0);
  const bool clamped = s.grips == GripCondition::kClamped;
  for (PrescribedMotion& m : motion) {
    m.fix_velocity = {true, clamped, true};
    m.fix_angular_velocity = {true, true, clamped};
  }
  integrator->set_prescribed_motions({motion[0], motion[1]});
}

void TensionTest::PullRun::record(const Sample& smp) {
  result.strain.push_back(smp.strain.exx);
  result.lateral_strain.push_back(smp.strain.eyy);
  result.shear_strain.push_back(smp.strain.gamma_xy);
  result.stress.push_back(smp.stress);
}

void TensionTest::PullRun::report(const char* phase, const CycleReport& cycle, long planned_left) {
  if (!progress || seconds_since(last_report) < progress_interval()) return;
  const long cycles = integrator->cycles();
  const double ratio = cycle.unbalanced_force_ratio;
  const double per_cycle = seconds_since(start) / std::max(1L, cycles);
  double left = planned_left;  // in cycles; < 0 = unknown
  if (planned_left < 0 && last_cycles > 0 && ratio < last_ratio && ratio > s.tolerance) {
    const double decay = std::log(last_ratio / ratio) / static_cast<double>(cycles - last_cycles);
    left = std::log(ratio / s.tolerance) / decay;
  }
  if (left >= 0 && stages_left > 0) {
    // Later stages cost what the last finished one did (the first: what this one will).
    const double per_stage = cycles_per_finished_stage > 0
                                 ? static_cast<double>(cycles_per_finished_stage)
                                 : static_cast<double>(cycles) + left;
    left += static_cast<double>(stages_left) * per_stage;
  }
  progress({phase, cycles, ratio, seconds_since(start), left >= 0 ? left * per_cycle : -1.0});
  last_report = Clock::now();
  last_cycles = cycles;
  last_ratio = ratio;
}

// How fast the grips move compared with the coupon's longitudinal wave (theory modulus along x).
double TensionTest::PullRun::loading_transits(double loading_time) const {
  const double modulus = in_plane_constants(rotate_reduced_stiffness(
                                                reduced_stiffness(spec.material), result.ply_angle))
                             .Ex;
  const double transit = span / std::sqrt(modulus / spec.material.density);
  const double transits = loading_time / transit;
  // Staged runs relax to quasi-static after each stage, so only a grip faster than the wave
  // itself (a shock) matters there; fixed-cycle runs measure while loading.
  if (transits < (s.fixed_cycles > 0 ? kQuasiStaticTransits : 1.0)) {
    spdlog::warn(
        "the grips reach their travel in {:.3g} wave transits of the coupon (< {:g}): the "
        "loading is too fast to be quasi-static{}; use more --ramp-cycles / --cycles or a lower "
        "--grip-velocity-mm-s",
        transits, s.fixed_cycles > 0 ? kQuasiStaticTransits : 1.0,
        s.fixed_cycles > 0 ? ", and the fixed-cycle mode does not relax afterwards" : "");
  }
  return transits;
}

void TensionTest::PullRun::save(long run_cycles) {
  if (!checkpointing || every <= 0 || integrator->cycles() < checkpointing->next) return;
  CheckpointWriter w;
  w.section("tension");
  w.i64(checkpointing->pull);
  if (checkpointing->pull == 1) write_pull_result(w, *checkpointing->along_x);
  w.section("pull");
  for (long v :
       {at.stage, at.phase, run_cycles, at.stage_start, at.relax_max, cycles_per_finished_stage})
    w.i64(v);
  for (const std::vector<double>* v :
       {&result.strain, &result.lateral_strain, &result.shear_strain, &result.stress})
    w.doubles(*v);
  w.f64(result.final_ratio);
  integrator->save(w);
  write_checkpoint(s.checkpoint.file, checkpointing->header, w);
  checkpointing->next = next_due();
}

void TensionTest::PullRun::resume() {
  CheckpointReader& in = checkpointing->resume->payload;
  in.section("pull");
  resumed.stage = in.i64();
  resumed.phase = in.i64();
  resumed_cycles = in.i64();
  resumed.stage_start = in.i64();
  resumed.relax_max = in.i64();
  cycles_per_finished_stage = in.i64();
  if (resumed.stage < 1 || resumed.stage > s.load_stages || resumed.phase < 0 ||
      resumed.phase > 1 || resumed_cycles < 0)
    in.corrupt(
        fmt::format("stage {}, phase {}, {} cycles", resumed.stage, resumed.phase, resumed_cycles));
  for (std::vector<double>* v :
       {&result.strain, &result.lateral_strain, &result.shear_strain, &result.stress})
    *v = in.doubles();
  result.final_ratio = in.f64();
  integrator->restore(in);
  in.finish();
  checkpointing->resume.reset();
  resuming = true;
  spdlog::info("continuing the pull along {} at cycle {}: {}", checkpointing->pull == 0 ? "x" : "y",
               integrator->cycles(),
               s.fixed_cycles > 0
                   ? fmt::format("{} of {} fixed cycles", resumed_cycles, s.fixed_cycles)
                   : fmt::format("stage {} of {}, {}", resumed.stage, s.load_stages,
                                 resumed.phase == 0 ? "moving the grips" : "relaxing"));
  if (every > 0) checkpointing->next = next_due();
}

void TensionTest::PullRun::start_from_uniform_state() {
  // CLT's uniaxial state of this pull's coupon (the ply, or the laminate, turned to this pull).
  InPlaneConstants clt;
  if (s.layup.empty()) {
    clt = in_plane_constants(
        rotate_reduced_stiffness(reduced_stiffness(spec.material), spec.ply_angle));
  } else {
    LaminateSpec turned{spec, s.layup, s.interface};
    for (double& angle : turned.ply_angles) angle += spec.ply_angle - s.coupon.ply_angle;
    clt = laminate_constants(laminate_plies(turned));
  }
  const double ex = s.target_strain, ey = -clt.nu_xy * ex,
               half_gamma = 0.5 * clt.shear_coupling_x * ex;
  const double cx = 0.5 * (grips.x_min + grips.x_max);
  const double cy =
      0.5 * (p.reference_position.col(1).minCoeff() + p.reference_position.col(1).maxCoeff());
  for (int i = 0; i < p.size(); ++i) {
    const double x = p.reference_position(i, 0) - cx, y = p.reference_position(i, 1) - cy;
    p.displacement.row(i) << ex * x + half_gamma * y, half_gamma * x + ey * y, 0;
    p.rotation.row(i).setZero();
  }
}

void TensionTest::PullRun::solve_at_target_strain() {
  // The model is linear: one solve at the target strain, fitted through the unloaded origin. An
  // iterative linear solver starts from CLT's uniform state (fewer iterations; a direct factor
  // ignores it).
  start_from_uniform_state();
  const StaticResult solved =
      solve_static(model, grip_constraints(p, -total_grip_travel, total_grip_travel, s.grips),
                   grip_solve_settings(s.linear_solver, s.force));
  record(sample(p));
  result.final_ratio = solved.relative_residual;
  result.linear_solver = solved.method_name;
  result.linear_iterations = solved.iterations;
  result.linear_solver_choice = solved.linear_solver_choice;
}

void TensionTest::PullRun::load_fixed_cycles() {
  const double v = s.grip_velocity > 0
                       ? s.grip_velocity
                       : total_grip_travel / (static_cast<double>(s.fixed_cycles) * dt);
  result.grip_velocity = v;
  result.loading_transits = loading_transits(total_grip_travel / v);
  grips_moving(v);
  // One check per sample (every 1% of the run), the samples from the second half.
  const long sample_every = std::max(1L, s.fixed_cycles / 100);
  const long done = resuming ? resumed_cycles : 0;
  Particles seen = p;  // the sampled particles' state, gathered from the kernel
  RunControl control;
  control.check_interval = sample_every;
  control.max_cycles = s.fixed_cycles - done;
  control.progress_seconds = 0;  // report() keeps its own two seconds
  control.on_progress = [&](const RunCheck& check) {
    report("loading", check.report, s.fixed_cycles - done - check.run_cycles);
  };
  // Sampling, every sample_every cycles: the forces belong to the state before the last cycle's
  // update, so both are sampled together.
  control.hooks.push_back({sample_every, 0, [&](const RunCheck& check) {
                             const long c = done + check.run_cycles;
                             if (c % sample_every == 0 && c > s.fixed_cycles / 2) {
                               integrator->gather(sampled, seen, StateAt::kForces);
                               record(sample(seen));
                             }
                             return true;
                           }});
  // Checkpointing (save() writes when one is due); the last check ends the run: nothing to
  // continue.
  control.hooks.push_back({0, 0, [&](const RunCheck& check) {
                             const long c = done + check.run_cycles;
                             if (c < s.fixed_cycles) save(c);
                             return true;
                           }});
  require(done < s.fixed_cycles, "the checkpoint's fixed-cycle run is finished already");
  const CycleReport cycle = integrator->run(control).last;
  result.final_ratio = cycle.unbalanced_force_ratio;
  if (result.final_ratio > s.tolerance) {
    spdlog::warn(
        "after {} fixed cycles the coupon at {:.4g} deg is not quasi-static (unbalanced-force "
        "ratio {:.3g} > tolerance {:.3g}): its modulus includes inertia and damping forces",
        s.fixed_cycles, result.ply_angle * 180 / std::numbers::pi, result.final_ratio, s.tolerance);
  }
}

void TensionTest::PullRun::load_in_stages() {
  const double stage_travel = total_grip_travel / s.load_stages;
  const double v = s.grip_velocity > 0 ? s.grip_velocity
                                       : stage_travel / (static_cast<double>(s.ramp_cycles) * dt);
  result.grip_velocity = v;
  result.loading_transits = loading_transits(stage_travel / v);
  const long ramp = std::max(1L, std::lround(stage_travel / (v * dt)));
  const int first_stage = resuming ? static_cast<int>(resumed.stage) : 1;
  for (int stage = first_stage; stage <= s.load_stages; ++stage) {
    const bool resume_here = resuming && stage == first_stage;
    const long stage_start = resume_here ? resumed.stage_start : integrator->cycles();
    at.stage = stage;
    at.stage_start = stage_start;
    stages_left = s.load_stages - stage;
    if (!(resume_here && resumed.phase == 1))
      move_grips_through_stage(resume_here, stage_start, v, ramp);
    grips_moving(0.0);
    relax_stage(resume_here, stage_start);
    compute_bond_forces(p, model.bonds);
    record(sample(p));
  }
}

void TensionTest::PullRun::move_grips_through_stage(bool resume_here, long stage_start,
                                                    double velocity, long ramp) {
  const long done = resume_here ? resumed_cycles : 0;
  grips_moving(velocity);
  RunControl loading;
  loading.check_interval = kProgressCheckCycles;
  loading.max_cycles = ramp - done;
  loading.progress_seconds = 0;  // report() keeps its own two seconds
  loading.on_progress = [&](const RunCheck& check) {
    const long moved = check.cycles - stage_start;
    report("loading", check.report,
           cycles_per_finished_stage > 0 ? std::max(0L, cycles_per_finished_stage - moved) : -1);
  };
  at.phase = 0;
  loading.hooks.push_back({0, 0, [&](const RunCheck& check) {  // checkpointing
                             if (done + check.run_cycles < ramp) save(done + check.run_cycles);
                             return true;
                           }});
  require(done < ramp, "the checkpoint's loading stage is finished already");
  integrator->run(loading);
}

// Relaxation, the ratio checked after every cycle: the stage ends at the first cycle whose ratio
// is within the tolerance (and after one cycle at least).
void TensionTest::PullRun::relax_stage(bool resume_here, long stage_start) {
  const bool relax_resumed = resume_here && resumed.phase == 1;
  const long relaxed_before = relax_resumed ? resumed_cycles : 0;
  at.phase = 1;
  at.relax_max =
      relax_resumed ? resumed.relax_max : std::max(1L, s.max_cycles - integrator->cycles());
  RunControl relaxing;
  relaxing.check_interval = kRelaxationCheckCycles;
  relaxing.tolerance = s.tolerance;
  relaxing.max_cycles = at.relax_max - relaxed_before;
  relaxing.progress_seconds = 0;
  relaxing.on_progress = [&](const RunCheck& check) { report("relaxing", check.report, -1); };
  relaxing.hooks.push_back({0, 0, [&](const RunCheck& check) {  // checkpointing
                              // Not at the check that ends the run (quasi-static or out of cycles).
                              const long c = relaxed_before + check.run_cycles;
                              if (check.report.unbalanced_force_ratio > s.tolerance &&
                                  c < at.relax_max)
                                save(c);
                              return true;
                            }});
  require(relaxing.max_cycles > 0, "the checkpoint's relaxation is finished already");
  const RunReport relaxed = integrator->run(relaxing);
  const CycleReport& cycle = relaxed.last;
  if (relaxed.stop != RunStop::kQuasiStatic) {
    throw Error(
        fmt::format("the tension test did not reach a quasi-static state within {} cycles "
                    "(unbalanced-force ratio {:.3g} > tolerance {:.3g}); raise --max-cycles or the "
                    "tolerance",
                    s.max_cycles, cycle.unbalanced_force_ratio, s.tolerance));
  }
  cycles_per_finished_stage = integrator->cycles() - stage_start;
  result.final_ratio = cycle.unbalanced_force_ratio;
}

PullResult TensionTest::PullRun::finish(const Specimen& specimen) {
  const LinearFit stress_fit = linear_fit(result.strain, result.stress);
  result.modulus = stress_fit.slope;
  result.fit_r_squared = stress_fit.r_squared;
  result.poisson = -linear_fit(result.strain, result.lateral_strain).slope;
  result.shear_coupling = linear_fit(result.strain, result.shear_strain).slope;
  result.cycles = integrator ? integrator->cycles() : 0;
  result.build_seconds = specimen.build_seconds;
  result.wall_seconds = specimen.build_seconds + seconds_since(start);
  result.model = std::move(loaded);
  require(std::isfinite(result.modulus) && result.modulus > 0,
          fmt::format("the tension test measured a non-positive modulus {} Pa", result.modulus));
  return std::move(result);
}

PullResult TensionTest::pull(const Specimen& specimen, double ply_angle,
                             Checkpointing* checkpointing) const {
  PullRun run(*this, specimen, ply_angle, checkpointing);
  if (settings_.solver == TensionSolver::kStatic) {
    run.solve_at_target_strain();
  } else if (settings_.fixed_cycles > 0) {
    run.load_fixed_cycles();
  } else {
    run.load_in_stages();
  }
  return run.finish(specimen);
}

}  // namespace plydem
