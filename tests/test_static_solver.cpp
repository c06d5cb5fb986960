// The implicit static solver: closed-form answers for one bond and a chain, the affine patch test
// of a hexagonal layer, equilibrium under the explicit kernel's own forces, the clear errors for
// floating particles, free rigid-body modes, mechanisms and negative springs, and direct vs CG.
#include <doctest/doctest.h>

#include <cmath>
#include <iomanip>
#include <random>
#include <string>

#include "contacts/bond_kernel.hpp"
#include "core/error.hpp"
#include "core/material.hpp"
#include "core/measurements.hpp"
#include "solvers/static_solver.hpp"
#include "strategies/hex2d.hpp"

using namespace plydem;

namespace {

constexpr double kDiameter = 0.05e-3;

// A chain of touching particles along x, one bond per neighbour pair with its own stiffnesses.
Model chain(int n, const std::vector<double>& kn, double ks, double kb, double kt) {
  Model m;
  Particles& p = m.particles;
  p.resize(n);
  for (int i = 0; i < n; ++i) p.reference_position(i, 0) = i * kDiameter;
  p.radius.setConstant(0.5 * kDiameter);
  p.mass.setConstant(1e-9);
  p.moment_of_inertia.setConstant(1e-19);
  p.volume.setConstant(1e-12);
  m.bonds.resize(n - 1);
  for (int b = 0; b < n - 1; ++b) {
    m.bonds.first(b) = b;
    m.bonds.second(b) = b + 1;
    m.bonds.normal_stiffness(b) = kn[b];
    m.bonds.shear_stiffness(b) = ks;
    m.bonds.bending_stiffness(b) = kb;
    m.bonds.twisting_stiffness(b) = kt;
    set_bond_geometry(p, m.bonds, b);
  }
  m.check_consistency();
  return m;
}

Model small_coupon(double angle = 0.3, bool complete_boundary_cells = true) {
  CouponSpec spec;
  spec.material = load_material("eglass-my750");
  spec.ply_angle = angle;
  spec.length = 0.6e-3;
  spec.width = 0.4e-3;
  spec.complete_boundary_cells = complete_boundary_cells;
  return Hex2dStrategy().build(spec).model;
}

// Particles within two diameters of each end go to the grip groups, as in the tension test.
void mark_grips(Particles& p) {
  const double x_min = p.reference_position.col(0).minCoeff();
  const double x_max = p.reference_position.col(0).maxCoeff();
  for (int i = 0; i < p.size(); ++i) {
    const double x = p.reference_position(i, 0);
    p.group(i) = static_cast<int>(x <= x_min + 2 * kDiameter   ? BoundaryGroup::kLeftGrip
                                  : x >= x_max - 2 * kDiameter ? BoundaryGroup::kRightGrip
                                                               : BoundaryGroup::kFree);
  }
}

// Every dof of the group's particles at a random value (displacements ~1 um, rotations ~1 mrad).
void fix_group_randomly(const Particles& p, BoundaryGroup group, DofConstraints& c, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0.0, 1.0);
  for (int i = 0; i < p.size(); ++i) {
    if (p.group(i) != static_cast<int>(group)) continue;
    c.fix_particle(i, 1e-6 * Eigen::Vector3d(g(rng), g(rng), g(rng)),
                   1e-3 * Eigen::Vector3d(g(rng), g(rng), g(rng)));
  }
}

std::string message_of(Model& m, const DofConstraints& c, const StaticSettings& s = {}) {
  try {
    solve_static(m, c, s);
  } catch (const Error& e) {
    return e.what();
  }
  return "(no error)";
}

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

// Largest |force| and |torque| on free and on prescribed particles after a solve.
struct Balance {
  double free_force = 0, free_torque = 0, reaction_force = 0, reaction_torque = 0;
};

