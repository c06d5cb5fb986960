// plydem_static_bench: how long one linear static solve of a hex2d tension coupon takes, by phase,
// and how much memory it needs (issue 4 item 6). One coupon per process, so that the peak resident
// set (VmHWM) belongs to that size alone; bench/static_solve runs the sizes and prints the table.
//
// The coupon is E-glass/MY750 at 0 deg with particle diameter 0.05 mm, shaped like the paper's
// 10 x 0.83 mm coupon (length/width = 10/0.83) and scaled to hold about the requested number of
// particles. It is loaded as the tension test's static path loads it
// (experiments/protocols/tension.cpp, free grips): particles within two diameters of each end
// are grips with ux prescribed (+-half the travel of a 0.1 % nominal strain) and uz, theta_x,
// theta_y held; the remaining rigid-body modes are pinned (StaticSettings::pin_rigid_modes).
// Timings are on one thread: the phases of the first solve in wall-clock seconds (StaticTimings),
// the whole solve_static call in wall-clock and CPU seconds (CPU time counts the kernel's page
// faults but not the time other processes take), and its minor page faults. With --repeat N the
// solve runs N times on fresh copies of the model and the best wall-clock and CPU times of the
// repeats are reported too: the first solve of a process pays for fresh memory (a page fault per 4
// KiB, expensive in a virtual machine), later ones reuse it (glibc is told to keep freed memory,
// see main).
//
// Sample runs:
//   plydem_static_bench --particles 10000
//   plydem_static_bench --paper --json          # the paper's 10 x 0.83 mm coupon (3791 particles)
//   plydem_static_bench --particles 100000 --method direct
//   plydem_static_bench --paper --layup "[0/45/-45/90]s" --linear-solver cholmod
//   plydem_static_bench --length-mm 20 --width-mm 10 --diameter-mm 0.1 --linear-solver petsc
//       --layup "[0/45/-45/90]s"              # (one line) issue 15's 20 x 10 mm laminate
//   mpiexec -n 2 plydem_static_bench --paper --layup "[0/45/-45/90]s" --linear-solver petsc
//
// --linear-solver picks the direct method's factorization (solvers/linear_solver.hpp); --layup
// builds a laminate of hex2d plies (strategies/laminate.hpp, default interface) on the coupon
// instead of the 0 deg ply, as `plydem tension --layup` does.
#include <fmt/format.h>
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <malloc.h>
#include <sys/resource.h>

#include <algorithm>
#include <cmath>
#include <ctime>
#include <fstream>
#include <iostream>
#include <memory>
#include <string>

#include "core/error.hpp"
#include "core/machine_memory.hpp"
#include "core/material.hpp"
#include "core/stopwatch.hpp"
#include "core/units.hpp"
#include "solvers/linear_solver.hpp"
#include "solvers/machine_rates.hpp"
#include "solvers/static_solver.hpp"
#include "strategies/laminate.hpp"
#include "strategies/registry.hpp"

namespace {

constexpr double kDiameter = 0.05e-3;
constexpr double kPaperLength = 10e-3;
constexpr double kPaperWidth = 0.83e-3;
constexpr double kNominalStrain = 1e-3;

double cpu_seconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) +
         plydem::kSecondsPerNanosecond * static_cast<double>(t.tv_nsec);
}

long minor_page_faults() {
  rusage usage{};
  getrusage(RUSAGE_THREAD, &usage);
  return usage.ru_minflt;
}

// Peak resident set size of this process [MiB], 0 if unavailable.
double peak_rss_mib() {
  return plydem::peak_resident_bytes() / (1024.0 * 1024.0);
}

// The tension test's static constraints with free grips (experiments/protocols/tension.cpp).
plydem::DofConstraints tension_constraints(const plydem::Model& model, double diameter) {
  using plydem::Dof;
  const plydem::Particles& p = model.particles;
  const double x_min = p.reference_position.col(0).minCoeff();
  const double x_max = p.reference_position.col(0).maxCoeff();
  const double grip = 2.0 * diameter;
  const double travel = 0.5 * kNominalStrain * (x_max - x_min);
  plydem::DofConstraints constraints(p.size());
  for (int i = 0; i < p.size(); ++i) {
    const double x = p.reference_position(i, 0);
    const bool left = x <= x_min + grip, right = x >= x_max - grip;
    if (!left && !right) continue;
    constraints.fix(i, Dof::kUx, right ? travel : -travel);
    constraints.fix(i, Dof::kUz);
    constraints.fix(i, Dof::kThetaX);
    constraints.fix(i, Dof::kThetaY);
  }
  return constraints;
}

