// The parallel bond and the kernel that loops over bonds: hand-derived two-particle answers,
// rigid-body invariance, action = reaction, and the stiffness matrix the solvers use.
#include <doctest/doctest.h>

#include <algorithm>
#include <numeric>
#include <random>

#include "contacts/bond_kernel.hpp"
#include "core/error.hpp"
#include "core/model.hpp"
#include "solvers/explicit_integrator.hpp"

using namespace plydem;

namespace {

// Two spheres of radius r touching along `direction`, bonded with the given stiffnesses.
Model two_particles(const Eigen::Vector3d& direction, double r, double kn, double ks, double kb,
                    double kt) {
  Model m;
  m.particles.resize(2);
  m.particles.reference_position.row(1) = (2 * r * direction.normalized()).transpose().array();
  m.particles.radius.setConstant(r);
  m.particles.mass.setConstant(1.0);
  m.particles.moment_of_inertia.setConstant(1.0);
  m.bonds.resize(1);
  m.bonds.first(0) = 0;
  m.bonds.second(0) = 1;
  m.bonds.normal_stiffness(0) = kn;
  m.bonds.shear_stiffness(0) = ks;
  m.bonds.bending_stiffness(0) = kb;
  m.bonds.twisting_stiffness(0) = kt;
  set_bond_geometry(m.particles, m.bonds, 0);
  return m;
}

Eigen::Vector3d row(const Vector3Array& a, int i) {
  return a.row(i).matrix().transpose();
}

// A small random 3D cloud with bonds between near neighbours and random stiffnesses.
Model random_model(unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Model m;
  const int n = 30;
  m.particles.resize(n);
  for (int i = 0; i < n; ++i) {
    m.particles.reference_position.row(i) << 3 * u(rng), 3 * u(rng), 3 * u(rng);
    m.particles.radius(i) = 0.2 + 0.2 * u(rng);
  }
  m.particles.mass.setConstant(1.0);
  m.particles.moment_of_inertia.setConstant(0.1);
  std::vector<std::pair<int, int>> pairs;
  for (int i = 0; i < n; ++i)
    for (int j = i + 1; j < n; ++j)
      if ((m.particles.reference_position.row(i) - m.particles.reference_position.row(j))
              .matrix()
              .norm() < 1.2)
        pairs.push_back({i, j});
  m.bonds.resize(static_cast<int>(pairs.size()));
  for (int b = 0; b < m.bonds.size(); ++b) {
    m.bonds.first(b) = pairs[b].first;
    m.bonds.second(b) = pairs[b].second;
    m.bonds.normal_stiffness(b) = 1 + u(rng);
    m.bonds.shear_stiffness(b) = u(rng);
    m.bonds.bending_stiffness(b) = 0.1 * u(rng);
    m.bonds.twisting_stiffness(b) = 0.1 * u(rng);
    set_bond_geometry(m.particles, m.bonds, b);
  }
  return m;
}

}  // namespace

TEST_CASE("two particles: normal stretch gives k_n * stretch along the branch") {
  Model m = two_particles({1, 0, 0}, 0.5, 100.0, 10.0, 1.0, 2.0);
  m.particles.displacement(1, 0) = 1e-3;
  compute_bond_forces(m.particles, m.bonds);
  CHECK(m.particles.force(1, 0) == doctest::Approx(-0.1).epsilon(1e-14));
  CHECK(m.particles.force(0, 0) == doctest::Approx(0.1).epsilon(1e-14));
  CHECK(row(m.particles.torque, 0).norm() == doctest::Approx(0.0));
  CHECK(row(m.particles.torque, 1).norm() == doctest::Approx(0.0));
}

TEST_CASE(
    "two particles: shear slip gives k_s * slip and the moment of that force about each centre") {
  // Particle 1 at (1, 0, 0), radius 0.5: contact point at (0.5, 0, 0). Slide particle 1 by +d in y.
  const double d = 2e-3, ks = 10.0;
  Model m = two_particles({1, 0, 0}, 0.5, 100.0, ks, 1.0, 2.0);
  m.particles.displacement(1, 1) = d;
  compute_bond_forces(m.particles, m.bonds);
  // Force on 1: -ks d in y; on 0: +ks d. Moment about each centre of a force at the contact point:
  // for 0, r = (0.5,0,0) x (0, ks d, 0) = +0.5 ks d in z; for 1, r = (-0.5,0,0) x (0,-ks d,0) =
  // +0.5 ks d.
  CHECK(m.particles.force(1, 1) == doctest::Approx(-ks * d));
  CHECK(m.particles.force(0, 1) == doctest::Approx(ks * d));
  CHECK(m.particles.torque(0, 2) == doctest::Approx(0.5 * ks * d));
  CHECK(m.particles.torque(1, 2) == doctest::Approx(0.5 * ks * d));
}