Balance balance(const Particles& p, const DofConstraints& c, const StaticResult& r) {
  Balance b;
  for (int i = 0; i < p.size(); ++i)
    for (int k = 0; k < 3; ++k) {
      if (!c.fixed(i, k)) b.free_force = std::max(b.free_force, std::abs(p.force(i, k)));
      if (!c.fixed(i, 3 + k)) b.free_torque = std::max(b.free_torque, std::abs(p.torque(i, k)));
      b.reaction_force = std::max(b.reaction_force, std::abs(r.reaction(i, k)));
      b.reaction_torque = std::max(b.reaction_torque, std::abs(r.reaction(i, 3 + k)));
    }
  return b;
}

// Stacks displacements (first 3 columns) and rotations (last 3) of a model's state.
DofArray state_of(const Particles& p) {
  DofArray s(p.size(), kDofsPerParticle);
  s << p.displacement, p.rotation;
  return s;
}

}  // namespace

TEST_CASE("one bond pulled along its axis: the reaction is k_n d") {
  const double kn = 2e6, ks = 7e5, kb = 3e-4, kt = 1e-4, d = 1.3e-7;
  Model m = chain(2, {kn}, ks, kb, kt);
  DofConstraints c(2);
  c.fix_particle(0);
  c.fix(1, Dof::kUx, d);
  const StaticResult r = solve_static(m, c);
  CHECK(r.method == StaticMethod::kDirect);
  CHECK(r.free_dofs == 5);
  CHECK(r.reaction(1, 0) == doctest::Approx(kn * d).epsilon(1e-13));
  CHECK(r.reaction(0, 0) == doctest::Approx(-kn * d).epsilon(1e-13));
  CHECK(m.particles.displacement(1, 0) == d);
  CHECK(std::abs(m.particles.displacement(1, 1)) < 1e-25);
  CHECK(std::abs(m.particles.rotation(1, 2)) < 1e-20);
  CHECK(m.particles.force(1, 0) == doctest::Approx(-kn * d).epsilon(1e-13));
  CHECK(r.strain_energy == doctest::Approx(0.5 * kn * d * d).epsilon(1e-12));
}

TEST_CASE("one bond sheared sideways with its rotation free: shear and bending springs in series") {
  // Particle 0 clamped, particle 1 moved by d along y, its other dofs free. With lever s (contact
  // point to centre of particle 1) the contact displacement is du_y = d - s theta_z and the energy
  //   E = 1/2 k_s (d - s theta_z)^2 + 1/2 k_b theta_z^2,
  // minimal at theta_z = k_s s d / (k_s s^2 + k_b). The bond force is then
  //   F = k_s (d - s theta_z) = d / (1/k_s + s^2/k_b):
  // the shear spring and the bending spring seen through the lever s act in series. Particle 1
  // is balanced in rotation (s F = k_b theta_z), so the clamp takes -F and the moment -L F.
  const double kn = 2e6, ks = 7e5, kb = 3e-4, kt = 1e-4, d = 1.3e-7;
  Model m = chain(2, {kn}, ks, kb, kt);
  const double s = m.bonds.lever_second(0), length = m.bonds.length(0);
  DofConstraints c(2);
  c.fix_particle(0);
  c.fix(1, Dof::kUy, d);
  const StaticResult r = solve_static(m, c);
  const double force = d / (1 / ks + s * s / kb);
  const double theta = ks * s * d / (ks * s * s + kb);
  CHECK(r.reaction(1, 1) == doctest::Approx(force).epsilon(1e-12));
  CHECK(m.particles.rotation(1, 2) == doctest::Approx(theta).epsilon(1e-12));
  CHECK(r.reaction(0, 1) == doctest::Approx(-force).epsilon(1e-12));
  CHECK(r.reaction(0, 5) == doctest::Approx(-length * force).epsilon(1e-12));
  CHECK(std::abs(m.particles.displacement(1, 0)) < 1e-25);
  CHECK(std::abs(m.particles.displacement(1, 2)) < 1e-25);
  CHECK(r.strain_energy == doctest::Approx(0.5 * force * d).epsilon(1e-12));
  // Without the bending spring's help (k_b -> infinity) the shear spring alone would give k_s d.
  CHECK(force < ks * d);
}

