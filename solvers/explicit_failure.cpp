#include "solvers/explicit_failure.hpp"

#include <fmt/format.h>

#include <cmath>
#include <cstddef>
#include <limits>
#include <numeric>
#include <utility>
#include <vector>

#include "contacts/bond_kernel.hpp"
#include "contacts/site_failure.hpp"
#include "core/error.hpp"
#include "core/parallel_bond.hpp"
#include "core/stopwatch.hpp"

namespace plydem {

void ExplicitFailureSettings::validate() const {
  plydem::validate(integrator);
  require(std::isfinite(failure_load_factor) && failure_load_factor > 0,
          fmt::format("explicit failure: failure_load_factor is {}, must be positive",
                      failure_load_factor));
  require(cycles_to_failure >= 100,
          fmt::format("explicit failure: cycles_to_failure is {}, must be at least 100 (fewer "
                      "cycles load the specimen faster than its waves cross it)",
                      cycles_to_failure));
  require(check_cycles >= 1,
          fmt::format("explicit failure: check_cycles is {}, must be >= 1", check_cycles));
  require(max_cycles >= cycles_to_failure,
          fmt::format("explicit failure: max_cycles ({}) is below cycles_to_failure ({})",
                      max_cycles, cycles_to_failure));
  require(std::isfinite(rest_ratio) && rest_ratio > 0,
          fmt::format("explicit failure: rest_ratio is {}, must be positive", rest_ratio));
  require(rest_cycles >= check_cycles,
          fmt::format("explicit failure: rest_cycles ({}) is below check_cycles ({})", rest_cycles,
                      check_cycles));
  require(
      std::isfinite(past_peak_travel) && past_peak_travel > 1,
      fmt::format("explicit failure: past_peak_travel is {}, must be above 1", past_peak_travel));
  require(stop_fraction >= 0 && stop_fraction < 1,
          fmt::format("explicit failure: stop_fraction is {}, must lie in [0, 1)", stop_fraction));
  require(progress_seconds > 0, fmt::format("explicit failure: progress_seconds is {}, must be "
                                            "positive",
                                            progress_seconds));
  if (material_point) {
    require(!material_point->softening,
            "softening cracks at the material point are opened by the events method only (its "
            "saw-tooth dissipates G exactly); the explicit method opens them brittle (leave out "
            "--softening, or use --method events)");
    require(!material_point->ply_angles.empty(),
            "explicit failure at the material point needs the fibre angle of every ply");
  }
}

namespace {

constexpr double kNever = std::numeric_limits<double>::infinity();

// The run: the integrator, the rate, the sites' judgement and the path.
class ExplicitFailureRun {
 public:
  ExplicitFailureRun(Model& model, const DofConstraints& unit, const DofFlags& reaction_dofs,
                     const ExplicitFailureSettings& settings)
      : model_(model),
        unit_(unit),
        reaction_dofs_(reaction_dofs),
        settings_(settings),
        integrator_(model, settings.integrator),
        shown_(model),
        before_(model.particles) {
    const int n = model.particles.size();
    require(unit.fixed.rows() == n && unit.value.rows() == n && reaction_dofs.rows() == n,
            fmt::format("explicit failure: the constraints are for {} particles, the model has {}",
                        unit.fixed.rows(), n));
    all_.resize(static_cast<std::size_t>(n));
    std::iota(all_.begin(), all_.end(), 0);
    prescribe();
    const long sample = settings.cycles_to_failure / 200;
    sample_cycles_ = std::max(1L, sample / settings.check_cycles) * settings.check_cycles;
  }

  EventsResult run() {
    const auto start = Stopwatch::Clock::now();
    RunControl control;
    control.check_interval = settings_.check_cycles;
    control.max_cycles = settings_.max_cycles;
    control.on_check = [&](const RunCheck& check) { return on_check(check); };
    if (settings_.on_progress) {
      control.progress_seconds = settings_.progress_seconds;
      control.on_progress = [&](const RunCheck&) {
        settings_.on_progress({static_cast<long>(result_.path.size()), broken_, load_factor_,
                               peak_reaction_, seconds_since(start)});
      };
    }
    const RunReport report = integrator_.run(control);
    if (result_.stop.empty())
      result_.stop =
          report.stop == RunStop::kCycleLimit ? "cycle limit" : std::string(to_string(report.stop));
    log_kernel_breaks(static_cast<double>(result_.path.size()));
    result_.dissipated_energy = integrator_.energy().released + result_.crack_energy;
    result_.wall_seconds = seconds_since(start);
    return std::move(result_);
  }

