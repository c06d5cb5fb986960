// plydem_events_bench: events per second of the quasi-static events solver
// (solvers/bond_events.hpp) on the paper's coupon, with the Woodbury updates of one factorization
// against the baseline that factors the stiffness afresh for every event (issue 16 item 7).
//
// The coupon is the paper's: hex2d, E-glass/MY750 at 0 deg, 10 x 0.83 mm, particle diameter
// 0.05 mm (3,791 particles). Its bonds get uniform strengths by hand (the strength calibration is
// not used here): section radius d/4, tensile strength 60 MPa, cohesion 80 MPa, friction 0.2,
// ductility as given (1 = brittle); bonds touching a grip never break. The grips are the tension
// test's free grips (two diameters at each end, ux prescribed, uz, theta_x, theta_y held, the
// rigid modes pinned). Both runs stop after the first N events; their paths are compared event
// by event (bond, load factor, reaction).
//
// Sample runs:
//   plydem_events_bench                       # 300 brittle events
//   plydem_events_bench --events 1000 --ductility 3 --max-update-rank 300
//   plydem_events_bench --markdown
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <ctime>
#include <iostream>
#include <memory>
#include <string>

#include "core/material.hpp"
#include "core/units.hpp"
#include "solvers/bond_events.hpp"
#include "strategies/registry.hpp"

namespace {

constexpr double kDiameter = 0.05e-3;

struct Run {
  plydem::EventsResult result;
  double cpu_seconds = 0;
  double events_per_second = 0;  // per CPU second: the machine may be shared
};

double cpu_seconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) +
         plydem::kSecondsPerNanosecond * static_cast<double>(t.tv_nsec);
}