TEST_CASE("a chain of unequal normal springs: series stiffness, piecewise uniform strain") {
  // Transverse displacements held at zero, rotations free (they stay zero: nothing turns them):
  // only the normal springs work, the chain carries one force F = d / sum(1/k_n) and bond b
  // stretches by F / k_n,b.
  const int n = 6;
  const std::vector<double> kn = {1e6, 2e6, 5e5, 3e6, 1.5e6};
  Model m = chain(n, kn, 1e3, 1e-6, 1e-6);
  const double d = 2e-7;
  DofConstraints c(n);
  c.fix_particle(0);
  for (int i = 1; i < n; ++i) {
    c.fix(i, Dof::kUy);
    c.fix(i, Dof::kUz);
  }
  c.fix(n - 1, Dof::kUx, d);
  const StaticResult r = solve_static(m, c);
  double compliance = 0;
  for (double k : kn) compliance += 1 / k;
  const double force = d / compliance;
  CHECK(r.reaction(n - 1, 0) == doctest::Approx(force).epsilon(1e-12));
  CHECK(r.reaction(0, 0) == doctest::Approx(-force).epsilon(1e-12));
  double u = 0;
  for (int i = 1; i < n; ++i) {
    u += force / kn[i - 1];
    CHECK(m.particles.displacement(i, 0) == doctest::Approx(u).epsilon(1e-12));
    CHECK(m.particles.rotation.row(i).abs().maxCoeff() < 1e-18);
    CHECK(std::abs(r.reaction(i, 1)) < 1e-12 * force);
  }
}

TEST_CASE("patch test: a hexagonal layer with an affine boundary deforms affinely inside") {
  // All bonds of a family are equal (no boundary-cell completion) and the layer at 0 deg is
  // mirror-symmetric about x and y, so a uniform in-plane stretch is an exact equilibrium of every
  // particle with six neighbours, with no spin.
  Model m = small_coupon(0.0, false);
  Particles& p = m.particles;
  std::vector<int> bonds_of(p.size(), 0);
  for (int b = 0; b < m.bonds.size(); ++b) {
    ++bonds_of[m.bonds.first(b)];
    ++bonds_of[m.bonds.second(b)];
  }
  const double exx = 1e-3, eyy = -4e-4;
  DofConstraints c(p.size());
  int inside = 0;
  for (int i = 0; i < p.size(); ++i) {
    c.fix(i, Dof::kUz);
    c.fix(i, Dof::kThetaX);
    c.fix(i, Dof::kThetaY);
    if (bonds_of[i] < 6) {
      c.fix(i, Dof::kUx, exx * p.reference_position(i, 0));
      c.fix(i, Dof::kUy, eyy * p.reference_position(i, 1));
      c.fix(i, Dof::kThetaZ);
    } else {
      ++inside;
    }
  }
  REQUIRE(inside > 20);
  solve_static(m, c);
  const double scale = exx * p.reference_position.col(0).abs().maxCoeff();
  for (int i = 0; i < p.size(); ++i) {
    CHECK(std::abs(p.displacement(i, 0) - exx * p.reference_position(i, 0)) < 1e-11 * scale);
    CHECK(std::abs(p.displacement(i, 1) - eyy * p.reference_position(i, 1)) < 1e-11 * scale);
    CHECK(std::abs(p.rotation(i, 2)) < 1e-11 * exx);
  }
}

