// The parallel bond and the kernel that loops over bonds: hand-derived two-particle answers,
// rigid-body invariance, action = reaction, and the stiffness matrix the solvers use.
#include <doctest/doctest.h>

#include <random>

#include "contacts/bond_kernel.hpp"
#include "core/model.hpp"

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