TEST_CASE("two particles: rotating one particle shears the contact and bends the bond") {
  // theta_z on particle 0 moves its contact point (0.5,0,0) by theta x r = (0, 0.5 theta, 0):
  // relative slip -0.5 theta in y, so force on 0 is -ks*0.5*theta... and the bending moment -kb
  // theta.
  const double th = 1e-3, ks = 10.0, kb = 3.0, kt = 7.0;
  Model m = two_particles({1, 0, 0}, 0.5, 100.0, ks, kb, kt);
  m.particles.rotation(0, 2) = th;
  compute_bond_forces(m.particles, m.bonds);
  const double slip = -0.5 * th;  // du_y = u_j - (u_i + theta x r_i)
  CHECK(m.particles.force(0, 1) == doctest::Approx(ks * slip));
  // Moment on 0: r_i x F + M with M = kb * (theta_j - theta_i) = -kb th (bending about z).
  CHECK(m.particles.torque(0, 2) == doctest::Approx(0.5 * ks * slip - kb * th));
  CHECK(m.particles.torque(1, 2) == doctest::Approx(0.5 * ks * slip + kb * th));
  // Twisting about the branch: theta_x on particle 1.
  Model t = two_particles({1, 0, 0}, 0.5, 100.0, ks, kb, kt);
  t.particles.rotation(1, 0) = th;
  compute_bond_forces(t.particles, t.bonds);
  CHECK(t.particles.torque(1, 0) == doctest::Approx(-kt * th));
  CHECK(t.particles.torque(0, 0) == doctest::Approx(kt * th));
  CHECK(row(t.particles.force, 0).norm() == doctest::Approx(0.0));
}

TEST_CASE("rigid translation and infinitesimal rigid rotation load no bond") {
  Model m = random_model(7);
  const Eigen::Vector3d shift(0.3, -0.2, 0.1);
  const Eigen::Vector3d omega(1e-4, -2e-4, 3e-4);
  for (int i = 0; i < m.particles.size(); ++i) {
    const Eigen::Vector3d x = row(m.particles.reference_position, i);
    m.particles.displacement.row(i) = (shift + omega.cross(x)).transpose().array();
    m.particles.rotation.row(i) = omega.transpose().array();
  }
  const BondPass pass = compute_bond_forces(m.particles, m.bonds);
  CHECK(pass.strain_energy == doctest::Approx(0.0).epsilon(1e-30));
  CHECK(m.particles.force.matrix().norm() < 1e-14);
  CHECK(m.particles.torque.matrix().norm() < 1e-14);
}

TEST_CASE("action equals reaction: bond forces and moments sum to zero") {
  Model m = random_model(11);
  std::mt19937 rng(3);
  std::normal_distribution<double> g(0.0, 1e-3);
  for (int i = 0; i < m.particles.size(); ++i)
    for (int c = 0; c < 3; ++c) {
      m.particles.displacement(i, c) = g(rng);
      m.particles.rotation(i, c) = g(rng);
    }
  compute_bond_forces(m.particles, m.bonds);
  Eigen::Vector3d total_force = Eigen::Vector3d::Zero(), total_moment = Eigen::Vector3d::Zero();
  for (int i = 0; i < m.particles.size(); ++i) {
    // Small-displacement kernel: moments are taken about the reference centres.
    total_force += row(m.particles.force, i);
    total_moment += row(m.particles.reference_position, i).cross(row(m.particles.force, i)) +
                    row(m.particles.torque, i);
  }
  const double scale = m.particles.force.matrix().norm();
  CHECK(scale > 0);
  CHECK(total_force.norm() < 1e-13 * scale);
  CHECK(total_moment.norm() < 1e-13 * scale);
}

TEST_CASE("the bond stiffness matrix is the kernel's exact linearization") {
  Model m = random_model(5);
  std::mt19937 rng(9);
  std::normal_distribution<double> g(0.0, 1.0);
  for (int b = 0; b < m.bonds.size(); ++b) {
    Eigen::Matrix<double, 12, 1> q;
    for (int k = 0; k < 12; ++k) q(k) = g(rng);
    const BondParameters p = bond_parameters(m.bonds, b);
    const BondResponse r = parallel_bond_response(p, q.segment<3>(0), q.segment<3>(3),
                                                  q.segment<3>(6), q.segment<3>(9));
    Eigen::Matrix<double, 12, 1> generalized;
    generalized << r.force_on_first, r.torque_on_first, -r.force_on_first, r.torque_on_second;
    const Matrix12d k = parallel_bond_stiffness(p);
    CHECK((k * q + generalized).norm() < 1e-12 * (1 + generalized.norm()));
    CHECK(0.5 * q.dot(k * q) == doctest::Approx(r.energy).epsilon(1e-12));
    CHECK((k - k.transpose()).norm() < 1e-12 * k.norm());
  }
}