TEST_CASE("the assembled stiffness is the kernel's: K q = -(force, torque) for any state") {
  Model m = small_coupon();
  Particles& p = m.particles;
  std::mt19937 rng(7);
  std::normal_distribution<double> g(0.0, 1.0);
  Eigen::VectorXd q(kDofsPerParticle * p.size());
  for (int i = 0; i < p.size(); ++i)
    for (int c = 0; c < 3; ++c) {
      p.displacement(i, c) = q(6 * i + c) = 1e-6 * g(rng);
      p.rotation(i, c) = q(6 * i + 3 + c) = 1e-3 * g(rng);
    }
  const Eigen::SparseMatrix<double> k = assemble_stiffness(m);
  CHECK((Eigen::SparseMatrix<double>(k.transpose()) - k).norm() == 0);
  const double energy = compute_bond_forces(p, m.bonds).strain_energy;
  const Eigen::VectorXd kq = k * q;
  double force_error = 0, torque_error = 0, force_scale = 0, torque_scale = 0;
  for (int i = 0; i < p.size(); ++i)
    for (int c = 0; c < 3; ++c) {
      force_error = std::max(force_error, std::abs(kq(6 * i + c) + p.force(i, c)));
      torque_error = std::max(torque_error, std::abs(kq(6 * i + 3 + c) + p.torque(i, c)));
      force_scale = std::max(force_scale, std::abs(p.force(i, c)));
      torque_scale = std::max(torque_scale, std::abs(p.torque(i, c)));
    }
  CHECK(force_error < 1e-12 * force_scale);
  CHECK(torque_error < 1e-12 * torque_scale);
  CHECK(0.5 * q.dot(kq) == doctest::Approx(energy).epsilon(1e-12));
}

TEST_CASE("the static solution is an equilibrium of the explicit kernel") {
  Model m = small_coupon();
  Particles& p = m.particles;
  mark_grips(p);
  DofConstraints c(p.size());
  fix_group_randomly(p, BoundaryGroup::kLeftGrip, c, 11);
  const StaticResult r = solve_static(m, c);
  CHECK(r.pinned.empty());  // a fully held grip removes every rigid-body mode
  CHECK(r.free_dofs + r.prescribed_dofs == 6 * p.size());
  CHECK(r.relative_residual < 1e-12);
  const Balance b = balance(p, c, r);
  MESSAGE("unbalanced/reaction: force " << b.free_force / b.reaction_force << ", torque "
                                        << b.free_torque / b.reaction_torque);
  CHECK(b.free_force < 1e-9 * b.reaction_force);
  CHECK(b.free_torque < 1e-9 * b.reaction_torque);
  for (int i = 0; i < p.size(); ++i)
    for (int k = 0; k < 3; ++k) {
      if (c.fixed(i, k)) CHECK(p.force(i, k) == doctest::Approx(-r.reaction(i, k)));
      if (c.fixed(i, k)) CHECK(p.displacement(i, k) == c.value(i, k));
    }
  // Prescribed displacements do work on the supports only: W = 1/2 u_p . r = strain energy.
  const DofArray u = state_of(p);
  CHECK(0.5 * (u * r.reaction).sum() == doctest::Approx(r.strain_energy).epsilon(1e-10));
}

