// plydem_kernel_bench: the explicit kernel's speed on a hexagonal layer of bonded particles, the
// program behind bench/run (which adds LAMMPS and YADE on the same lattice and prints one table).
//
// Sample runs:
//   plydem_kernel_bench layer --particles 100000 --steps 500 --threads 2   # one JSON line
//   plydem_kernel_bench layer --particles 10000 --lammps-data layer.data --yade-layer layer.txt
//   plydem_kernel_bench coupon --cycles 200000     # the paper's Table 2 Hex2D coupon, timed
//   plydem_kernel_bench layer --particles 10000000 --steps 200 --backend cuda   # on a GPU
//   plydem_kernel_bench tension --cycles 200000    # the same coupon through the tension test
//   plydem_kernel_bench table < rows.jsonl         # the table bench/run prints
//   mpiexec -n 2 plydem_kernel_bench layer --particles 200000 --steps 300 --backend reference
//                                     # split between 2 MPI ranks (bench/ranks prints the table)
//
// The layer is the Hex2D model of the paper's 0 deg E-glass/MY750 ply (0.05 mm particles, full
// parallel bonds: normal, shear, bending and twisting, particles spinning), square, pulled by grips
// at both ends that move apart while PFC local damping (0.7) acts, as in the tension test. Only
// the cycles are timed; building the model and the kernel's gather lists is not. The cycles run
// through ExplicitIntegrator::run(), the run loop users run (`--api advance`: the bare advance(N)),
// with a check every --report-every cycles in coupon mode. `tension` times the tension test's own
// explicit fixed-cycle pull of the coupon (`plydem tension --solver explicit --cycles N`, one
// loading along x; building the coupon included), the figure to hold beside `coupon`.
//
// Under mpiexec the layer is split between the ranks (solvers/rank_exchange.hpp); rank 0 prints the
// row, with the largest share, ghost count, exchanged bytes per cycle and peak memory of any rank.
#include <fmt/format.h>
#include <omp.h>
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <ctime>
#include <fstream>
#include <iostream>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "contacts/bond_kernel.hpp"
#include "contacts/particle_ordering.hpp"
#include "core/error.hpp"
#include "core/machine_memory.hpp"
#include "core/material.hpp"
#include "core/stopwatch.hpp"
#include "core/units.hpp"
#include "experiments/protocols/tension.hpp"
#include "solvers/device_backend.hpp"
#include "solvers/explicit_integrator.hpp"
#include "solvers/linear_solver.hpp"
#include "solvers/rank_exchange.hpp"
#include "strategies/hex2d.hpp"

