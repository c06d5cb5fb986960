// The explicit integrator's device backends (solvers/device_backend.hpp) against its host kernel on
// the same model: elastic and with breaking bonds, the same state, forces, reports, breaks and
// energy account.
//
// - emulation cases (every build, no GPU): the CUDA kernel's code path (solvers/particle_step.hpp,
//   one particle at a time on the host) equals the host's SIMD kernel to the bit, cycle for cycle,
//   with breaks in the same order: the device code is the host's law and the host's update, in the
//   host's order of operations;
// - "gpu:" cases (their own ctest entry, test_cuda_backend_gpu): the CUDA backend itself, 10^4
//   cycles, within 1e-12 relative of the host kernel, the same breaks in the same order, and
//   bitwise reproducible run to run. Without a CUDA device, or in a build without the backend,
//   they say why and ctest reports them skipped;
// - asking for the CUDA backend where it cannot run is a clear error.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "solvers/device_backend.hpp"
#include "solvers/explicit_integrator.hpp"
#include "support/coupon_fixtures.hpp"
#include "support/test_support.hpp"

using namespace plydem;
using namespace plydem::test;

namespace {

// Uniform strengths on every bond: the section a disc of the particle radius.
void set_strengths(Model& m, double tensile, double cohesion, double friction, double ductility) {
  Bonds& b = m.bonds;
  for (int k = 0; k < b.size(); ++k) {
    b.strength_radius(k) = m.particles.radius(b.first(k));
    b.tensile_strength(k) = tensile;
    b.cohesion(k) = cohesion;
    b.friction_coefficient(k) = friction;
    b.ductility(k) = ductility;
  }
}

// The largest normal section stress of the coupon's bonds after `cycles` elastic cycles of pulling
// at `speed`, per cycle: strengths set from it break the first bonds after a known number of
// cycles (the coupon is linear).
double stress_per_cycle(const Model& model, const ExplicitSettings& settings, double speed,
                        long cycles) {
  Model m = model;
  ExplicitIntegrator integrator(m, settings);
  integrator.set_prescribed_motions(pull(speed));
  integrator.advance(cycles);
  double largest = 0;
  for (int b = 0; b < m.bonds.size(); ++b) {
    const int i = m.bonds.first(b), j = m.bonds.second(b);
    const BondStresses s = bond_stresses(bond_parameters(m.bonds, b), m.particles.radius(i),
                                         m.particles.displacement.row(i).matrix().transpose(),
                                         m.particles.rotation.row(i).matrix().transpose(),
                                         m.particles.displacement.row(j).matrix().transpose(),
                                         m.particles.rotation.row(j).matrix().transpose());
    largest = std::max(largest, s.normal);
  }
  return largest / static_cast<double>(cycles);
}

struct Run {
  Model model;
  std::vector<BondBreak> breaks;
  std::vector<CycleReport> reports;  // at every check
  EnergyAccount energy;
  std::vector<std::array<BondEnd, 2>> ends;
};

// Pulls the coupon for `cycles` cycles, a check every `check_every`, on `backend`.
Run pull_coupon(Model m, ExplicitSettings settings, ExplicitBackend backend, double speed,
                long cycles, long check_every) {
  settings.backend = backend;
  Run r;
  ExplicitIntegrator integrator(m, settings);
  integrator.set_prescribed_motions(pull(speed));
  RunControl control;
  control.check_interval = check_every;
  control.max_cycles = cycles;
  control.on_check = [&](const RunCheck& check) {
    r.reports.push_back(check.report);
    return true;
  };
  integrator.run(control);
  r.breaks = integrator.breaks();
  r.energy = integrator.energy();
  for (int b = 0; b < m.bonds.size(); ++b) r.ends.push_back(integrator.bond_ends(b));
  r.model = std::move(m);
  return r;
}

bool same_breaks(const std::vector<BondBreak>& a, const std::vector<BondBreak>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t k = 0; k < a.size(); ++k)
    if (a[k].bond != b[k].bond || a[k].mode != b[k].mode || a[k].at != b[k].at) return false;
  return true;
}

// max |a - b| / max |b| over the state, forces and moments (0 where both are zero).
double relative_difference(const Particles& a, const Particles& b) {
  double worst = 0;
  auto compare = [&](const Vector3Array& x, const Vector3Array& y) {
    const double scale = y.abs().maxCoeff();
    const double difference = (x - y).abs().maxCoeff();
    if (difference > 0) worst = std::max(worst, scale > 0 ? difference / scale : INFINITY);
  };
  compare(a.displacement, b.displacement);
  compare(a.rotation, b.rotation);
  compare(a.velocity, b.velocity);
  compare(a.angular_velocity, b.angular_velocity);
  compare(a.force, b.force);
  compare(a.torque, b.torque);
  return worst;
}