 private:
  // Every particle with a prescribed dof moves at rate x its unit value; the reference dof (the
  // largest travel) gives the load factor.
  void prescribe() {
    const ExplicitFailureSettings& s = settings_;
    rate_ = s.failure_load_factor /
            (static_cast<double>(s.cycles_to_failure) * integrator_.time_step());
    double largest = 0;
    for (int i = 0; i < unit_.fixed.rows(); ++i) {
      if (!unit_.fixed.row(i).any()) continue;
      PrescribedMotion m;
      m.particle = i;
      for (int c = 0; c < 3; ++c) {
        m.fix_velocity[static_cast<std::size_t>(c)] = unit_.fixed(i, c);
        m.velocity(c) = unit_.fixed(i, c) ? rate_ * unit_.value(i, c) : 0.0;
        m.fix_angular_velocity[static_cast<std::size_t>(c)] = unit_.fixed(i, 3 + c);
        m.angular_velocity(c) = unit_.fixed(i, 3 + c) ? rate_ * unit_.value(i, 3 + c) : 0.0;
      }
      motions_.push_back(m);
      m.velocity.setZero();
      m.angular_velocity.setZero();
      held_.push_back(m);
      for (int d = 0; d < kDofsPerParticle; ++d) {
        if (unit_.fixed(i, d) && std::abs(unit_.value(i, d)) > largest) {
          largest = std::abs(unit_.value(i, d));
          reference_ = {i, d};
        }
      }
    }
    require(largest > 0, "explicit failure: the unit load prescribes no motion");
    integrator_.set_prescribed_motions(motions_);
  }

  double dof(const Particles& p, int i, int d) const {
    return d < 3 ? p.displacement(i, d) : p.rotation(i, d - 3);
  }

  bool on_check(const RunCheck& check) {
    std::swap(before_, shown_.particles);
    before_reaction_ = reaction_;
    before_load_factor_ = load_factor_;
    Particles& p = shown_.particles;
    integrator_.gather(all_, p, StateAt::kForces);
    load_factor_ = dof(p, reference_.first, reference_.second) /
                   unit_.value(reference_.first, reference_.second);
    reaction_ = 0;
    for (int i = 0; i < p.size(); ++i)
      for (int d = 0; d < kDofsPerParticle; ++d)
        if (reaction_dofs_(i, d)) reaction_ -= d < 3 ? p.force(i, d) : p.torque(i, d - 3);
    const double reaction = reaction_;
    // The kernels' breaks since the last check belong to this point.
    const bool kernel_breaks = integrator_.breaks().size() > logged_breaks_;
    // The kernels break within a check interval, a whole uniform coupon at once: the last check's
    // state, before them, is the critical state (the peak of a brittle coupon).
    if (kernel_breaks && !recorded_last_) record_before();
    if (kernel_breaks) {
      log_kernel_breaks(static_cast<double>(result_.path.size() + 1));
      shown_.bonds = model_.bonds;
    }
    // Held after a break, the sites are judged once the coupon is at rest again.
    const bool at_rest = !held_now_ ||
                         check.report.unbalanced_force_ratio <= settings_.rest_ratio ||
                         integrator_.cycles() - held_since_ >= settings_.rest_cycles;
    OpeningSite opening;
    if (settings_.material_point && at_rest) opening = judge_sites();
    const bool event = opening.particle >= 0 || kernel_breaks;
    started_ = started_ || event;
    const bool sample = started_ && integrator_.cycles() % sample_cycles_ == 0;
    recorded_last_ = event || sample;
    if (recorded_last_) record(reaction, opening);
    if (opening.particle >= 0) open(opening);
    hold_or_move(event, at_rest);
    const bool past = result_.peak >= 0 && peak_reaction_ > 0 &&
                      static_cast<int>(result_.path.size()) - 1 > result_.peak;
    if (past && std::abs(reaction) < settings_.stop_fraction * peak_reaction_) {
      result_.stop = "failed";
    } else if (past &&
               std::abs(load_factor_) >
                   settings_.past_peak_travel *
                       std::abs(result_.path[static_cast<std::size_t>(result_.peak)].load_factor)) {
      result_.stop = "past the peak";
    }
    return result_.stop.empty();
  }

  // After something broke the grips stand still until the coupon is at rest again (the
  // unbalanced-force ratio at most settings.rest_ratio, or rest_cycles at most) and no site fails
  // there, so that each break meets the state the last one left, as in the events method, and not
  // the waves it sent out.
  void hold_or_move(bool event, bool at_rest) {
    if (event) {
      if (!held_now_) integrator_.set_prescribed_motions(held_);
      held_now_ = true;
      held_since_ = integrator_.cycles();
    } else if (held_now_ && at_rest) {
      integrator_.set_prescribed_motions(motions_);
      held_now_ = false;
    }
  }

  // A point at the last check's state (the bonds as they were then).
  void record_before() {
    std::swap(before_, shown_.particles);
    std::swap(before_load_factor_, load_factor_);
    record(before_reaction_, OpeningSite{});
    std::swap(before_load_factor_, load_factor_);
    std::swap(before_, shown_.particles);
  }