TEST_CASE("direct LDL^T and conjugate gradient agree") {
  Model m = small_coupon();
  mark_grips(m.particles);
  DofConstraints c(m.particles.size());
  fix_group_randomly(m.particles, BoundaryGroup::kLeftGrip, c, 21);
  fix_group_randomly(m.particles, BoundaryGroup::kRightGrip, c, 22);
  StaticSettings direct;
  direct.method = StaticMethod::kDirect;
  const StaticResult rd = solve_static(m, c, direct);
  const DofArray ud = state_of(m.particles);
  CHECK(rd.iterations == 0);

  for (StaticPreconditioner pc :
       {StaticPreconditioner::kIncompleteCholesky, StaticPreconditioner::kDiagonal}) {
    Model mi = small_coupon();
    mark_grips(mi.particles);
    StaticSettings iterative;
    iterative.method = StaticMethod::kIterative;
    iterative.preconditioner = pc;
    const StaticResult ri = solve_static(mi, c, iterative);
    CHECK(ri.method == StaticMethod::kIterative);
    CHECK(ri.iterations > 0);
    const DofArray ui = state_of(mi.particles);
    MESSAGE(ri.method_name << ": " << ri.iterations << " iterations");
    CHECK((ui.leftCols(3) - ud.leftCols(3)).matrix().norm() <
          1e-8 * ud.leftCols(3).matrix().norm());
    CHECK((ui.rightCols(3) - ud.rightCols(3)).matrix().norm() <
          1e-8 * ud.rightCols(3).matrix().norm());
    CHECK((ri.reaction - rd.reaction).matrix().norm() < 1e-8 * rd.reaction.matrix().norm());

    // Warm start: solving again from the solution takes (almost) no iterations.
    const StaticResult again = solve_static(mi, c, iterative);
    CHECK(again.iterations <= 1);
  }

  // kAuto picks CG above the threshold: PETSc's where it is built, Eigen's otherwise.
  StaticSettings automatic;
  automatic.direct_max_dofs = 10;
  Model fresh = small_coupon();
  mark_grips(fresh.particles);
  const StaticResult large = solve_static(fresh, c, automatic);
  if (petsc_available()) {
    CHECK(contains(large.method_name, "PETSc"));
    CHECK(large.iterations > 0);
    // PETSc's CG starts from the model's state too: from the solution, (almost) no iterations.
    CHECK(solve_static(m, c, automatic).iterations <= 1);
  } else {
    CHECK(large.method == StaticMethod::kIterative);
  }
  automatic.linear_solver_use = LinearSolverUse::kManySolves;  // no PETSc for the events solver
  CHECK(solve_static(m, c, automatic).method == StaticMethod::kIterative);
}

TEST_CASE("grips that prescribe only ux leave rigid modes: a clear error, or pinned at no cost") {
  Model m = small_coupon();
  Particles& p = m.particles;
  mark_grips(p);
  DofConstraints c(p.size());
  c.fix_group(p, BoundaryGroup::kLeftGrip, Dof::kUx, 0.0);
  c.fix_group(p, BoundaryGroup::kRightGrip, Dof::kUx, 5e-7);

  const std::string error = message_of(m, c);
  MESSAGE(error);
  CHECK(contains(error, "rigid-body modes free"));
  for (const char* mode :
       {"translation y", "translation z", "rotation about x", "rotation about y"})
    CHECK(contains(error, mode));
  CHECK(!contains(error, "translation x"));
  CHECK(contains(error, "pin_rigid_modes"));
  CHECK(p.displacement.abs().maxCoeff() == 0);  // a refused solve leaves the model alone
  CHECK(rigid_mode_pins(m, DofConstraints(p.size())).size() == 6);

  // The helper adds one dof per free mode: one uy (nearest the centroid) and three uz.
  const std::vector<PinnedDof> pins = rigid_mode_pins(m, c);
  REQUIRE(pins.size() == 4);
  int uy = 0, uz = 0;
  for (const PinnedDof& pin : pins) {
    uy += pin.dof == Dof::kUy;
    uz += pin.dof == Dof::kUz;
  }
  CHECK(uy == 1);
  CHECK(uz == 3);

  StaticSettings pinning;
  pinning.pin_rigid_modes = true;
  const StaticResult r = solve_static(m, c, pinning);
  REQUIRE(r.pinned.size() == 4);
  double left = 0, right = 0;
  for (int i = 0; i < p.size(); ++i) {
    if (p.group(i) == static_cast<int>(BoundaryGroup::kLeftGrip)) left += r.reaction(i, 0);
    if (p.group(i) == static_cast<int>(BoundaryGroup::kRightGrip)) right += r.reaction(i, 0);
  }
  CHECK(right > 0);
  CHECK(left == doctest::Approx(-right).epsilon(1e-10));
  // No load acts on the pinned modes, so the pins carry no force.
  for (const PinnedDof& pin : r.pinned)
    CHECK(std::abs(r.reaction(pin.particle, static_cast<int>(pin.dof))) < 1e-10 * right);
  // Out of plane nothing is loaded: the pins hold the layer flat.
  CHECK(p.displacement.col(2).abs().maxCoeff() < 1e-20);

  // Another choice of pins (uy of particle 0, uz of three other particles) changes nothing but a
  // rigid motion: same grip force and energy.
  Model other = small_coupon();
  mark_grips(other.particles);
  DofConstraints c2 = c;
  c2.fix(0, Dof::kUy);
  const int n = p.size();
  c2.fix(1, Dof::kUz);
  c2.fix(n / 2, Dof::kUz);
  c2.fix(n - 1, Dof::kUz);
  const StaticResult r2 = solve_static(other, c2);
  CHECK(r2.pinned.empty());
  CHECK(r2.strain_energy == doctest::Approx(r.strain_energy).epsilon(1e-10));
  CHECK((r2.reaction.col(0) - r.reaction.col(0)).matrix().norm() < 1e-9 * right);
}

