// The fused explicit kernel against the simple reference path: the same forces, the same cycles,
// the same result on one or two threads and under any particle numbering; and the space-filling
// curve it numbers particles by.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>
#include <set>

#include "contacts/bond_kernel.hpp"
#include "contacts/particle_ordering.hpp"
#include "core/error.hpp"
#include "core/material.hpp"
#include "solvers/explicit_integrator.hpp"
#include "strategies/hex2d.hpp"
#include "support/threads.hpp"

using namespace plydem;

namespace {

// A random 3D cloud bonded between near neighbours, random stiffnesses and sizes (so that no two
// bonds share parameters), some particles in the grip groups.
Model random_model(unsigned seed, int n = 60) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Model m;
  m.particles.resize(n);
  for (int i = 0; i < n; ++i) {
    m.particles.reference_position.row(i) << 4 * u(rng), 4 * u(rng), 2 * u(rng);
    m.particles.radius(i) = 0.2 + 0.2 * u(rng);
    m.particles.mass(i) = 0.5 + u(rng);
    m.particles.moment_of_inertia(i) = 0.05 + 0.1 * u(rng);
    m.particles.group(i) = i % 7 == 0 ? 1 : (i % 11 == 0 ? 2 : 0);
  }
  std::vector<std::pair<int, int>> pairs;
  for (int i = 0; i < n; ++i)
    for (int j = i + 1; j < n; ++j)
      if ((m.particles.reference_position.row(i) - m.particles.reference_position.row(j))
              .matrix()
              .norm() < 1.3)
        pairs.push_back(u(rng) < 0.5 ? std::pair(i, j) : std::pair(j, i));
  m.bonds.resize(static_cast<int>(pairs.size()));
  for (int b = 0; b < m.bonds.size(); ++b) {
    m.bonds.first(b) = pairs[b].first;
    m.bonds.second(b) = pairs[b].second;
    m.bonds.normal_stiffness(b) = 1 + u(rng);
    m.bonds.shear_stiffness(b) = 0.5 * u(rng);
    m.bonds.bending_stiffness(b) = 0.1 * u(rng);
    m.bonds.twisting_stiffness(b) = 0.1 * u(rng);
    set_bond_geometry(m.particles, m.bonds, b);
  }
  return m;
}

Model hex_coupon(double length = 0.6e-3, double width = 0.4e-3) {
  CouponSpec spec;
  spec.material = load_material("eglass-my750");
  spec.ply_angle = 0.3;
  spec.length = length;
  spec.width = width;
  return Hex2dStrategy().build(spec).model;
}

// Random displacements, rotations and velocities of the size a loaded model sees.
void disturb(Model& m, unsigned seed, double scale) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0.0, 1.0);
  Particles& p = m.particles;
  for (int i = 0; i < p.size(); ++i)
    for (int c = 0; c < 3; ++c) {
      p.displacement(i, c) = scale * g(rng);
      p.rotation(i, c) = scale * g(rng) / p.radius(i);
      p.velocity(i, c) = scale * g(rng);
      p.angular_velocity(i, c) = scale * g(rng) / p.radius(i);
    }
}

std::vector<PrescribedMotion> grips() {
  PrescribedMotion left, right;
  left.group = BoundaryGroup::kLeftGrip;
  left.velocity = Eigen::Vector3d(-1e-3, 2e-4, 0);
  left.fix_velocity = {true, false, true};
  left.fix_angular_velocity = {true, true, false};
  right.group = BoundaryGroup::kRightGrip;
  right.velocity = Eigen::Vector3d(1e-3, 0, 0);
  right.angular_velocity = Eigen::Vector3d(0, 0, 0.5);
  right.fix_velocity = {true, true, true};
  right.fix_angular_velocity = {true, true, true};
  return {left, right};
}

// max |a - b| / max |b|, the relative difference of two arrays.
double relative_difference(const Vector3Array& a, const Vector3Array& b) {
  const double scale = b.abs().maxCoeff();
  return scale > 0 ? (a - b).abs().maxCoeff() / scale : (a - b).abs().maxCoeff();
}