// What the command line asked for.
struct BenchOptions {
  double particles = 0;
  bool paper = false, json = false, markdown = false, header = false, rates = false;
  int repeat = 1;
  int solves = 1;
  std::string method = "auto";
  std::string linear_solver = "auto";
  std::string layup;
  double length_mm = 0, width_mm = 0, diameter_mm = 0;
};

void add_options(CLI::App& app, BenchOptions& o) {
  app.add_option("--particles", o.particles,
                 "about this many particles, in a coupon of the paper's aspect ratio");
  app.add_flag("--paper", o.paper, "the paper's 10 x 0.83 mm coupon");
  app.add_option("--length-mm", o.length_mm, "a coupon this long [mm] (with --width-mm)")
      ->check(CLI::PositiveNumber);
  app.add_option("--width-mm", o.width_mm, "a coupon this wide [mm] (with --length-mm)")
      ->check(CLI::PositiveNumber);
  app.add_option("--diameter-mm", o.diameter_mm, "particle diameter [mm] (default 0.05)")
      ->check(CLI::PositiveNumber);
  app.add_option("--method", o.method,
                 "auto (direct up to StaticSettings::direct_max_dofs free dofs), direct or cg")
      ->check(CLI::IsMember({"auto", "direct", "cg"}));
  app.add_option("--linear-solver", o.linear_solver,
                 "the direct method's factorization: auto (by size), direct, cholmod or petsc");
  app.add_option("--layup", o.layup, "a laminate of hex2d plies, e.g. \"[0/45/-45/90]s\"");
  app.add_option("--repeat", o.repeat, "solve this many times, report the best repeat too")
      ->check(CLI::Range(1, 1000));
  app.add_option("--solves", o.solves,
                 "solves with one factorization (the specimen stiffness makes 3): setup once, then "
                 "this many solves, all timed together (solve_s, iterations: their sums)")
      ->check(CLI::Range(1, 100));
  app.add_flag("--json", o.json, "one JSON object per line instead of text");
  app.add_flag("--markdown", o.markdown, "one row of a markdown table instead of text");
  app.add_flag("--markdown-header", o.header, "print the markdown table's header and exit");
  app.add_flag("--machine-rates", o.rates,
               "print this machine's rates that --linear-solver auto predicts from (measured now "
               "and cached, or read from the cache: solvers/machine_rates.hpp) as JSON, and exit");
}

void print_markdown_header() {
  std::cout << "| coupon [mm] | particles | bonds | free dofs | method | checks [s] | assembly [s] "
               "| factorization [s] | solve [s] | call [s] | call CPU [s] | page faults | best "
               "repeat: wall / CPU [s] | peak RSS [MiB] |\n"
               "|---|--:|--:|--:|---|--:|--:|--:|--:|--:|--:|--:|--:|--:|\n";
}

// The coupon asked for: the paper's, one of a given size, or the smallest of the paper's shape
// holding about `particles`.
plydem::CouponSpec coupon_of(const BenchOptions& o) {
  const bool sized = o.length_mm > 0 || o.width_mm > 0;
  plydem::require(static_cast<int>(o.paper) + (o.particles > 0) + sized == 1,
                  "give one of --particles N (N > 0), --paper, or --length-mm with --width-mm");
  plydem::require(!sized || (o.length_mm > 0 && o.width_mm > 0),
                  "--length-mm and --width-mm go together");
  plydem::CouponSpec spec;
  spec.material = plydem::load_material("eglass-my750");
  spec.ply_angle = 0;
  spec.particle_diameter = o.diameter_mm > 0 ? o.diameter_mm * plydem::kMetresPerMm : kDiameter;
  spec.length = sized ? o.length_mm * plydem::kMetresPerMm : kPaperLength;
  spec.width = sized ? o.width_mm * plydem::kMetresPerMm : kPaperWidth;
  if (o.particles > 0) {
    // Sites of the hexagonal layer (at 0 deg, first site at (R, R)) with centres at least one
    // radius inside an L x W rectangle: rows sqrt(3)/2 d apart, every other row shifted by d/2.
    // Bisection on L for the smallest coupon of the paper's shape holding `particles`.
    const double aspect = kPaperLength / kPaperWidth, d = spec.particle_diameter;
    auto sites = [&](double length) {
      const double width = length / aspect;
      const double rows = std::floor((width - d) / (std::sqrt(3.0) / 2 * d) + 1e-9) + 1;
      const double even = std::floor((length - d) / d + 1e-9) + 1;
      const double odd = std::floor((length - 1.5 * d) / d + 1e-9) + 1;
      return std::ceil(rows / 2) * even + std::floor(rows / 2) * odd;
    };
    double lo = 2 * d * aspect, hi = 1.0;
    for (int k = 0; k < 100; ++k)
      (sites(0.5 * (lo + hi)) < o.particles ? lo : hi) = 0.5 * (lo + hi);
    spec.length = hi;
    spec.width = hi / aspect;
  }
  return spec;
}