bool bitwise_equal(const Particles& a, const Particles& b) {
  return (a.displacement == b.displacement).all() && (a.rotation == b.rotation).all() &&
         (a.velocity == b.velocity).all() && (a.angular_velocity == b.angular_velocity).all() &&
         (a.force == b.force).all() && (a.torque == b.torque).all();
}

bool same_reports(const std::vector<CycleReport>& a, const std::vector<CycleReport>& b,
                  double tolerance) {
  if (a.size() != b.size()) return false;
  auto close = [&](double x, double y) {
    return std::abs(x - y) <= tolerance * std::max(std::abs(x), std::abs(y));
  };
  for (std::size_t k = 0; k < a.size(); ++k)
    if (!close(a[k].strain_energy, b[k].strain_energy) ||
        !close(a[k].kinetic_energy, b[k].kinetic_energy) ||
        !close(a[k].unbalanced_force_ratio, b[k].unbalanced_force_ratio))
      return false;
  return true;
}

// A 1.5 x 0.5 mm hex2d coupon of 0.05 mm particles (about 300), pulled as the tension test pulls.
struct BreakingCase {
  Model model;
  ExplicitSettings settings;
  double speed = 0.02;
};

// The coupon with strengths that break its first bonds after about 2500 of `cycles` cycles:
// brittle (ductility 1) or softening, strengths per type or per slot; contacts off (the device
// backends have none).
BreakingCase breaking_case(double ductility, StrengthStorage storage) {
  BreakingCase c;
  c.model = small_coupon(1.5e-3, 0.5e-3, 0.05e-3);
  c.settings.time_step = 0.8 * critical_time_step(c.model);
  c.settings.contacts = false;
  c.settings.strength_storage = storage;
  const double rate = stress_per_cycle(c.model, c.settings, c.speed, 500);
  set_strengths(c.model, 2500.37 * rate, 4000.37 * rate, 0.3, ductility);
  return c;
}