TEST_CASE("a particle without bonds is refused: it floats") {
  Model m = chain(3, {1e6, 1e6}, 1e5, 1e-4, 1e-4);
  // Particle 3 far from the chain, with no bond.
  Particles& p = m.particles;
  p.append(p.select({0}));  // particle 1's mass, radius and volume
  const int n = p.size();
  p.group(n - 1) = static_cast<int>(BoundaryGroup::kFree);
  p.reference_position.row(n - 1) << 1e-3, 2e-3, 0;
  DofConstraints c(n);
  c.fix_particle(0);
  c.fix(2, Dof::kUx, 1e-7);
  const std::string error = message_of(m, c);
  CHECK(contains(error, "particle 3 at (1, 2, 0) mm has no bonds: it floats freely"));
  // Held in all six dofs it is harmless: no reaction.
  c.fix_particle(3);
  CHECK(solve_static(m, c).reaction.row(3).abs().maxCoeff() == 0);
}

TEST_CASE("a mechanism is refused with its zero pivots") {
  // Without bending springs, each particle of a chain can turn and slide sideways at no cost
  // (du_y = uy_j - uy_i - s (theta_z,i + theta_z,j) = 0): 4 free particles give one such mode per
  // bond in each transverse plane, 2 x 4 = 8, while the clamped end removes every rigid mode.
  Model m = chain(5, {1e6, 1e6, 1e6, 1e6}, 1e5, 0.0, 1e-4);
  DofConstraints c(5);
  c.fix_particle(0);
  c.fix(4, Dof::kUx, 1e-7);
  const std::string error = message_of(m, c);
  MESSAGE(error);
  CHECK(contains(error, "not restrained"));
  CHECK(contains(error, "8 zero pivots"));
  CHECK(contains(error, "mechanism"));
}

TEST_CASE("a free dof with no stiffness at all is named") {
  // Only normal springs along x: nothing resists uy.
  Model m = chain(3, {1e6, 1e6}, 0.0, 1e-4, 1e-4);
  DofConstraints c(3);
  c.fix_particle(0);
  c.fix(2, Dof::kUx, 1e-7);
  const std::string error = message_of(m, c);
  CHECK(contains(error, "nothing resists uy of particle 1"));
}

TEST_CASE("a negative spring is refused as an unstable calibration") {
  Model m = small_coupon();
  mark_grips(m.particles);
  m.bonds.shear_stiffness(5) = -1e3;
  DofConstraints c(m.particles.size());
  fix_group_randomly(m.particles, BoundaryGroup::kLeftGrip, c, 3);
  const std::string error = message_of(m, c);
  CHECK(contains(error, "bond 5"));
  CHECK(contains(error, "negative shear stiffness"));
  CHECK(contains(error, "unstable calibration"));
}