Run run(const plydem::Model& built, const plydem::DofConstraints& unit,
        const plydem::DofFlags& reaction, plydem::EventSettings settings) {
  plydem::Model model = built;
  Run r;
  const double start = cpu_seconds();
  r.result = plydem::run_events(model, unit, reaction, settings);
  r.cpu_seconds = cpu_seconds() - start;
  r.events_per_second = static_cast<double>(r.result.path.size()) / r.cpu_seconds;
  return r;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"plydem_events_bench: events per second, Woodbury updates vs refactoring"};
  long events = 300;
  int max_rank = plydem::EventSettings{}.max_update_rank;
  double ductility = 1, tooth_ratio = plydem::EventSettings{}.tooth_stiffness_ratio;
  bool markdown = false, only_updates = false;
  app.add_option("--events", events, "the first N events of each run")
      ->check(CLI::Range(1L, 10000000L));
  app.add_option("--max-update-rank", max_rank, "EventSettings::max_update_rank")
      ->check(CLI::Range(0, 100000));
  app.add_option("--ductility", ductility, "kappa_u of every breakable bond (1 = brittle)")
      ->check(CLI::Range(1.0, 1e6));
  app.add_option("--tooth-ratio", tooth_ratio, "EventSettings::tooth_stiffness_ratio");
  app.add_flag("--markdown", markdown, "the table in markdown");
  app.add_flag("--updates-only", only_updates, "run the Woodbury path alone (for profiling)");
  CLI11_PARSE(app, argc, argv);
  try {
    plydem::CouponSpec spec;
    spec.material = plydem::load_material("eglass-my750");
    spec.ply_angle = 0;
    spec.length = 10e-3;
    spec.width = 0.83e-3;
    spec.particle_diameter = kDiameter;
    plydem::Model built = plydem::default_registry().create("hex2d")->build(spec).model;

    const plydem::Particles& p = built.particles;
    const double x_min = p.reference_position.col(0).minCoeff();
    const double x_max = p.reference_position.col(0).maxCoeff();
    auto in_grip = [&](int i) {
      const double x = p.reference_position(i, 0);
      return x <= x_min + 2 * kDiameter || x >= x_max - 2 * kDiameter;
    };
    plydem::DofConstraints unit(p.size());
    plydem::DofFlags reaction =
        plydem::DofFlags::Constant(p.size(), plydem::kDofsPerParticle, false);
    const double travel = 0.5e-3 * (x_max - x_min);  // 0.1 % nominal strain at load factor 1
    for (int i = 0; i < p.size(); ++i) {
      if (!in_grip(i)) continue;
      const bool right = p.reference_position(i, 0) > 0.5 * (x_min + x_max);
      unit.fix(i, plydem::Dof::kUx, right ? travel : -travel);
      unit.fix(i, plydem::Dof::kUz);
      unit.fix(i, plydem::Dof::kThetaX);
      unit.fix(i, plydem::Dof::kThetaY);
      if (right) reaction(i, static_cast<int>(plydem::Dof::kUx)) = true;
    }
    plydem::Bonds& b = built.bonds;
    for (int k = 0; k < b.size(); ++k) {
      if (in_grip(b.first(k)) || in_grip(b.second(k))) continue;
      b.strength_radius(k) = 0.25 * kDiameter;
      b.tensile_strength(k) = 60e6;
      b.cohesion(k) = 80e6;
      b.friction_coefficient(k) = 0.2;
      b.ductility(k) = ductility;
    }

    plydem::EventSettings settings;
    settings.max_events = events;
    settings.max_update_rank = max_rank;
    settings.tooth_stiffness_ratio = tooth_ratio;
    settings.last_tooth_stiffness = std::min(settings.last_tooth_stiffness, tooth_ratio);
    settings.static_settings.pin_rigid_modes = true;
    const Run woodbury = run(built, unit, reaction, settings);
    if (only_updates) {
      std::cout << fmt::format(
          "Woodbury updates: {} events, {} factorizations, {:.3f} s wall, {:.3f} s CPU, {:.1f} "
          "events per CPU second\n",
          woodbury.result.path.size(), woodbury.result.factorizations, woodbury.result.wall_seconds,
          woodbury.cpu_seconds, woodbury.events_per_second);
      return 0;
    }
    settings.refactor_every_event = true;
    const Run refactor = run(built, unit, reaction, settings);

    const std::size_t common = std::min(woodbury.result.path.size(), refactor.result.path.size());
    std::size_t same = 0;
    double worst = 0;
    for (std::size_t k = 0; k < common; ++k) {
      const plydem::EventPoint &a = woodbury.result.path[k], &c = refactor.result.path[k];
      if (a.bond != c.bond) break;
      ++same;
      worst = std::max({worst, std::abs(a.load_factor - c.load_factor) / c.load_factor,
                        std::abs(a.reaction - c.reaction) / std::abs(c.reaction)});
    }

    std::cout << fmt::format(
        "paper coupon: {} particles, {} bonds; ductility {}, tooth ratio {}, max update rank {}\n",
        p.size(), b.size(), ductility, tooth_ratio, max_rank);
    const char* row =
        markdown ? "| {} | {} | {} | {} | {} | {:.3f} | {:.3f} | {:.1f} | {:.2f} |\n"
                 : "{:<22} {:>7} {:>7} {:>15} {:>12} {:>9.3f} {:>9.3f} {:>10.1f} {:>8.2f}\n";
    if (markdown)
      std::cout << "| method | events | broken | factorizations | stop | wall [s] | CPU [s] | "
                   "events per CPU s | speed-up |\n|---|--:|--:|--:|---|--:|--:|--:|--:|\n";
    else
      std::cout << fmt::format("{:<22} {:>7} {:>7} {:>15} {:>12} {:>9} {:>9} {:>10} {:>8}\n",
                               "method", "events", "broken", "factorizations", "stop", "wall [s]",
                               "CPU [s]", "events/s", "speed-up");
    for (const auto& [name, r] :
         {std::pair{"Woodbury updates", &woodbury}, std::pair{"refactor every event", &refactor}})
      std::cout << fmt::format(fmt::runtime(row), name, r->result.path.size(),
                               r->result.breaks.size(), r->result.factorizations, r->result.stop,
                               r->result.wall_seconds, r->cpu_seconds, r->events_per_second,
                               r->events_per_second / refactor.events_per_second);
    std::cout << fmt::format(
        "same failing bond for the first {} of {} events; load factors and reactions agree to "
        "{:.2g} (relative)\n",
        same, common, worst);
  } catch (const std::exception& e) {
    std::cerr << "plydem_events_bench: " << e.what() << '\n';
    return 1;
  }
  return 0;
}