std::string backend_error(ExplicitSettings settings, Model m) {
  try {
    ExplicitIntegrator integrator(m, settings);
    integrator.advance(1);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST_CASE("emulation: the device's code path equals the host kernel to the bit, elastic") {
  const Model m = small_coupon(1.5e-3, 0.5e-3, 0.05e-3);
  ExplicitSettings settings;  // PFC damping 0.7, as the tension test runs
  settings.time_step = 0.8 * critical_time_step(m);
  // Checks every 700 cycles: several batches, each ending with a report cycle.
  const Run host = pull_coupon(m, settings, ExplicitBackend::kCpu, 0.02, 3000, 700);
  const Run device = pull_coupon(m, settings, ExplicitBackend::kDeviceEmulation, 0.02, 3000, 700);
  REQUIRE(host.model.particles.displacement.abs().maxCoeff() > 0);
  CHECK(bitwise_equal(device.model.particles, host.model.particles));
  CHECK(same_reports(device.reports, host.reports, 0.0));
  CHECK(host.reports.size() == 5);
}

TEST_CASE("emulation: the device's code path breaks the host kernel's bonds in the same order") {
  struct Variant {
    const char* name;
    double ductility;
    StrengthStorage storage;
  };
  for (const Variant& v :
       {Variant{"brittle, strengths per type", 1.0, StrengthStorage::kTypes},
        Variant{"brittle, strengths per slot", 1.0, StrengthStorage::kSlots},
        Variant{"softening, strengths per type", 3.0, StrengthStorage::kTypes},
        Variant{"softening, strengths per slot", 3.0, StrengthStorage::kSlots}}) {
    const std::string variant = v.name;
    CAPTURE(variant);
    const BreakingCase c = breaking_case(v.ductility, v.storage);
    const Run host = pull_coupon(c.model, c.settings, ExplicitBackend::kCpu, c.speed, 6000, 1000);
    const Run device =
        pull_coupon(c.model, c.settings, ExplicitBackend::kDeviceEmulation, c.speed, 6000, 1000);
    REQUIRE(host.breaks.size() > 5);
    CHECK(same_breaks(device.breaks, host.breaks));
    CHECK(bitwise_equal(device.model.particles, host.model.particles));
    CHECK(same_reports(device.reports, host.reports, 0.0));
    CHECK(device.energy.boundary_work == host.energy.boundary_work);
    CHECK(device.energy.damping == host.energy.damping);
    CHECK(device.energy.released == host.energy.released);
    int ends_differ = 0;
    for (std::size_t b = 0; b < host.ends.size(); ++b)
      for (int e = 0; e < 2; ++e)
        ends_differ += host.ends[b][e].holds != device.ends[b][e].holds ||
                               host.ends[b][e].damage != device.ends[b][e].damage ||
                               host.ends[b][e].kappa != device.ends[b][e].kappa
                           ? 1
                           : 0;
    CHECK(ends_differ == 0);
    for (int b = 0; b < c.model.bonds.size(); ++b)
      CHECK(device.model.bonds.state(b) == host.model.bonds.state(b));
  }
}

TEST_CASE("a device backend without contacts refuses a breaking run that has them, clearly") {
  BreakingCase c = breaking_case(1.0, StrengthStorage::kAutomatic);
  c.settings.contacts = true;
  c.settings.backend = ExplicitBackend::kDeviceEmulation;
  const std::string message = backend_error(c.settings, c.model);
  CHECK(contains(message, "emulation backend has no contacts"));
  CHECK(contains(message, "contacts off"));
  CHECK(contains(error_message([] { parse_backend("gpu"); }), "unknown backend 'gpu'"));
}

TEST_CASE("asking for the CUDA backend where it cannot run is a clear error") {
  std::string why;
  if (cuda_available(&why)) {
    skip("a CUDA device is present: the CUDA backend can run here (test_cuda_backend_gpu)");
    return;
  }
  ExplicitSettings settings;
  settings.backend = ExplicitBackend::kCuda;
  const std::string message = backend_error(settings, small_coupon());
  CHECK(contains(message, "--backend cuda: "));
  CHECK(contains(message, why));
  CHECK((contains(message, "no CUDA backend") || contains(message, "no CUDA device")));
}

// --- on a CUDA device --------------------------------------------------------------------------

namespace {

bool no_device() {
  std::string why;
  if (cuda_available(&why)) return false;
  skip("no CUDA device: " + why);
  return true;
}

}  // namespace

TEST_CASE("gpu: the CUDA backend equals the host kernel within 1e-12 after 10^4 cycles, elastic") {
  if (no_device()) return;
  const Model m = small_coupon(4e-3, 1e-3, 0.05e-3);  // about 1800 particles
  ExplicitSettings settings;
  settings.time_step = 0.8 * critical_time_step(m);
  const Run host = pull_coupon(m, settings, ExplicitBackend::kCpu, 0.01, 10000, 2500);
  const Run gpu = pull_coupon(m, settings, ExplicitBackend::kCuda, 0.01, 10000, 2500);
  const Run again = pull_coupon(m, settings, ExplicitBackend::kCuda, 0.01, 10000, 2500);
  const double difference = relative_difference(gpu.model.particles, host.model.particles);
  MESSAGE("largest relative difference from the host kernel: " << difference);
  CHECK(difference <= 1e-12);
  CHECK(same_reports(gpu.reports, host.reports, 1e-12));
  CHECK(bitwise_equal(again.model.particles, gpu.model.particles));
  CHECK(same_reports(again.reports, gpu.reports, 0.0));
}

TEST_CASE("gpu: the CUDA backend breaks the host kernel's bonds in the same order") {
  if (no_device()) return;
  for (const double ductility : {1.0, 3.0}) {
    CAPTURE(ductility);
    const BreakingCase c = breaking_case(ductility, StrengthStorage::kAutomatic);
    const Run host = pull_coupon(c.model, c.settings, ExplicitBackend::kCpu, c.speed, 10000, 1000);
    const Run gpu = pull_coupon(c.model, c.settings, ExplicitBackend::kCuda, c.speed, 10000, 1000);
    const Run again =
        pull_coupon(c.model, c.settings, ExplicitBackend::kCuda, c.speed, 10000, 1000);
    REQUIRE(host.breaks.size() > 5);
    CHECK(same_breaks(gpu.breaks, host.breaks));
    const double difference = relative_difference(gpu.model.particles, host.model.particles);
    MESSAGE("largest relative difference from the host kernel: " << difference);
    CHECK(difference <= 1e-12);
    CHECK(same_breaks(again.breaks, gpu.breaks));
    CHECK(bitwise_equal(again.model.particles, gpu.model.particles));
  }
}