// The first solve's result and costs, and the best of the repeats.
struct Measurement {
  plydem::StaticResult result;
  double build_seconds = 0;
  double first_wall = 0, first_cpu = 0, best_wall = 1e300, best_cpu = 1e300;
  long first_faults = 0;
  double rss = 0;
};

// Solves `repeat` times on fresh copies of `built`.
void time_solves(const plydem::Model& built, const plydem::CouponSpec& spec, const BenchOptions& o,
                 Measurement& m) {
  const plydem::DofConstraints constraints = tension_constraints(built, spec.particle_diameter);
  plydem::StaticSettings settings;
  settings.pin_rigid_modes = true;
  if (o.method == "direct") settings.method = plydem::StaticMethod::kDirect;
  if (o.method == "cg") settings.method = plydem::StaticMethod::kIterative;
  settings.linear_solver = plydem::parse_linear_solver(o.linear_solver);

  settings.expected_solves = o.solves;
  for (int k = 0; k < o.repeat; ++k) {
    plydem::Model model = built;
    const long faults = minor_page_faults();
    const double cpu = cpu_seconds();
    const plydem::Stopwatch clock;
    const plydem::StaticSystem system(model, constraints, settings);
    plydem::StaticResult solved = system.solve(model, constraints.value);
    for (int more = 1; more < o.solves; ++more) {
      const plydem::StaticResult again = system.solve(model, (more + 1.0) * constraints.value);
      solved.seconds.assembly += again.seconds.assembly;
      solved.seconds.solve += again.seconds.solve;
      solved.iterations += again.iterations;
    }
    const double wall = clock.seconds();
    const double used = cpu_seconds() - cpu;
    if (k == 0) {
      m.result = std::move(solved);
      m.first_wall = wall;
      m.first_cpu = used;
      m.first_faults = minor_page_faults() - faults;
    } else {
      m.best_wall = std::min(m.best_wall, wall);
      m.best_cpu = std::min(m.best_cpu, used);
    }
  }
  m.rss = peak_rss_mib();
}

void print_json(const plydem::CouponSpec& spec, const plydem::Model& built, int repeat, int solves,
                const Measurement& m) {
  const plydem::StaticResult& r = m.result;
  const plydem::StaticTimings& t = r.seconds;
  nlohmann::json j;
  j["coupon_mm"] = {spec.length * plydem::kMmPerMetre, spec.width * plydem::kMmPerMetre};
  j["particles"] = built.particles.size();
  j["bonds"] = built.bonds.size();
  j["free_dofs"] = r.free_dofs;
  j["ranks"] = plydem::mpi_size();
  j["nonzeros"] = r.stiffness_nonzeros;
  j["method"] = r.method == plydem::StaticMethod::kDirect ? "direct" : "CG";
  j["solver"] = r.method_name;
  j["linear_solver_choice"] = r.linear_solver_choice;
  j["factor_entries"] = r.factor_entries;
  j["factor_flops"] = r.factor_flops;
  j["solves"] = solves;
  j["iterations"] = r.iterations;
  j["relative_residual"] = r.relative_residual;
  j["build_s"] = m.build_seconds;
  j["checks_s"] = t.checks;
  j["assembly_s"] = t.assembly;
  j["factorization_s"] = t.factorization;
  j["solve_s"] = t.solve;
  j["phases_total_s"] = t.total();
  j["call_s"] = m.first_wall;
  j["call_cpu_s"] = m.first_cpu;
  j["page_faults"] = m.first_faults;
  if (repeat > 1) {
    j["repeat"] = repeat;
    j["best_repeat_s"] = m.best_wall;
    j["best_repeat_cpu_s"] = m.best_cpu;
  }
  j["peak_rss_mib"] = m.rss;
  std::cout << j.dump() << '\n';
}