TEST_CASE("constraints of the wrong size or with NaN are refused") {
  Model m = chain(3, {1e6, 1e6}, 1e5, 1e-4, 1e-4);
  CHECK(contains(message_of(m, DofConstraints(2)), "constraints are for 2 particles"));
  DofConstraints c(3);
  c.fix_particle(0);
  c.fix(2, Dof::kUx, std::nan(""));
  CHECK(contains(message_of(m, c), "ux of particle 2"));
}

TEST_CASE("the paper's 3800-particle coupon in tension: E1 from one solve") {
  CouponSpec spec;
  spec.material = load_material("eglass-my750");
  Model m = Hex2dStrategy().build(spec).model;
  Particles& p = m.particles;
  mark_grips(p);
  const double x_min = p.reference_position.col(0).minCoeff();
  const double x_max = p.reference_position.col(0).maxCoeff();
  const double span = x_max - x_min, strain = 1e-3;
  DofConstraints c(p.size());
  c.fix_group(p, BoundaryGroup::kLeftGrip, Dof::kUx, -0.5 * strain * span);
  c.fix_group(p, BoundaryGroup::kRightGrip, Dof::kUx, 0.5 * strain * span);
  StaticSettings settings;
  settings.pin_rigid_modes = true;  // free grips, as `--grips free`
  const StaticResult r = solve_static(m, c, settings);
  MESSAGE(p.size() << " particles, " << r.free_dofs << " free dofs, " << r.stiffness_nonzeros
                   << " nonzeros, " << r.method_name << ": checks " << r.seconds.checks * 1e3
                   << " ms, assembly " << r.seconds.assembly * 1e3 << " ms, factorization "
                   << r.seconds.factorization * 1e3 << " ms, solve " << r.seconds.solve * 1e3
                   << " ms");
  const Balance b = balance(p, c, r);
  CHECK(b.free_force < 1e-9 * b.reaction_force);

  // E1 measured as the tension test does: gauge strain in the central half, away from the edges.
  const double x_mid = 0.5 * (x_min + x_max), half = 0.25 * span;
  const double y_min = p.reference_position.col(1).minCoeff();
  const double y_max = p.reference_position.col(1).maxCoeff();
  std::vector<int> gauge;
  for (int i : particles_between(p, x_mid - half, x_mid + half)) {
    const double y = p.reference_position(i, 1);
    if (y >= y_min + 2 * kDiameter && y <= y_max - 2 * kDiameter) gauge.push_back(i);
  }
  const GaugeStrain e = fit_gauge_strain(p, gauge);
  double force = 0;
  for (int i = 0; i < p.size(); ++i)
    if (p.group(i) == static_cast<int>(BoundaryGroup::kRightGrip)) force += r.reaction(i, 0);
  const double area = cross_section_area(p, x_mid - half, x_mid + half, 4 * kDiameter);
  const double e1 = force / area / e.exx;
  MESSAGE(std::setprecision(8) << "E1 = " << e1 * 1e-9 << " GPa (CLT " << spec.material.E1 * 1e-9
                               << " GPa), nu12 = " << -e.eyy / e.exx);
  CHECK(std::abs(e1 / spec.material.E1 - 1) < 0.01);
  CHECK(std::abs(-e.eyy / e.exx - spec.material.nu12) < 0.005);

  StaticSettings cg = settings;
  cg.method = StaticMethod::kIterative;
  Model mi = Hex2dStrategy().build(spec).model;
  mark_grips(mi.particles);
  const StaticResult ri = solve_static(mi, c, cg);
  MESSAGE(ri.method_name << ": " << ri.iterations << " iterations, preconditioner "
                         << ri.seconds.factorization * 1e3 << " ms, iterations "
                         << ri.seconds.solve * 1e3 << " ms");
  const DofArray ud = state_of(p), ui = state_of(mi.particles);
  CHECK((ui.leftCols(3) - ud.leftCols(3)).matrix().norm() < 1e-8 * ud.leftCols(3).matrix().norm());
  CHECK((ui.rightCols(3) - ud.rightCols(3)).matrix().norm() <
        1e-8 * ud.rightCols(3).matrix().norm());
}