namespace {

using namespace plydem;

// The Hex2D strategy with its free edges treated by edge equilibrium (1, the default: each edge
// bond its own weight, so the kernel holds thousands of half-bond types) or by the count
// completion (0: a few types, the model plydem built before edge equilibrium; the kernel's speed
// compared across versions needs the same model on both sides).
Hex2dStrategy hex2d_with_edges(int edge_equilibrium) {
  Hex2dStrategy strategy;
  strategy.set_option("edge_equilibrium", edge_equilibrium);
  return strategy;
}

// A square Hex2D layer of about `particles` particles (the edges lose a few).
Model square_layer(long particles, int edge_equilibrium) {
  CouponSpec spec;
  spec.material = load_material("eglass-my750");
  const double d = spec.particle_diameter;
  const double side = std::sqrt(static_cast<double>(particles) * std::sqrt(3.0) / 2.0) * d;
  spec.length = side;
  spec.width = side;
  return hex2d_with_edges(edge_equilibrium).build(spec).model;
}

// The paper's Table 2 coupon: 0 deg E-glass/MY750, 10 x 0.83 mm, 200 x 19 particles.
Model table2_coupon(int edge_equilibrium) {
  CouponSpec spec;
  spec.material = load_material("eglass-my750");
  return hex2d_with_edges(edge_equilibrium).build(spec).model;
}

// Grips within two diameters of either end move apart along x (free laterally), reaching a
// nominal strain of 1e-3 after `cycles` cycles: the tension test's loading.
void pull_with_grips(Model& model, ExplicitIntegrator& integrator, long cycles) {
  Particles& p = model.particles;
  const double x_min = p.reference_position.col(0).minCoeff();
  const double x_max = p.reference_position.col(0).maxCoeff();
  const double grip = 4.0 * p.radius.maxCoeff();
  for (int i = 0; i < p.size(); ++i) {
    const double x = p.reference_position(i, 0);
    p.group(i) = static_cast<int>(x <= x_min + grip   ? BoundaryGroup::kLeftGrip
                                  : x >= x_max - grip ? BoundaryGroup::kRightGrip
                                                      : BoundaryGroup::kFree);
  }
  const double velocity =
      0.5e-3 * (x_max - x_min) / (static_cast<double>(cycles) * integrator.time_step());
  PrescribedMotion motion[2];
  motion[0].group = BoundaryGroup::kLeftGrip;
  motion[1].group = BoundaryGroup::kRightGrip;
  motion[0].velocity = Eigen::Vector3d(-velocity, 0, 0);
  motion[1].velocity = Eigen::Vector3d(velocity, 0, 0);
  for (PrescribedMotion& m : motion) {
    m.fix_velocity = {true, false, true};
    m.fix_angular_velocity = {true, true, false};
  }
  integrator.set_prescribed_motions({motion[0], motion[1]});
}

// CPU time of the whole process, all threads [s]: with the wall time it shows whether the run had
// its cores to itself.
double process_cpu_seconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + kSecondsPerNanosecond * static_cast<double>(t.tv_nsec);
}

// `cycles` cycles with a check every `check_every`, through run() or (api "advance") through
// advance(check_every) calls; the timers of run() go into `r` (when given).
CycleReport timed_cycles(ExplicitIntegrator& integrator, const std::string& api, long cycles,
                         long check_every, nlohmann::json* r) {
  if (api == "advance") {
    CycleReport report;
    for (long done = 0; done < cycles;) {
      const long chunk = std::min(check_every, cycles - done);
      report = integrator.advance(chunk);
      done += chunk;
    }
    return report;
  }
  RunControl control;
  control.check_interval = check_every;
  control.max_cycles = cycles;
  const RunReport run = integrator.run(control);
  if (r) {
    (*r)["kernel_seconds"] = run.kernel_seconds;
    (*r)["check_seconds"] = run.check_seconds;
    (*r)["transfer_seconds"] = run.transfer_seconds;
    (*r)["checks"] = run.checks;
  }
  return run.last;
}

nlohmann::json row(const std::string& engine, long particles, long bonds, int threads, long steps,
                   double seconds, double cpu_seconds, double bytes_per_particle) {
  nlohmann::json r;
  r["engine"] = engine;
  r["particles"] = particles;
  r["bonds"] = bonds;
  r["threads"] = threads;
  r["steps"] = steps;
  r["seconds"] = seconds;
  r["cpu_seconds"] = cpu_seconds;
  r["ns_per_step"] = kNanosecondsPerSecond * seconds / static_cast<double>(steps);
  r["particle_steps_per_s"] = static_cast<double>(particles) * static_cast<double>(steps) / seconds;
  r["bond_steps_per_s"] = static_cast<double>(bonds) * static_cast<double>(steps) / seconds;
  r["bytes_per_particle"] = bytes_per_particle;
  return r;
}