// Dropping bonds from the gather table (GatherBonds::drop_bond, ExplicitIntegrator::drop_bond):
// the forces equal those of a model without the bonds.
namespace {

// A simple cubic lattice, spacing 1 and radius 1/2, so that every normal, lever and length is
// exact and all bonds share one set of stiffnesses: the gather table's types are exact, and the
// blocks of 8 particles along x share their types and neighbour runs (the fast paths).
Model cubic_lattice(int nx, int ny, int nz) {
  Model m;
  const int n = nx * ny * nz;
  m.particles.resize(n);
  auto index = [&](int x, int y, int z) { return (z * ny + y) * nx + x; };
  for (int z = 0; z < nz; ++z)
    for (int y = 0; y < ny; ++y)
      for (int x = 0; x < nx; ++x) m.particles.reference_position.row(index(x, y, z)) << x, y, z;
  m.particles.radius.setConstant(0.5);
  m.particles.mass.setConstant(1.0);
  m.particles.moment_of_inertia.setConstant(0.1);
  std::vector<std::pair<int, int>> pairs;
  for (int z = 0; z < nz; ++z)
    for (int y = 0; y < ny; ++y)
      for (int x = 0; x < nx; ++x) {
        if (x + 1 < nx) pairs.push_back({index(x, y, z), index(x + 1, y, z)});
        if (y + 1 < ny) pairs.push_back({index(x, y, z), index(x, y + 1, z)});
        if (z + 1 < nz) pairs.push_back({index(x, y, z), index(x, y, z + 1)});
      }
  m.bonds.resize(static_cast<int>(pairs.size()));
  for (int b = 0; b < m.bonds.size(); ++b) {
    m.bonds.first(b) = pairs[b].first;
    m.bonds.second(b) = pairs[b].second;
    m.bonds.normal_stiffness(b) = 1e6;
    m.bonds.shear_stiffness(b) = 3e5;
    m.bonds.bending_stiffness(b) = 2;
    m.bonds.twisting_stiffness(b) = 1;
    set_bond_geometry(m.particles, m.bonds, b);
  }
  m.check_consistency();
  return m;
}

void disturb(Particles& p, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0.0, 1e-4);
  for (int i = 0; i < p.size(); ++i)
    for (int c = 0; c < 3; ++c) {
      p.displacement(i, c) = g(rng);
      p.rotation(i, c) = g(rng);
    }
}

// The bond forces and moments through the gather table, in model order.
void gather_forces(const GatherBonds& g, const std::vector<int>& order, const Particles& p,
                   Vector3Array& force, Vector3Array& torque) {
  const int n = p.size(), padded = g.padded_count();
  lanes::Array u[3], t[3];
  GatherState state;
  for (int c = 0; c < 3; ++c) {
    u[c] = lanes::Array(padded);
    t[c] = lanes::Array(padded);
    for (int k = 0; k < n; ++k) {
      u[c][k] = p.displacement(order[k], c);
      t[c][k] = p.rotation(order[k], c);
    }
    state.displacement[c] = u[c].data();
    state.rotation[c] = t[c].data();
  }
  force.setZero(n, 3);
  torque.setZero(n, 3);
  for (int first = 0; first < padded; first += lanes::kCount) {
    lanes::Doubles f[3] = {}, m[3] = {}, energy = {}, force_norm = {};
    gather_bond_block<false>(g, first, state, f, m, energy, force_norm);
    for (int l = 0; l < lanes::kCount && first + l < n; ++l)
      for (int c = 0; c < 3; ++c) {
        force(order[first + l], c) = f[c][l];
        torque(order[first + l], c) = m[c][l];
      }
  }
}

double relative_difference(const Vector3Array& a, const Vector3Array& b) {
  return (a - b).abs().maxCoeff() / b.abs().maxCoeff();
}

// The slot of kernel particle `own` that holds its bond to `other`, or -1.
int slot_of(const GatherBonds& g, int own, int other) {
  for (int s = 0; s < g.width(); ++s)
    if (g.types(s)[own] != 0 && g.neighbours(s)[own] == other) return s;
  return -1;
}