double state_difference(const Particles& a, const Particles& b) {
  return std::max({relative_difference(a.displacement, b.displacement),
                   relative_difference(a.rotation, b.rotation),
                   relative_difference(a.velocity, b.velocity),
                   relative_difference(a.angular_velocity, b.angular_velocity),
                   relative_difference(a.force, b.force), relative_difference(a.torque, b.torque)});
}

bool bitwise_equal(const Particles& a, const Particles& b) {
  return (a.displacement == b.displacement).all() && (a.rotation == b.rotation).all() &&
         (a.velocity == b.velocity).all() && (a.angular_velocity == b.angular_velocity).all() &&
         (a.force == b.force).all() && (a.torque == b.torque).all();
}

ExplicitSettings settings_for(ExplicitBackend kernel, double damping = 0.7) {
  ExplicitSettings s;
  s.backend = kernel;
  s.local_damping = damping;
  return s;
}

struct Run {
  Model model;
  CycleReport report;
};

// `cycles` cycles of `model` (grips moving) with the given kernel, in chunks of `chunk`.
Run run(Model model, ExplicitBackend kernel, long cycles, long chunk, double damping = 0.7) {
  ExplicitIntegrator integrator(model, settings_for(kernel, damping));
  integrator.set_prescribed_motions(grips());
  Run r;
  for (long done = 0; done < cycles; done += chunk) r.report = integrator.advance(chunk);
  r.model = std::move(model);
  return r;
}

void check_reports_close(const CycleReport& a, const CycleReport& b, double tolerance) {
  CHECK(a.strain_energy == doctest::Approx(b.strain_energy).epsilon(tolerance));
  CHECK(a.kinetic_energy == doctest::Approx(b.kinetic_energy).epsilon(tolerance));
  CHECK(a.unbalanced_force_ratio == doctest::Approx(b.unbalanced_force_ratio).epsilon(tolerance));
}

using plydem::test::Threads;

}  // namespace

TEST_CASE("the fused kernel's forces equal the reference loop's on random models") {
  for (unsigned seed : {1u, 2u, 3u}) {
    Model fast = random_model(seed);
    disturb(fast, 10 + seed, 1e-3);
    Model slow = fast;
    const BondPass pass = compute_bond_forces(slow.particles, slow.bonds);
    ExplicitIntegrator integrator(fast, settings_for(ExplicitBackend::kCpu));
    const CycleReport report = integrator.cycle();
    // After one cycle the model holds the forces the cycle used: those of the initial state.
    CHECK(relative_difference(fast.particles.force, slow.particles.force) < 1e-12);
    CHECK(relative_difference(fast.particles.torque, slow.particles.torque) < 1e-12);
    CHECK(report.strain_energy == doctest::Approx(pass.strain_energy).epsilon(1e-12));
    CHECK(report.strain_energy > 0);
  }
}

TEST_CASE("advance(n) on the fused kernel equals n reference cycles") {
  SUBCASE("random models, damped, with prescribed motions") {
    for (unsigned seed : {4u, 5u}) {
      Model m = random_model(seed, 90);
      disturb(m, 20 + seed, 1e-3);
      const Run slow = run(m, ExplicitBackend::kReference, 60, 1);
      const Run fast = run(m, ExplicitBackend::kCpu, 60, 20);
      CHECK(state_difference(fast.model.particles, slow.model.particles) < 1e-12);
      check_reports_close(fast.report, slow.report, 1e-12);
      CHECK(slow.report.kinetic_energy > 0);
    }
  }
  SUBCASE("the Hex2D lattice, undamped, over a thousand cycles") {
    // A lattice's bond normals and levers differ only in their last bits; the gather lists merge
    // them to within 1e-12 (contacts/bond_kernel.cpp), hence the looser tolerance here.
    Model m = hex_coupon();
    disturb(m, 7, 1e-9);
    const Run slow = run(m, ExplicitBackend::kReference, 1000, 1, 0.0);
    const Run fast = run(m, ExplicitBackend::kCpu, 1000, 250, 0.0);
    CHECK(state_difference(fast.model.particles, slow.model.particles) < 1e-9);
    check_reports_close(fast.report, slow.report, 1e-9);
  }
}