void write_lammps_data(const Model& model, const std::string& path) {
  const Particles& p = model.particles;
  std::ofstream out(path);
  require(static_cast<bool>(out), fmt::format("cannot write {}", path));
  const double margin = 4.0 * p.radius.maxCoeff();
  out << fmt::format("plydem hexagonal layer: {} particles, {} bonds (SI units)\n\n", p.size(),
                     model.bonds.size());
  out << fmt::format("{} atoms\n{} bonds\n1 atom types\n1 bond types\n\n", p.size(),
                     model.bonds.size());
  for (int c = 0; c < 3; ++c) {
    const char* axis = c == 0 ? "x" : (c == 1 ? "y" : "z");
    out << fmt::format("{:.17g} {:.17g} {}lo {}hi\n",
                       p.reference_position.col(c).minCoeff() - margin,
                       p.reference_position.col(c).maxCoeff() + margin, axis, axis);
  }
  out << fmt::format("\nMasses\n\n1 {:.17g}\n\nAtoms # bond\n\n", p.mass(0));
  for (int i = 0; i < p.size(); ++i) {
    out << fmt::format("{} 1 1 {:.17g} {:.17g} {:.17g}\n", i + 1, p.reference_position(i, 0),
                       p.reference_position(i, 1), p.reference_position(i, 2));
  }
  out << "\nBonds\n\n";
  for (int b = 0; b < model.bonds.size(); ++b) {
    out << fmt::format("{} 1 {} {}\n", b + 1, model.bonds.first(b) + 1, model.bonds.second(b) + 1);
  }
}

void write_yade_layer(const Model& model, const std::string& path) {
  const Particles& p = model.particles;
  std::ofstream out(path);
  require(static_cast<bool>(out), fmt::format("cannot write {}", path));
  out << fmt::format("# x y z radius [m]; {} particles, {} bonds between touching neighbours\n",
                     p.size(), model.bonds.size());
  for (int i = 0; i < p.size(); ++i) {
    out << fmt::format("{:.17g} {:.17g} {:.17g} {:.17g}\n", p.reference_position(i, 0),
                       p.reference_position(i, 1), p.reference_position(i, 2), p.radius(i));
  }
}

ParticleOrder order_named(const std::string& name) {
  if (name == "hilbert") return ParticleOrder::kHilbert;
  if (name == "built") return ParticleOrder::kAsBuilt;
  return ParticleOrder::kAutomatic;
}

// Strengths far above anything the pull reaches (no bond breaks): the breaking kernel decides every
// bond at every cycle, the elastic one's work plus the failure law's.
void unreachable_strengths(Model& model) {
  for (int b = 0; b < model.bonds.size(); ++b) {
    model.bonds.strength_radius(b) = model.particles.radius(model.bonds.first(b));
    model.bonds.tensile_strength(b) = 1e15;
    model.bonds.cohesion(b) = 1e15;
  }
}

// The MPI ranks' figures of a run (the largest of any rank; on one rank its own): the particles
// it advances and its ghosts, the bytes it receives per cycle, its peak memory, the wall time.
nlohmann::json rank_figures(const ExplicitIntegrator& integrator, double seconds) {
  const int size = mpi_size();
  nlohmann::json r;
  r["ranks"] = size;
  r["seconds"] = max_over_ranks(seconds);
  r["peak_rss_mib"] = max_over_ranks(peak_resident_bytes() / (1024.0 * 1024.0));
  if (const RankPartition* split = integrator.rank_partition()) {
    const RankPartition& part = *split;
    r["own_per_rank"] = max_over_ranks(static_cast<double>(part.own.size()));
    r["ghosts_per_rank"] = max_over_ranks(static_cast<double>(part.ghosts.size()));
    r["bonds_per_rank"] = max_over_ranks(static_cast<double>(part.bonds.size()));
    r["exchanged_bytes_per_cycle"] =
        max_over_ranks(static_cast<double>(part.received_bytes_per_cycle()));
  }
  return r;
}

// The explicit settings of the benchmark runs: the kernel on `backend`; a breakable model without
// contacts (none would touch: no bond breaks), which the device backends do not have.
ExplicitSettings bench_settings(const std::string& order, const std::string& backend) {
  ExplicitSettings settings;
  settings.particle_order = order_named(order);
  settings.backend = parse_backend(backend);
  settings.contacts = false;
  return settings;
}