int block_type(const GatherBonds& g, int own, int other) {
  return g.block_types(own / lanes::kCount)[slot_of(g, own, other)];
}

int bond_between(const Bonds& b, int i, int j) {
  for (int k = 0; k < b.size(); ++k)
    if ((b.first(k) == i && b.second(k) == j) || (b.first(k) == j && b.second(k) == i)) return k;
  return -1;
}

// The model's bonds less the listed ones.
Bonds without(const Bonds& bonds, const std::vector<int>& dropped) {
  std::vector<int> kept;
  for (int b = 0; b < bonds.size(); ++b)
    if (std::find(dropped.begin(), dropped.end(), b) == dropped.end()) kept.push_back(b);
  return bonds.select(kept);
}

}  // namespace

TEST_CASE("dropping bonds from the gather table gives the forces of a model without them") {
  constexpr int nx = 16, ny = 3, nz = 2;
  Model m = cubic_lattice(nx, ny, nz);
  disturb(m.particles, 3);
  auto at = [&](int x, int y, int z) { return (z * ny + y) * nx + x; };
  std::vector<int> order(m.particles.size());
  std::iota(order.begin(), order.end(), 0);  // kernel index = model index
  GatherBonds g(m.bonds, order);
  REQUIRE(g.lattice_slots());
  REQUIRE(g.width() == 6);

  // Bonds whose both ends sit in uniform blocks with consecutive neighbours (the fast path), a
  // second one in a block the first drop made mixed, one in a block that is mixed from the start
  // (x = 15 has no +x bond), and all eight +z bonds of one block (its slot becomes empty).
  const std::pair<int, int> uniform{at(3, 0, 0), at(3, 1, 0)};
  REQUIRE(block_type(g, uniform.first, uniform.second) > 0);
  REQUIRE(block_type(g, uniform.second, uniform.first) > 0);
  REQUIRE(g.block_runs(0)[slot_of(g, uniform.first, uniform.second)] >= 0);
  const std::pair<int, int> mixed{at(14, 1, 1), at(15, 1, 1)};
  REQUIRE(block_type(g, mixed.first, mixed.second) == -1);
  std::vector<std::pair<int, int>> drops = {uniform, {at(5, 0, 0), at(5, 1, 0)}, mixed};
  for (int x = 8; x < 16; ++x) drops.push_back({at(x, 2, 0), at(x, 2, 1)});
  const int z_slot = slot_of(g, at(8, 2, 0), at(8, 2, 1));
  const int z_block = at(8, 2, 0) / lanes::kCount;
  REQUIRE(g.block_types(z_block)[z_slot] > 0);

  std::vector<int> dropped;
  for (const auto& [i, j] : drops) {
    dropped.push_back(bond_between(m.bonds, i, j));
    g.drop_bond(i, j);
    CHECK(slot_of(g, i, j) == -1);
    CHECK(slot_of(g, j, i) == -1);
  }
  CHECK(block_type(g, at(4, 0, 0), at(4, 1, 0)) == -1);  // uniform before, mixed now
  CHECK(g.block_types(z_block)[z_slot] == 0);            // no bond left in the slot
  CHECK(g.block_runs(z_block)[z_slot] == at(8, 2, 0));   // every slot points to itself

  Model reduced = m;
  reduced.bonds = without(m.bonds, dropped);
  REQUIRE(reduced.bonds.size() == m.bonds.size() - static_cast<int>(drops.size()));
  compute_bond_forces(reduced.particles, reduced.bonds);
  Vector3Array force, torque;
  gather_forces(g, order, m.particles, force, torque);
  CHECK(relative_difference(force, reduced.particles.force) < 1e-14);
  CHECK(relative_difference(torque, reduced.particles.torque) < 1e-14);
  // A table built without the bonds has the same slots: the same forces to the bit.
  const GatherBonds rebuilt(reduced.bonds, order);
  REQUIRE(rebuilt.lattice_slots());
  Vector3Array force_rebuilt, torque_rebuilt;
  gather_forces(rebuilt, order, m.particles, force_rebuilt, torque_rebuilt);
  CHECK((force == force_rebuilt).all());
  CHECK((torque == torque_rebuilt).all());

  // A dropped bond is gone: dropping it again, or a pair that was never bonded, is refused.
  CHECK_THROWS_AS(g.drop_bond(uniform.first, uniform.second), Error);
  CHECK_THROWS_AS(g.drop_bond(at(0, 0, 0), at(2, 0, 0)), Error);
  CHECK_THROWS_AS(g.drop_bond(0, m.particles.size()), Error);
}