TEST_CASE("cycle() reports every cycle as advance(1) does, and advance(n) ends in the same state") {
  Model m = random_model(6, 80);
  disturb(m, 31, 1e-3);
  const Run by_cycle = run(m, ExplicitBackend::kCpu, 30, 1);
  const Run at_once = run(m, ExplicitBackend::kCpu, 30, 30);
  CHECK(bitwise_equal(by_cycle.model.particles, at_once.model.particles));
  CHECK(by_cycle.report.strain_energy == at_once.report.strain_energy);
  CHECK(by_cycle.report.unbalanced_force_ratio == at_once.report.unbalanced_force_ratio);
  Model copy = m;
  ExplicitIntegrator integrator(copy, ExplicitSettings{});
  CHECK_THROWS_AS(integrator.advance(0), Error);
}

TEST_CASE("a serial run is bitwise reproducible") {
  Threads one(1);
  Model m = hex_coupon();
  disturb(m, 8, 1e-9);
  const Run a = run(m, ExplicitBackend::kCpu, 300, 100);
  const Run b = run(m, ExplicitBackend::kCpu, 300, 100);
  CHECK(bitwise_equal(a.model.particles, b.model.particles));
  CHECK(a.report.strain_energy == b.report.strain_energy);
  CHECK(a.report.kinetic_energy == b.report.kinetic_energy);
}

TEST_CASE("one and two threads give the same result") {
  // Large enough to be split (the kernel keeps small models on one thread).
  Model m = hex_coupon(2.4e-3, 0.8e-3);
  REQUIRE(m.particles.size() > 700);
  disturb(m, 9, 1e-9);
  Run one, two;
  {
    Threads t(1);
    one = run(m, ExplicitBackend::kCpu, 200, 50);
  }
  {
    Threads t(2);
    two = run(m, ExplicitBackend::kCpu, 200, 50);
  }
  // Each particle sums its own bonds in a fixed order and the report sums blocks in block order,
  // so the split cannot change a bit; the tolerance is what the kernel promises.
  CHECK(state_difference(one.model.particles, two.model.particles) < 1e-13);
  CHECK(bitwise_equal(one.model.particles, two.model.particles));
  check_reports_close(one.report, two.report, 1e-13);
}

TEST_CASE("renumbering the particles permutes the results and changes nothing else") {
  Model m = random_model(12, 70);
  disturb(m, 40, 1e-3);
  std::vector<int> shuffle(m.particles.size());
  std::iota(shuffle.begin(), shuffle.end(), 0);
  std::shuffle(shuffle.begin(), shuffle.end(), std::mt19937(5));
  for (const std::vector<int>& order :
       {shuffle, space_filling_curve_order(m.particles.reference_position)}) {
    Model renumbered = m;
    renumber(renumbered, order);
    renumbered.check_consistency();
    // The same bonds between the same particles.
    std::set<std::pair<int, int>> before, after;
    for (int b = 0; b < m.bonds.size(); ++b) {
      before.insert({m.bonds.first(b), m.bonds.second(b)});
      after.insert({order[renumbered.bonds.first(b)], order[renumbered.bonds.second(b)]});
    }
    CHECK(before == after);
    for (int k = 0; k < m.particles.size(); ++k) {
      CHECK(renumbered.particles.group(k) == m.particles.group(order[k]));
      CHECK(renumbered.particles.mass(k) == m.particles.mass(order[k]));
    }
    for (ExplicitBackend kernel : {ExplicitBackend::kCpu, ExplicitBackend::kReference}) {
      const Run original = run(m, kernel, 40, 10);
      const Run permuted = run(renumbered, kernel, 40, 10);
      // The original run's state in the new numbering.
      Particles back = original.model.particles;
      for (auto [dst, src] :
           {std::pair(&back.displacement, &original.model.particles.displacement),
            std::pair(&back.rotation, &original.model.particles.rotation),
            std::pair(&back.velocity, &original.model.particles.velocity),
            std::pair(&back.angular_velocity, &original.model.particles.angular_velocity),
            std::pair(&back.force, &original.model.particles.force),
            std::pair(&back.torque, &original.model.particles.torque)}) {
        for (int k = 0; k < m.particles.size(); ++k) dst->row(k) = src->row(order[k]);
      }
      CHECK(state_difference(permuted.model.particles, back) < 1e-12);
      check_reports_close(permuted.report, original.report, 1e-12);
    }
  }
}