// The kernel's bond table in the bench's order (GatherBonds, as the CPU backend builds it): its
// half-bond types and the share of a block's occupied slots whose eight particles hold different
// types (those load the types lane by lane; a slot whose particles share one loads it as vectors).
// Built and freed before the integrator builds its own, so the two are never held at once.
nlohmann::json describe_bond_table(const Model& model, const std::string& order,
                                   int edge_equilibrium) {
  const GatherBonds g(model.bonds, kernel_order(model, order_named(order)));
  long occupied = 0, mixed = 0;
  for (int block = 0; block < g.padded_count() / lanes::kCount; ++block) {
    for (int slot = 0; slot < g.width(); ++slot) {
      const std::int32_t type = g.block_types(block)[slot];
      occupied += type != 0;
      mixed += type < 0;
    }
  }
  nlohmann::json r;
  r["edge_equilibrium"] = edge_equilibrium;
  r["half_bond_types"] = g.type_count() - 1;  // type 0 is the empty slot's
  r["mixed_slot_share"] = occupied > 0 ? static_cast<double>(mixed) / occupied : 0.0;
  return r;
}

// The largest number of bonds of one particle: the gather table's width on a lattice.
int max_degree(const Model& model) {
  std::vector<int> degree(static_cast<std::size_t>(model.particles.size()), 0);
  int widest = 0;
  for (int b = 0; b < model.bonds.size(); ++b)
    for (int end : {model.bonds.first(b), model.bonds.second(b)})
      widest = std::max(widest, ++degree[static_cast<std::size_t>(end)]);
  return widest;
}

// What a device must stream per particle and cycle (solvers/device_backend.hpp), for the achieved
// bandwidth bench/gpu_check reports.
double streamed_bytes(const Model& model, bool breaking) {
  return streamed_bytes_per_particle(max_degree(model), breaking ? kBrittleTypes : kElasticMode);
}