TEST_CASE("dropping bonds from an irregular packing's gather table") {
  Model m = random_model(11);
  disturb(m.particles, 5);
  std::vector<int> order(m.particles.size());
  std::iota(order.begin(), order.end(), 0);
  std::reverse(order.begin(), order.end());  // kernel numbering differs from the model's
  std::vector<int> kernel_index(order.size());
  for (std::size_t k = 0; k < order.size(); ++k) kernel_index[order[k]] = static_cast<int>(k);
  GatherBonds g(m.bonds, order);
  REQUIRE(!g.lattice_slots());
  const std::vector<int> dropped = {0, 7, 8, m.bonds.size() / 2, m.bonds.size() - 1};
  for (int b : dropped)
    g.drop_bond(kernel_index[m.bonds.first(b)], kernel_index[m.bonds.second(b)]);
  Model reduced = m;
  reduced.bonds = without(m.bonds, dropped);
  compute_bond_forces(reduced.particles, reduced.bonds);
  Vector3Array force, torque;
  gather_forces(g, order, m.particles, force, torque);
  CHECK(relative_difference(force, reduced.particles.force) < 1e-14);
  CHECK(relative_difference(torque, reduced.particles.torque) < 1e-14);
}

TEST_CASE("the integrator breaks bonds by hand in both kernels alike") {
  Model base = cubic_lattice(16, 3, 2);
  disturb(base.particles, 8);
  ExplicitSettings settings;
  settings.time_step = 0.5 * critical_time_step(base);
  settings.local_damping = 0;
  Model fused_model = base, reference_model = base, reduced = base;
  settings.backend = ExplicitBackend::kCpu;
  ExplicitIntegrator fused(fused_model, settings);
  settings.backend = ExplicitBackend::kReference;
  ExplicitIntegrator reference(reference_model, settings);
  CHECK(!fused.breaking());
  fused.advance(20);
  reference.advance(20);
  const std::vector<int> broken = {5, 40, 41, base.bonds.size() - 1};
  for (int b : broken) {
    fused.break_bond(b);
    reference.break_bond(b, BondState::kBrokenShear);
  }
  CHECK(fused.breaking());  // the first break switched it to the breaking kernel
  // The rows stay, broken, with no stiffness; the table kept no slot for them.
  CHECK(fused_model.bonds.size() == base.bonds.size());
  for (int b : broken) {
    CHECK(fused_model.bonds.state(b) == static_cast<int>(BondState::kBrokenTension));
    CHECK(reference_model.bonds.state(b) == static_cast<int>(BondState::kBrokenShear));
    CHECK(fused_model.bonds.normal_stiffness(b) == 0);
    CHECK(!fused.bond_ends(b)[0].holds);
    CHECK(!fused.bond_ends(b)[1].holds);
  }
  CHECK(fused.bond_ends(6)[0].holds);
  CHECK(fused.breaks().empty());  // a hand break is not the failure law's
  CHECK_THROWS_AS(fused.break_bond(fused_model.bonds.size()), Error);
  CHECK_THROWS_AS(fused.break_bond(5), Error);  // broken already
  CHECK_THROWS_AS(fused.break_bond(6, BondState::kIntact), Error);
  fused.advance(30);
  reference.advance(30);
  const Particles& a = fused_model.particles;
  const Particles& b = reference_model.particles;
  CHECK(relative_difference(a.displacement, b.displacement) < 1e-12);
  CHECK(relative_difference(a.rotation, b.rotation) < 1e-12);
  CHECK(relative_difference(a.force, b.force) < 1e-12);
  // Broken before the first cycle: the run of a model built with the bonds broken.
  Model breaking = base;
  settings.backend = ExplicitBackend::kCpu;
  ExplicitIntegrator early(breaking, settings);
  for (int k : broken) early.break_bond(k);
  for (int k : broken) {
    reduced.bonds.state(k) = static_cast<int>(BondState::kBrokenTension);
    reduced.bonds.damage(k) = 1;
    reduced.bonds.normal_stiffness(k) = reduced.bonds.shear_stiffness(k) = 0;
    reduced.bonds.bending_stiffness(k) = reduced.bonds.twisting_stiffness(k) = 0;
  }
  settings.backend = ExplicitBackend::kReference;
  settings.time_step = early.time_step();  // the built-broken model's own bound is the intact one
  ExplicitIntegrator never(reduced, settings);
  early.advance(30);
  never.advance(30);
  CHECK(relative_difference(breaking.particles.displacement, reduced.particles.displacement) <
        1e-12);
  CHECK(relative_difference(breaking.particles.force, reduced.particles.force) < 1e-12);
}