void print_markdown_row(const plydem::CouponSpec& spec, const plydem::Model& built, int repeat,
                        const Measurement& m) {
  const plydem::StaticResult& r = m.result;
  const plydem::StaticTimings& t = r.seconds;
  const std::string method_cell =
      r.method != plydem::StaticMethod::kDirect ? fmt::format("CG ({} iterations)", r.iterations)
      : r.iterations > 0 ? fmt::format("{} ({} iterations)", r.method_name, r.iterations)
                         : r.method_name;
  const std::string best =
      repeat > 1 ? fmt::format("{:.4f} / {:.4f} ({} runs)", m.best_wall, m.best_cpu, repeat - 1)
                 : std::string("-");
  std::cout << fmt::format(
      "| {:.3g} x {:.3g} | {} | {} | {} | {} | {:.4f} | {:.4f} | {:.4f} | {:.4f} | {:.4f} | "
      "{:.4f} | {} | {} | {:.0f} |\n",
      spec.length * plydem::kMmPerMetre, spec.width * plydem::kMmPerMetre, built.particles.size(),
      built.bonds.size(), r.free_dofs, method_cell, t.checks, t.assembly, t.factorization, t.solve,
      m.first_wall, m.first_cpu, m.first_faults, best, m.rss);
}

void print_text(const plydem::CouponSpec& spec, const plydem::Model& built, int repeat,
                const Measurement& m) {
  const plydem::StaticResult& r = m.result;
  const plydem::StaticTimings& t = r.seconds;
  std::cout << fmt::format(
      "{:.3g} x {:.3g} mm: {} particles, {} bonds, {} free dofs, {} ({} iterations), "
      "residual {:.2g}; build {:.3f} s\n  first solve: checks {:.4f} s, assembly {:.4f} s, "
      "factorization {:.4f} s, solve {:.4f} s; call {:.4f} s wall, {:.4f} s CPU, {} page "
      "faults\n",
      spec.length * plydem::kMmPerMetre, spec.width * plydem::kMmPerMetre, built.particles.size(),
      built.bonds.size(), r.free_dofs, r.method_name, r.iterations, r.relative_residual,
      m.build_seconds, t.checks, t.assembly, t.factorization, t.solve, m.first_wall, m.first_cpu,
      m.first_faults);
  if (repeat > 1)
    std::cout << fmt::format("  best of {} more solves: {:.4f} s wall, {:.4f} s CPU\n", repeat - 1,
                             m.best_wall, m.best_cpu);
  std::cout << fmt::format("  peak RSS {:.0f} MiB\n", m.rss);
}

}  // namespace

int main(int argc, char** argv) {
  const plydem::ParallelSession session(&argc, &argv);  // PETSc and MPI under mpiexec
  CLI::App app{"plydem_static_bench: time one static solve of a hex2d tension coupon"};
  BenchOptions o;
  add_options(app, o);
  CLI11_PARSE(app, argc, argv);
  if (o.header) {
    print_markdown_header();
    return 0;
  }
  if (o.rates) {
    const plydem::MachineRates& r = plydem::machine_rates();
    if (plydem::is_root())
      std::cout << nlohmann::json{{"eigen_gflops", r.eigen_gflops},
                                  {"blas_gflops", r.blas_gflops},
                                  {"memory_gbytes", r.memory_gbytes},
                                  {"blas", r.blas},
                                  {"key", r.key},
                                  {"source", r.source}}
                       .dump()
                << '\n';
    return 0;
  }
  try {
    const plydem::CouponSpec spec = coupon_of(o);

    // Freed memory stays with the process (no trimming, no per-allocation mmap), so that repeated
    // solves measure the arithmetic rather than the kernel's first touch of fresh pages.
    mallopt(M_MMAP_THRESHOLD, 32 << 20);
    mallopt(M_TRIM_THRESHOLD, 1 << 30);

    Measurement m;
    const plydem::Stopwatch clock;
    const std::unique_ptr<plydem::Strategy> hex2d = plydem::default_registry().create("hex2d");
    const plydem::Model built =
        o.layup.empty()
            ? hex2d->build(spec).model
            : plydem::build_laminate(*hex2d, {spec, plydem::parse_layup(o.layup), {}}).model;
    m.build_seconds = clock.seconds();
    time_solves(built, spec, o, m);

    if (!plydem::is_root()) return 0;  // under mpiexec, rank 0 reports (its own time and memory)
    if (o.json) {
      print_json(spec, built, o.repeat, o.solves, m);
    } else if (o.markdown) {
      print_markdown_row(spec, built, o.repeat, m);
    } else {
      print_text(spec, built, o.repeat, m);
    }
  } catch (const std::exception& e) {
    std::cerr << "plydem_static_bench: " << e.what() << '\n';
    return 1;
  }
  return 0;
}