int run_layer(long particles, long steps, int threads, const std::string& order,
              const std::string& api, const std::string& lammps_data, const std::string& yade_layer,
              bool describe, const std::string& backend, bool breakable, int edge_equilibrium) {
  Model model = square_layer(particles, edge_equilibrium);
  if (breakable) unreachable_strengths(model);
  const long n = model.particles.size(), bonds = model.bonds.size();
  if (!lammps_data.empty()) write_lammps_data(model, lammps_data);
  if (!yade_layer.empty()) write_yade_layer(model, yade_layer);
  if (describe) {
    const Bonds& b = model.bonds;
    nlohmann::json d;
    d["particles"] = n;
    d["bonds"] = bonds;
    d["spacing"] = 2.0 * model.particles.radius(0);
    d["mass"] = model.particles.mass(0);
    d["normal_stiffness"] = b.normal_stiffness.maxCoeff();
    d["time_step"] = critical_time_step(model);
    std::cout << d.dump() << "\n";
    return 0;
  }
  require(steps >= 1, "--steps must be at least 1");
  const nlohmann::json table = describe_bond_table(model, order, edge_equilibrium);
  omp_set_num_threads(threads);
  const ExplicitSettings settings = bench_settings(order, backend);
  ExplicitIntegrator integrator(model, settings);
  pull_with_grips(model, integrator, 200'000);
  integrator.advance(1);  // first touch of the kernel's arrays, not timed
  const double cpu = process_cpu_seconds();
  const Stopwatch clock;
  nlohmann::json timers;
  const CycleReport report = timed_cycles(integrator, api, steps, steps, &timers);
  const double seconds = clock.seconds();
  require(std::isfinite(report.strain_energy), "the benchmark run diverged");
  nlohmann::json r = row("plydem", n, bonds, threads, steps, seconds, process_cpu_seconds() - cpu,
                         static_cast<double>(integrator.kernel_bytes()) / static_cast<double>(n));
  r["order"] = order;
  r["api"] = api;
  r["backend"] = backend;
  r["breakable"] = breakable;
  r["streamed_bytes_per_particle_step"] = streamed_bytes(model, integrator.breaking());
  r.update(table);
  if (timers.is_object()) r.update(timers);
  r.update(rank_figures(integrator, seconds));
  std::cout << r.dump() << "\n";
  return 0;
}

int run_coupon(long cycles, int threads, const std::string& order, const std::string& api,
               long report_every, bool breakable, const std::string& backend,
               int edge_equilibrium) {
  require(cycles >= 1 && report_every >= 1, "--cycles and --report-every must be at least 1");
  Model model = table2_coupon(edge_equilibrium);
  if (breakable) unreachable_strengths(model);
  const nlohmann::json table = describe_bond_table(model, order, edge_equilibrium);
  omp_set_num_threads(threads);
  const ExplicitSettings settings = bench_settings(order, backend);
  ExplicitIntegrator integrator(model, settings);
  pull_with_grips(model, integrator, cycles);
  const double cpu = process_cpu_seconds();
  const Stopwatch clock;
  nlohmann::json timers;
  const CycleReport report = timed_cycles(integrator, api, cycles, report_every, &timers);
  const double seconds = clock.seconds();
  require(std::isfinite(report.strain_energy) && report.strain_energy > 0,
          "the coupon run did not load the coupon");
  nlohmann::json r = row(
      "plydem", model.particles.size(), model.bonds.size(), threads, cycles, seconds,
      process_cpu_seconds() - cpu,
      static_cast<double>(integrator.kernel_bytes()) / static_cast<double>(model.particles.size()));
  r["case"] = breakable ? "table2-hex2d-coupon-breakable" : "table2-hex2d-coupon";
  r["broken_bonds"] = static_cast<long>(integrator.breaks().size());
  r["order"] = order;
  r["api"] = api;
  r["report_every"] = report_every;
  r["backend"] = backend;
  r["streamed_bytes_per_particle_step"] = streamed_bytes(model, integrator.breaking());
  r["unbalanced_force_ratio"] = report.unbalanced_force_ratio;
  r.update(table);
  if (timers.is_object()) r.update(timers);
  std::cout << r.dump() << "\n";
  return 0;
}

// The same coupon through the tension test: its explicit fixed-cycle pull along x, as
// `plydem tension --solver explicit --cycles N` runs it (free grips, 1e-3 nominal strain, a sample
// every 1% of the run), timed whole: building the coupon, the gauge and the samples included.
int run_tension(long cycles, int threads) {
  require(cycles >= 1, "--cycles must be at least 1");
  omp_set_num_threads(threads);
  TensionSettings settings;
  settings.coupon.material = load_material("eglass-my750");
  settings.solver = TensionSolver::kExplicit;
  settings.fixed_cycles = cycles;
  const double cpu = process_cpu_seconds();
  const PullResult pull = TensionTest(settings).pull(Hex2dStrategy(), 0.0);
  nlohmann::json r = row("plydem", pull.particles, pull.bonds, threads, pull.cycles,
                         pull.wall_seconds, process_cpu_seconds() - cpu, std::nan(""));
  r.erase("bytes_per_particle");  // the kernel is the tension test's own
  r["case"] = "table2-hex2d-coupon-tension-test";
  r["modulus"] = pull.modulus;
  r["unbalanced_force_ratio"] = pull.final_ratio;
  std::cout << r.dump() << "\n";
  return 0;
}

std::string engineering(double x) {
  if (!std::isfinite(x)) return "-";
  const char* prefix[] = {"", "k", "M", "G", "T"};
  int k = 0;
  while (std::abs(x) >= 1000 && k < 4) {
    x /= 1000;
    ++k;
  }
  return fmt::format("{:.3g}{}", x, prefix[k]);
}

// The table of bench/run: one row per JSON line read from stdin, each peer's row with the ratio of
// plydem's bond-steps/s at the same size and thread count to the peer's.
int print_table() {
  std::vector<nlohmann::json> rows;
  std::string line;
  while (std::getline(std::cin, line)) {
    if (line.empty() || line[0] != '{') continue;
    rows.push_back(nlohmann::json::parse(line));
  }
  // Bond-steps per second of wall time, and per second of CPU time (the per-core rate, which a
  // busy machine distorts less).
  auto per_cpu_second = [](const nlohmann::json& r) {
    const double cpu = r.value("cpu_seconds", std::nan(""));
    return static_cast<double>(r["bonds"].get<long>()) *
           static_cast<double>(r["steps"].get<long>()) / cpu;
  };
  std::map<std::pair<long, int>, std::pair<double, double>> plydem_rate;
  for (const auto& r : rows) {
    if (r.value("engine", "") == "plydem" && !r.contains("case") && !r.contains("missing"))
      plydem_rate[{r["particles"].get<long>(), r["threads"].get<int>()}] = {
          r["bond_steps_per_s"].get<double>(), per_cpu_second(r)};
  }
  std::cout << fmt::format(
      "{:<8} {:>9} {:>9} {:>3} {:>7} {:>9} {:>5} {:>10} {:>13} {:>12} {:>10} {:<15}\n", "engine",
      "particles", "bonds", "thr", "steps", "seconds", "cpu%", "ns/step", "particle-st/s",
      "bond-st/s", "bytes/part", "plydem/peer (per cpu-s)");
  for (const auto& r : rows) {
    const std::string engine = r.value("engine", "?");
    if (r.contains("missing")) {
      std::cout << fmt::format(
          "{:<8} {:>9} {}\n", engine,
          r.contains("particles") ? std::to_string(r["particles"].get<long>()) : std::string("-"),
          r["missing"].get<std::string>());
      continue;
    }
    std::string ratio = "";
    const auto it = plydem_rate.find({r["particles"].get<long>(), r["threads"].get<int>()});
    if (engine != "plydem" && it != plydem_rate.end()) {
      ratio = fmt::format("{:.1f}x", it->second.first / r["bond_steps_per_s"].get<double>());
      const double cpu_ratio = it->second.second / per_cpu_second(r);
      if (std::isfinite(cpu_ratio)) ratio += fmt::format(" ({:.1f}x)", cpu_ratio);
    }
    const double bytes = r.value("bytes_per_particle", std::nan(""));
    const double cpu = r.value("cpu_seconds", std::nan(""));
    const double seconds = r["seconds"].get<double>();
    const std::string cpu_share =
        std::isfinite(cpu) ? fmt::format("{:.0f}", 100.0 * cpu / seconds / r["threads"].get<int>())
                           : std::string("-");
    std::cout << fmt::format(
        "{:<8} {:>9} {:>9} {:>3} {:>7} {:>9.3f} {:>5} {:>10} {:>13} {:>12} {:>10} {:<15}{}\n",
        engine, r["particles"].get<long>(), r["bonds"].get<long>(), r["threads"].get<int>(),
        r["steps"].get<long>(), seconds, cpu_share, engineering(r["ns_per_step"].get<double>()),
        engineering(r["particle_steps_per_s"].get<double>()),
        engineering(r["bond_steps_per_s"].get<double>()),
        std::isfinite(bytes) ? fmt::format("{:.0f}", bytes) : std::string("-"), ratio,
        r.contains("case") ? "  " + r["case"].get<std::string>() : std::string());
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  const ParallelSession session(&argc, &argv);  // MPI under mpiexec: the layer split between ranks
  if (!is_root()) std::cout.setstate(std::ios::badbit);
  CLI::App app{"plydem_kernel_bench: the explicit kernel on a hexagonal layer (see bench/run)"};
  app.require_subcommand(1);
  long particles = 10000, steps = 100, cycles = 200'000, report_every = 2000;
  int threads = 1;
  std::string lammps_data, yade_layer, order = "auto", api = "run";
  bool describe = false;
  CLI::App* layer = app.add_subcommand("layer", "time the kernel on a square hexagonal layer");
  layer->add_option("--particles", particles, "about this many particles")->capture_default_str();
  layer->add_option("--steps", steps, "cycles to time")->capture_default_str();
  layer->add_option("--threads", threads, "OpenMP threads")->capture_default_str();
  const auto orders = CLI::IsMember({"auto", "hilbert", "built"});
  layer->add_option("--order", order, "kernel particle order: auto (lattice lines), hilbert, built")
      ->check(orders)
      ->capture_default_str();
  const auto apis = CLI::IsMember({"run", "advance"});
  layer->add_option("--api", api, "run: ExplicitIntegrator::run(); advance: advance(N)")
      ->check(apis)
      ->capture_default_str();
  layer->add_option("--lammps-data", lammps_data, "also write the layer as a LAMMPS data file");
  layer->add_option("--yade-layer", yade_layer, "also write x y z radius per particle for YADE");
  layer->add_flag("--describe", describe, "print the layer's size and parameters, run nothing");
  std::string backend = "cpu";
  const auto backends = CLI::IsMember({"cpu", "cuda", "emulation", "reference"});
  layer
      ->add_option("--backend", backend,
                   "where the kernel runs: cpu, cuda, emulation, reference (under mpiexec: split "
                   "between the ranks)")
      ->check(backends)
      ->capture_default_str();
  bool breakable = false;
  int edge_equilibrium = 1;
  layer->add_flag("--breakable", breakable,
                  "give every bond a strength it never reaches: times the breaking kernel");
  CLI::App* coupon = app.add_subcommand("coupon", "the paper's Table 2 Hex2D coupon, timed");
  coupon->add_option("--cycles", cycles, "explicit cycles")->capture_default_str();
  coupon->add_option("--threads", threads, "OpenMP threads")->capture_default_str();
  coupon
      ->add_option("--order", order, "kernel particle order: auto (lattice lines), hilbert, built")
      ->check(orders)
      ->capture_default_str();
  coupon
      ->add_option("--report-every", report_every,
                   "cycles between unbalanced-force reports (the tension test samples every "
                   "1% of the run)")
      ->capture_default_str();
  coupon->add_option("--api", api, "run: ExplicitIntegrator::run(); advance: advance(N) calls")
      ->check(apis)
      ->capture_default_str();
  coupon
      ->add_option("--backend", backend,
                   "where the kernel runs: cpu, cuda, emulation, reference (under mpiexec: split "
                   "between the ranks)")
      ->check(backends)
      ->capture_default_str();
  coupon->add_flag("--breakable", breakable,
                   "give every bond a strength it never reaches: times the breaking kernel");
  for (CLI::App* command : {layer, coupon}) {
    command
        ->add_option("--edge-equilibrium", edge_equilibrium,
                     "free edges: 1 edge equilibrium (each edge bond its own weight: thousands of "
                     "half-bond types), 0 the count completion (a few types, as plydem built "
                     "before edge equilibrium)")
        ->check(CLI::IsMember({0, 1}))
        ->capture_default_str();
  }
  CLI::App* tension =
      app.add_subcommand("tension", "the same coupon through the tension test's explicit path");
  tension->add_option("--cycles", cycles, "fixed explicit cycles")->capture_default_str();
  tension->add_option("--threads", threads, "OpenMP threads")->capture_default_str();
  CLI::App* table = app.add_subcommand("table", "print JSON lines from stdin as the bench table");
  CLI::App* copy = app.add_subcommand("copy", "the CUDA device's copy bandwidth (one JSON line)");
  double copy_bytes = 4e9;
  copy->add_option("--bytes", copy_bytes, "bytes per copy")->capture_default_str();
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  try {
    require(threads >= 1, "--threads must be at least 1");
    if (*layer)
      return run_layer(particles, steps, threads, order, api, lammps_data, yade_layer, describe,
                       backend, breakable, edge_equilibrium);
    if (*coupon)
      return run_coupon(cycles, threads, order, api, report_every, breakable, backend,
                        edge_equilibrium);
    if (*tension) return run_tension(cycles, threads);
    if (*table) return print_table();
    if (*copy) {
      require(copy_bytes >= 1e6, "--bytes must be at least 1e6");
      nlohmann::json r;
      r["copy_bytes"] = copy_bytes;
      r["copy_bandwidth"] = cuda_copy_bandwidth(static_cast<std::size_t>(copy_bytes));
      std::cout << r.dump() << "\n";
      return 0;
    }
  } catch (const std::exception& e) {
    std::cerr << "plydem_kernel_bench: error: " << e.what() << "\n";
    return 2;
  }
  return 1;
}