TEST_CASE("the Hilbert curve steps between neighbouring grid points") {
  // On a 2^k grid a Hilbert curve visits every point once, each step to an adjacent point.
  for (int dims : {2, 3}) {
    const int side = dims == 2 ? 32 : 8;
    const int count = dims == 2 ? side * side : side * side * side;
    Vector3Array grid = Vector3Array::Zero(count, 3);
    for (int i = 0; i < count; ++i) {
      grid(i, 0) = 0.5 * (i % side);
      grid(i, 1) = 0.5 * ((i / side) % side);
      if (dims == 3) grid(i, 2) = 0.5 * (i / (side * side));
    }
    // Shuffle, so that the order cannot come from the input order.
    std::vector<int> shuffle(count);
    std::iota(shuffle.begin(), shuffle.end(), 0);
    std::shuffle(shuffle.begin(), shuffle.end(), std::mt19937(dims));
    Vector3Array shuffled(count, 3);
    for (int i = 0; i < count; ++i) shuffled.row(i) = grid.row(shuffle[i]);
    const std::vector<int> order = space_filling_curve_order(shuffled);
    check_permutation(order, count);
    int unit_steps = 0;
    for (int k = 1; k < count; ++k) {
      const double step = (shuffled.row(order[k]) - shuffled.row(order[k - 1])).matrix().norm();
      unit_steps += std::abs(step - 0.5) < 1e-12 ? 1 : 0;
    }
    CHECK(unit_steps == count - 1);
  }
}

TEST_CASE("a particle ordering that is not a permutation is refused") {
  Model m = random_model(13, 10);
  CHECK_THROWS_WITH_AS(renumber(m, {0, 1, 2}), doctest::Contains("lists 3 particles"), Error);
  CHECK_THROWS_WITH_AS(renumber(m, {0, 1, 2, 3, 4, 5, 6, 7, 8, 8}), doctest::Contains("twice"),
                       Error);
  CHECK_THROWS_WITH_AS(renumber(m, {0, 1, 2, 3, 4, 5, 6, 7, 8, 10}),
                       doctest::Contains("does not exist"), Error);
}

TEST_CASE("gather lists: a lattice gets one slot per direction and a few bond types") {
  // The count completion of the edges: a few weights (edge equilibrium, the default, gives every
  // bond in its edge strips a weight, and a half-bond type, of its own).
  CouponSpec spec;
  spec.material = load_material("eglass-my750");
  spec.ply_angle = 0.3;
  spec.length = 0.6e-3;
  spec.width = 0.4e-3;
  Hex2dStrategy counted;
  counted.set_option("edge_equilibrium", 0);
  const Model lattice = counted.build(spec).model;
  const std::vector<int> order = space_filling_curve_order(lattice.particles.reference_position);
  const GatherBonds g(lattice.bonds, order);
  CHECK(g.lattice_slots());
  CHECK(g.width() == 6);
  // 6 directions, with the stiffness of edge bonds completed (strategies/boundary_cells.hpp): a few
  // dozen distinct half-bonds, not one per bond end.
  CHECK(g.type_count() < 100);
  CHECK(g.padded_count() % lanes::kCount == 0);
  // Every bond end is in the lists, once.
  int ends = 0;
  for (int s = 0; s < g.width(); ++s)
    for (int k = 0; k < g.particle_count(); ++k) ends += g.types(s)[k] != 0 ? 1 : 0;
  CHECK(ends == 2 * lattice.bonds.size());

  const Model cloud = random_model(14);
  std::vector<int> identity(cloud.particles.size());
  std::iota(identity.begin(), identity.end(), 0);
  const GatherBonds h(cloud.bonds, identity);
  CHECK_FALSE(h.lattice_slots());
  std::vector<int> degree(cloud.particles.size(), 0);
  for (int b = 0; b < cloud.bonds.size(); ++b) {
    ++degree[cloud.bonds.first(b)];
    ++degree[cloud.bonds.second(b)];
  }
  CHECK(h.width() == *std::max_element(degree.begin(), degree.end()));
  CHECK(h.type_count() == 2 * cloud.bonds.size() + 1);
}
