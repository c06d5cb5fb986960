// Checkpoint and restart (core/checkpoint.hpp): an explicit run with breaking bonds stopped half
// way, written to a file, read back into fresh objects and continued gives, bit for bit, the
// particles, bonds, break log and energy account of the run that was not stopped (both kernels,
// brittle and softening bonds, checkpoints between runs and from a run's hook); an events run
// resumed from any of its checkpoints gives the same events to the bit (Woodbury updates replayed
// after the factor is rebuilt); a corrupt, truncated, other-version or mismatched file is a clear
// error.
#include <doctest/doctest.h>
#include <fmt/format.h>
#include <unistd.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

#include "contacts/bond_kernel.hpp"
#include "core/checkpoint.hpp"
#include "core/error.hpp"
#include "core/material.hpp"
#include "solvers/bond_events.hpp"
#include "solvers/explicit_integrator.hpp"
#include "strategies/cure_stress.hpp"
#include "strategies/registry.hpp"
#include "support/coupon_fixtures.hpp"

using namespace plydem;
using namespace plydem::test;
namespace fs = std::filesystem;

namespace {

// A file in the temporary folder, removed at the end of the scope.
struct TempFile {
  explicit TempFile(const std::string& name)
      : path(fs::temp_directory_path() / fmt::format("plydem_{}_{}.ckpt", name, ::getpid())) {}
  ~TempFile() {
    std::error_code ec;
    fs::remove(path, ec);
  }
  fs::path path;
};

std::string read_bytes(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void write_bytes(const fs::path& file, const std::string& bytes) {
  std::ofstream out(file, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

// Strengths that the pull reaches after about `cycles` cycles (the largest bond stress of an
// elastic run grows linearly with the grips' travel).
// `mixed`: every bond gets the mixed-mode law of interface bonds (core/bond_failure.hpp) instead.
void set_strengths(Model& m, const ExplicitSettings& settings, double speed, double cycles,
                   double ductility, bool mixed = false) {
  Model elastic = m;
  ExplicitSettings s = settings;
  s.backend = ExplicitBackend::kReference;
  ExplicitIntegrator integrator(elastic, s);
  integrator.set_prescribed_motions(pull(speed));
  integrator.advance(1000);
  double largest = 0;
  for (int b = 0; b < elastic.bonds.size(); ++b) {
    const Particles& p = elastic.particles;
    const BondStresses st =
        bond_stresses(bond_parameters(elastic.bonds, b), p.radius(elastic.bonds.first(b)),
                      p.displacement.row(elastic.bonds.first(b)).matrix().transpose(),
                      p.rotation.row(elastic.bonds.first(b)).matrix().transpose(),
                      p.displacement.row(elastic.bonds.second(b)).matrix().transpose(),
                      p.rotation.row(elastic.bonds.second(b)).matrix().transpose());
    largest = std::max(largest, st.normal);
  }
  const double rate = largest / 1000;
  for (int k = 0; k < m.bonds.size(); ++k) {
    m.bonds.strength_radius(k) = m.particles.radius(m.bonds.first(k));
    m.bonds.tensile_strength(k) = cycles * rate;
    m.bonds.cohesion(k) = 1.7 * cycles * rate;
    m.bonds.friction_coefficient(k) = mixed ? 0.0 : 0.3;
    m.bonds.ductility(k) = ductility;
    if (mixed) {
      m.bonds.mixed_mode_exponent(k) = 2.284;
      m.bonds.fracture_energy_ratio(k) = 2.5;
      m.bonds.peak_energy_ratio(k) = 3.0;
    }
  }
}

template <class S>
bool same_fields(const S& a, const S& b) {
  bool same = true;
  S::for_each_field([&](const FieldInfo& info, auto member) {
    const auto& x = a.*member;
    const auto& y = b.*member;
    const bool equal =
        x.rows() == y.rows() && std::memcmp(x.data(), y.data(), sizeof(*x.data()) * x.size()) == 0;
    if (!equal) MESSAGE("field ", info.name, " differs");
    same &= equal;
  });
  return same;
}

bool same_breaks(const std::vector<BondBreak>& a, const std::vector<BondBreak>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t k = 0; k < a.size(); ++k)
    if (a[k].bond != b[k].bond || a[k].mode != b[k].mode || a[k].at != b[k].at ||
        a[k].load != b[k].load || a[k].position != b[k].position)
      return false;
  return true;
}

bool same_account(const EnergyAccount& a, const EnergyAccount& b) {
  return a.initial == b.initial && a.boundary_work == b.boundary_work &&
         a.strain_energy == b.strain_energy && a.kinetic_energy == b.kinetic_energy &&
         a.damping == b.damping && a.released == b.released &&
         a.contact_energy == b.contact_energy && a.friction == b.friction;
}

struct ExplicitOutcome {
  Model model;
  std::vector<BondBreak> breaks;
  EnergyAccount energy;
  long cycles = 0;
  double time = 0;
  std::size_t breaks_at_checkpoint = 0;
};

RunControl control(long cycles) {
  RunControl c;
  c.check_interval = 500;
  c.max_cycles = cycles;
  return c;
}

const CheckpointHeader kNoHeader{};

// Runs `cycles` cycles of `initial` pulled at `speed`; with `file`, saves at `at` cycles (from the
// run's hook, or between two runs) and continues in fresh objects from the file.
ExplicitOutcome explicit_run(const Model& initial, const ExplicitSettings& settings, double speed,
                             long cycles, const fs::path* file = nullptr, long at = 0,
                             bool from_hook = false) {
  ExplicitOutcome out;
  out.model = initial;
  auto integrator = std::make_unique<ExplicitIntegrator>(out.model, settings);
  integrator->set_prescribed_motions(pull(speed));
  if (!file) {
    integrator->run(control(cycles));
  } else {
    if (from_hook) {
      // The whole run, saving from its check at `at` (the run goes on: only the file is used).
      RunControl c = control(cycles);
      c.on_check = [&](const RunCheck& check) {
        if (check.cycles == at) {
          CheckpointWriter w;
          integrator->save(w);
          write_checkpoint(*file, kNoHeader, w);
          out.breaks_at_checkpoint = integrator->breaks().size();
        }
        return true;
      };
      integrator->run(c);
    } else {
      integrator->run(control(at));
      CheckpointWriter w;
      integrator->save(w);
      write_checkpoint(*file, kNoHeader, w);
      out.breaks_at_checkpoint = integrator->breaks().size();
    }
    // Fresh objects: the model as built, a new integrator, the state from the file.
    integrator.reset();
    out.model = initial;
    integrator = std::make_unique<ExplicitIntegrator>(out.model, settings);
    integrator->set_prescribed_motions(pull(speed));
    CheckpointFile f = read_checkpoint(*file);
    integrator->restore(f.payload);
    f.payload.finish();
    REQUIRE(integrator->cycles() == at);
    integrator->run(control(cycles - at));
  }
  out.breaks = integrator->breaks();
  out.energy = integrator->energy();
  out.cycles = integrator->cycles();
  out.time = integrator->time();
  return out;
}

}  // namespace

namespace {

// Runs `initial` with strengths reached after about 2000 cycles for 6000 cycles, uninterrupted
// and restarted at 3000, for each ductility, kernel and way of saving given.
void check_explicit_restart(const std::vector<double>& ductilities,
                            const std::vector<ExplicitBackend>& kernels,
                            const std::vector<bool>& from_hooks, bool mixed = false) {
  const Model built = small_coupon();
  ExplicitSettings settings;
  settings.time_step = 0.8 * critical_time_step(built);
  const double speed = 0.02;
  const long cycles = 6000, half = 3000;
  TempFile file("explicit");
  for (const double ductility : ductilities) {
    Model initial = built;
    set_strengths(initial, settings, speed, 2000.37, ductility, mixed);
    for (const ExplicitBackend kernel : kernels) {
      for (const bool from_hook : from_hooks) {
        CAPTURE(ductility);
        CAPTURE(static_cast<int>(kernel));
        CAPTURE(from_hook);
        settings.backend = kernel;
        const ExplicitOutcome whole = explicit_run(initial, settings, speed, cycles);
        const ExplicitOutcome resumed =
            explicit_run(initial, settings, speed, cycles, &file.path, half, from_hook);
        // Bonds broke before the checkpoint and after it.
        CHECK(resumed.breaks_at_checkpoint > 0);
        CHECK(whole.breaks.size() > resumed.breaks_at_checkpoint);
        CHECK(resumed.cycles == whole.cycles);
        CHECK(resumed.time == whole.time);
        CHECK(same_fields(resumed.model.particles, whole.model.particles));
        CHECK(same_fields(resumed.model.bonds, whole.model.bonds));
        CHECK(same_breaks(resumed.breaks, whole.breaks));
        CHECK(same_account(resumed.energy, whole.energy));
        if (ductility > 1) {
          int softened = 0;
          for (int b = 0; b < whole.model.bonds.size(); ++b)
            softened += whole.model.bonds.damage(b) > 0 && !whole.model.bonds.is_broken(b);
          CHECK(softened > 0);
        }
      }
    }
  }
}

}  // namespace

TEST_CASE("an explicit run with softening bonds restarted from a hook's checkpoint is the same") {
  // The path the tension test takes (fused kernel, saved from a check), in every build.
  check_explicit_restart({4.0}, {ExplicitBackend::kCpu}, {true});
}

TEST_CASE("every kernel: explicit runs with breaking bonds restarted are bitwise the same") {
  // Brittle and softening, fused and reference kernels, saved between runs and from a hook.
  check_explicit_restart({1.0, 4.0}, {ExplicitBackend::kCpu, ExplicitBackend::kReference},
                         {false, true});
}

TEST_CASE("explicit runs with mixed-mode bonds restarted are bitwise the same") {
  // The interface bonds' law (its fields travel in the checkpoint's bonds), both kernels.
  check_explicit_restart({4.0}, {ExplicitBackend::kCpu, ExplicitBackend::kReference}, {false},
                         true);
}

TEST_CASE("an explicit checkpoint of another model or other settings is refused") {
  const Model built = small_coupon();
  ExplicitSettings settings;
  settings.time_step = 0.8 * critical_time_step(built);
  Model initial = built;
  set_strengths(initial, settings, 0.02, 2000.37, 1.0);
  TempFile file("explicit_other");
  {
    Model m = initial;
    ExplicitIntegrator integrator(m, settings);
    integrator.set_prescribed_motions(pull(0.02));
    integrator.advance(500);
    CheckpointWriter w;
    integrator.save(w);
    write_checkpoint(file.path, kNoHeader, w);
  }
  auto restore_into = [&](Model m, const ExplicitSettings& s) {
    ExplicitIntegrator integrator(m, s);
    CheckpointFile f = read_checkpoint(file.path);
    integrator.restore(f.payload);
  };
  CHECK_NOTHROW(restore_into(initial, settings));
  Model stronger = initial;
  stronger.bonds.tensile_strength *= 1.01;
  CHECK(contains(error_message([&] { restore_into(stronger, settings); }),
                 "is for another model: field tensile_strength of the bonds differs"));
  ExplicitSettings other = settings;
  other.time_step *= 0.5;
  CHECK(contains(error_message([&] { restore_into(initial, other); }),
                 "is for another run: time step is"));
  other = settings;
  other.backend = ExplicitBackend::kReference;
  CHECK(contains(
      error_message([&] { restore_into(initial, other); }),
      "is for another run: backend is kernel order (cpu, emulation, cuda) there, reference here"));
  CHECK(contains(error_message([&] { restore_into(small_coupon(2e-3, 0.6e-3), settings); }),
                 "is for another"));
}

namespace {

// ductility 0: bonds that never break by their own law (failure at the material point), the ply
// at 90 degrees.
Model events_coupon(double ductility) {
  const double d = 0.1e-3;
  CouponSpec spec;
  spec.material = load_material("eglass-my750");
  spec.ply_angle = ductility > 0 ? 0.0 : std::numbers::pi / 2;
  spec.length = 2e-3;
  spec.width = ductility > 0 ? 0.5e-3 : 1.2e-3;  // a crack of a site per row
  spec.particle_diameter = d;
  Model m = default_registry().create("hex2d")->build(spec).model;
  const double unbreakable = std::numeric_limits<double>::infinity();
  for (int b = 0; b < m.bonds.size(); ++b) {
    m.bonds.strength_radius(b) = 0.25 * d;
    m.bonds.tensile_strength(b) = ductility > 0 ? 60e6 : unbreakable;
    m.bonds.cohesion(b) = ductility > 0 ? 80e6 : unbreakable;
    m.bonds.friction_coefficient(b) = 0.2;
    m.bonds.ductility(b) = ductility > 0 ? ductility : 1.0;
  }
  return m;
}

bool same_path(const std::vector<EventPoint>& a, const std::vector<EventPoint>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t k = 0; k < a.size(); ++k)
    if (a[k].event != b[k].event || a[k].load_factor != b[k].load_factor ||
        a[k].reaction != b[k].reaction || a[k].bond != b[k].bond || a[k].broken != b[k].broken ||
        a[k].strain_energy != b[k].strain_energy || a[k].site_tooth != b[k].site_tooth)
      return false;
  return true;
}

}  // namespace

TEST_CASE("an events run resumed from its checkpoints gives the same events to the bit") {
  // Brittle bonds, softening bonds, and sites that crack at the material point (each crack's
  // bonds in one update of the factor), brittle (ductility 0) and softening (-1: the cracks'
  // teeth and their state in the checkpoint); softening sites again with a cure (the coupon
  // cooled by 40 K, held by its grips: the preload's state in the checkpoint; the bonds' roots
  // under a preload are test_bond_events.cpp's); brittle sites by the coupled criterion (its
  // layer cracks' energy factors, kept as bounds, in the checkpoint).
  struct Case {
    double ductility, cooling;
    bool coupled = false;
  };
  double uncured_first = NAN;  // the first crack's load factor of the uncured softening sites
  for (const Case& c :
       {Case{1, 0}, Case{3, 0}, Case{0, 0}, Case{-1, 0}, Case{-1, -40}, Case{0, 0, true}}) {
    const double ductility = c.ductility;
    CAPTURE(ductility);
    CAPTURE(c.cooling);
    CAPTURE(c.coupled);
    Model built = events_coupon(std::max(ductility, 0.0));
    if (c.cooling != 0) {
      const Material eglass = load_material("eglass-my750");
      const double angle = ductility > 0 ? 0.0 : std::numbers::pi / 2;
      set_cure_offsets(built, {Ply{eglass, angle, 0.2e-3}}, c.cooling);
    }
    DofConstraints unit;
    DofFlags reaction;
    grip_constraints(built, 0.1e-3, 1e-6, unit, reaction);
    EventSettings settings;
    settings.static_settings.pin_rigid_modes = true;
    settings.max_events = ductility > 1 ? 300 : 2000;
    settings.max_update_rank = 24;  // several refactorizations along the way
    if (ductility <= 0) {
      MaterialPointFailure sites;
      sites.criterion = FailureCriterion::kPuck;
      sites.material = load_material("eglass-my750");
      sites.material.strength.G_fibre = 40e3;
      sites.material.strength.G_matrix = 300;
      sites.softening = ductility < 0;
      sites.coupled = c.coupled;
      sites.ply_angles = {std::numbers::pi / 2};
      settings.material_point = sites;
    }
    // Every event's state goes through a file; the run itself is the uninterrupted one.
    struct Saved {
      std::string bytes;
      bool stale = false;
      long events = 0;
    };
    std::vector<Saved> saved;
    settings.checkpoint_every = 1;
    settings.on_checkpoint = [&](const Model& model, const EventsState& state) {
      CheckpointWriter w;
      write_model(w, model);
      write_events_state(w, state);
      saved.push_back({w.bytes(), state.stale, state.events});
    };
    Model whole_model = built;
    const EventsResult whole = run_events(whole_model, unit, reaction, settings);
    REQUIRE(whole.path.size() > (ductility > 0 ? 15u : (c.coupled ? 2u : 4u)));
    CHECK(whole.factorizations > (ductility > 0 ? 2 : 1));
    if (ductility <= 0) CHECK(whole.path.front().site >= 0);
    // Held by its grips as it cools, the 90 deg ply carries E2 alpha2 40 K, 17 MPa, of its YT
    // before the load: its first site cracks at a smaller load factor than uncured.
    if (ductility < 0 && c.cooling == 0) uncured_first = whole.path.front().load_factor;
    if (c.cooling != 0) {
      MESSAGE("first crack at load factor " << whole.path.front().load_factor << ", uncured "
                                            << uncured_first);
      CHECK(whole.path.front().load_factor < 0.8 * uncured_first);
    }
    if (ductility < 0) CHECK(whole.path.back().site_tooth > 0);
    // Resume from a spread of events (all of a short run): right before factorizations (stale),
    // in the middle of update sequences, near the end.
    settings.on_checkpoint = nullptr;
    settings.checkpoint_every = 0;
    int resumed = 0, stale = 0;
    TempFile file("events");
    // With the cure, fewer (its preload's state goes through the same reads and writes).
    const int most_stale = c.cooling != 0 ? 2 : 6;
    for (std::size_t k = 0; k < saved.size(); ++k) {
      // At most six right before a factorization, every 40th event, the last but one.
      const bool pick = (c.cooling == 0 && (saved.size() < 25 || k % 40 == 5)) ||
                        k + 2 == saved.size() || (c.cooling != 0 && k == saved.size() / 2) ||
                        (saved[k].stale && stale < most_stale);
      if (!pick) continue;
      CAPTURE(saved[k].events);
      CheckpointWriter w;
      // Through a file, as a restart reads it.
      CheckpointReader direct(saved[k].bytes, "memory");
      Model state_model;
      read_model(direct, state_model);
      const EventsState state0 = read_events_state(direct);
      write_model(w, state_model);
      write_events_state(w, state0);
      write_checkpoint(file.path, kNoHeader, w);
      CheckpointFile f = read_checkpoint(file.path);
      Model model = built;
      Model checkpointed;
      read_model(f.payload, checkpointed);
      const EventsState state = read_events_state(f.payload);
      f.payload.finish();
      model.bonds = checkpointed.bonds;
      model.particles = checkpointed.particles;
      const EventsResult r = run_events(model, unit, reaction, settings, &state);
      CHECK(same_path(r.path, whole.path));
      CHECK(same_breaks(r.breaks, whole.breaks));
      CHECK(r.peak == whole.peak);
      CHECK(r.stop == whole.stop);
      CHECK(r.solves == whole.solves);
      CHECK(r.factorizations == whole.factorizations);
      CHECK(r.dissipated_energy == whole.dissipated_energy);
      CHECK(r.crack_energy == whole.crack_energy);
      CHECK(r.crack_area == whole.crack_area);
      CHECK(same_fields(model.bonds, whole_model.bonds));
      CHECK(same_fields(model.particles, whole_model.particles));
      ++resumed;
      stale += saved[k].stale ? 1 : 0;
    }
    MESSAGE(
        fmt::format("ductility {}, cooling {} K{}: {} events, {} factorizations, resumed from {} "
                    "checkpoints ({} right before a factorization)",
                    ductility, c.cooling, c.coupled ? ", coupled criterion" : "", whole.path.size(),
                    whole.factorizations, resumed, stale));
    CHECK(stale > 0);
    // The coupled criterion's layer cracks each pass the update's rank: every event refactors.
    if (c.coupled)
      CHECK(resumed >= 3);
    else
      CHECK(resumed - stale > (c.cooling != 0 ? 0 : (ductility > 0 ? 2 : 1)));
  }
}

TEST_CASE("a corrupt, truncated, other-version or mismatched checkpoint is a clear error") {
  TempFile file("bad");
  const Model m = small_coupon();
  // GCC 12 warns (-Wrestrict) inside std::string on assignments to a copied header's strings:
  // every header here is built afresh.
  auto make_header = [&](const std::string& kind, const std::string& seed, const Model& model) {
    CheckpointHeader h;
    h.kind = kind;
    h.add("seed", seed);
    h.add("material", "eglass-my750");
    add_model_fingerprint(h, model);
    return h;
  };
  const CheckpointHeader header = make_header("strength/events", "1", m);
  CheckpointWriter w;
  write_model(w, m);
  write_checkpoint(file.path, header, w);
  const std::string good = read_bytes(file.path);
  {
    CheckpointFile f = read_checkpoint(file.path);
    CHECK(f.header.kind == header.kind);
    CHECK(f.header.settings == header.settings);
    CHECK(f.header.settings_hash() == header.settings_hash());
    Model back;
    read_model(f.payload, back);
    f.payload.finish();
    CHECK(same_fields(back.particles, m.particles));
    CHECK(same_fields(back.bonds, m.bonds));
  }
  const std::string name = file.path.string();
  auto read_error = [&](const std::string& bytes) {
    write_bytes(file.path, bytes);
    return error_message([&] { read_checkpoint(file.path); });
  };
  // One byte of the payload changed.
  std::string bytes = good;
  bytes[bytes.size() / 2] ^= 0x10;
  std::string e = read_error(bytes);
  CHECK(contains(e, "checkpoint " + name + " is corrupt: checksum"));
  MESSAGE(e);
  // Cut short.
  e = read_error(good.substr(0, good.size() - 100));
  CHECK(contains(e, "checkpoint " + name + " is truncated"));
  MESSAGE(e);
  e = read_error(good.substr(0, 12));
  CHECK(contains(e, "is truncated"));
  // Another format version.
  bytes = good;
  bytes[8] = static_cast<char>(kCheckpointVersion + 1);
  e = read_error(bytes);
  CHECK(contains(e, fmt::format("has format version {}, this plydem reads version {}",
                                kCheckpointVersion + 1, kCheckpointVersion)));
  MESSAGE(e);
  // Not a checkpoint at all; no file.
  CHECK(contains(read_error("seed = 1\n"), "is not a plydem checkpoint"));
  std::error_code ec;
  fs::remove(file.path, ec);
  CHECK(contains(error_message([&] { read_checkpoint(file.path); }), "cannot read checkpoint"));
  // Written whole again: no temporary file left beside it.
  write_checkpoint(file.path, header, w);
  const fs::path written(file.path);
  for (const fs::directory_entry& entry : fs::directory_iterator(written.parent_path())) {
    const std::string beside = entry.path().filename().string();
    CHECK_FALSE(
        (beside.starts_with(written.filename().string() + ".") && beside.ends_with(".tmp")));
  }
  // Mismatched settings name what differs.
  const CheckpointHeader seed2 = make_header("strength/events", "2", m);
  e = error_message([&] { check_same_run(header, seed2, name); });
  CHECK(e == fmt::format("checkpoint {} is for another run: seed is 1 there, 2 here", name));
  const CheckpointHeader tension = make_header("tension/explicit", "1", m);
  CHECK(contains(error_message([&] { check_same_run(header, tension, name); }),
                 "a strength/events run, this is tension/explicit"));
  Model other = m;
  other.particles.mass *= 2;
  const CheckpointHeader heavier = make_header("strength/events", "1", other);
  e = error_message([&] { check_same_run(header, heavier, name); });
  CHECK(contains(e, "model.particles.mass is"));
  MESSAGE(e);
  CHECK_NOTHROW(check_same_run(header, header, name));
  // A payload read past its end is truncated, not a crash.
  CheckpointReader short_reader(w.bytes().substr(0, 40), "memory");
  Model back;
  CHECK(contains(error_message([&] { read_model(short_reader, back); }), "truncated"));
}