  // The site that opens at this check (particle -1: none): the first to fail, if it fails at a
  // load factor of at most 1.
  OpeningSite judge_sites() {
    const MaterialPointFailure& mp = *settings_.material_point;
    std::vector<SiteFailure> sites = site_failures(shown_.particles, model_.bonds, mp.ply_angles,
                                                   mp.criterion, mp.material, mp.strength_factors);
    for (int i = 0; i < shown_.particles.size(); ++i) {
      if (unit_.fixed(i, static_cast<int>(Dof::kUx)) || unit_.fixed(i, static_cast<int>(Dof::kUy)))
        sites[static_cast<std::size_t>(i)].failure.load_factor = kNever;
    }
    OpeningSite opening = next_opening_site(shown_.particles, model_.bonds, sites, kTieTolerance);
    if (opening.particle >= 0 && opening.site.failure.load_factor > 1) opening = OpeningSite{};
    return opening;
  }

  void record(double reaction, const OpeningSite& opening) {
    EventPoint point;
    point.event = static_cast<long>(result_.path.size()) + 1;
    point.load_factor = load_factor_;
    point.reaction = reaction;
    point.bond = opening.particle >= 0 ? opening.bonds.front() : -1;
    point.broken = broken_ + static_cast<int>(opening.bonds.size());
    if (opening.particle >= 0) {
      point.site = opening.particle;
      point.site_mode = opening.site.failure.mode;
      point.site_fracture_angle = opening.site.failure.fracture_angle;
    }
    result_.path.push_back(point);
    if (std::abs(reaction) > peak_reaction_) {
      peak_reaction_ = std::abs(reaction);
      result_.peak = static_cast<int>(result_.path.size()) - 1;
    }
    if (settings_.on_point) settings_.on_point(shown_, point);
  }

  // The site's bonds break together; their strain energy is what the crack dissipates.
  void open(const OpeningSite& opening) {
    const Particles& p = shown_.particles;
    const Bonds& bonds = model_.bonds;
    for (int b : opening.bonds) {
      const int i = bonds.first(b), j = bonds.second(b);
      const BondResponse r = parallel_bond_response(
          bond_parameters(bonds, b), p.displacement.row(i).matrix().transpose(),
          p.rotation.row(i).matrix().transpose(), p.displacement.row(j).matrix().transpose(),
          p.rotation.row(j).matrix().transpose());
      result_.crack_energy += r.energy;
    }
    const double area = crack_share(p, bonds, opening.particle, opening.normal);
    const PlyFailureMode mode = opening.site.failure.mode;
    const bool fibre =
        mode == PlyFailureMode::kFibreTension || mode == PlyFailureMode::kFibreCompression;
    const LaminaStrength& strength = settings_.material_point->material.strength;
    result_.crack_area += area;
    result_.crack_fracture_energy += (fibre ? strength.G_fibre : strength.G_matrix) * area;
    const BondState state = crack_bond_state(mode);
    for (int b : opening.bonds) {
      integrator_.break_bond(b, state);
      log_break(b, state, static_cast<double>(result_.path.size()));
    }
    shown_.bonds = model_.bonds;
  }

  // The kernels' breaks not logged yet, at point `at`.
  void log_kernel_breaks(double at) {
    const std::vector<BondBreak>& breaks = integrator_.breaks();
    for (; logged_breaks_ < breaks.size(); ++logged_breaks_)
      log_break(breaks[logged_breaks_].bond, breaks[logged_breaks_].mode, at);
  }

  // Bond b broke in `mode` at point `at` (its number), at its contact point.
  void log_break(int b, BondState mode, double at) {
    const Bonds& bonds = model_.bonds;
    BondBreak record;
    record.bond = b;
    record.mode = mode;
    record.at = at;
    record.load = load_factor_;
    const int i = bonds.first(b);
    record.position = model_.particles.reference_position.row(i).transpose().matrix() +
                      bonds.lever_first(b) * bonds.normal.row(b).transpose().matrix();
    result_.breaks.push_back(record);
    ++broken_;
  }

  Model& model_;
  const DofConstraints& unit_;
  const DofFlags& reaction_dofs_;
  const ExplicitFailureSettings& settings_;
  ExplicitIntegrator integrator_;
  Model shown_;       // the state at the checks (particles gathered from the kernel), for on_point
  Particles before_;  // the last check's
  double reaction_ = 0, before_reaction_ = 0, before_load_factor_ = 0;
  bool recorded_last_ = false;  // the last check is a point of the path
  std::vector<int> all_;
  std::vector<PrescribedMotion> motions_, held_;  // the grips moving, and standing still
  bool held_now_ = false;
  long held_since_ = 0;
  double rate_ = 0, load_factor_ = 0, peak_reaction_ = 0;
  std::pair<int, int> reference_{0, 0};
  long sample_cycles_ = 1;
  bool started_ = false;
  std::size_t logged_breaks_ = 0;
  int broken_ = 0;
  EventsResult result_;
};

}  // namespace

EventsResult run_explicit_failure(Model& model, const DofConstraints& unit,
                                  const DofFlags& reaction_dofs,
                                  const ExplicitFailureSettings& settings) {
  settings.validate();
  ExplicitFailureRun run(model, unit, reaction_dofs, settings);
  return run.run();
}

}  // namespace plydem
