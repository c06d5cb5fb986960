// The linear solvers behind the static solve (solvers/linear_solver.hpp): CHOLMOD and the
// hand-written supernodal Cholesky give the same solutions on a ply and a laminate, the same
// mechanism diagnosis, the same tension-test moduli; one factorization serves many right-hand
// sides exactly as fresh solves do (StaticSystem, the specimen stiffness' three solves); unknown
// solver names are clear errors.
#include <doctest/doctest.h>

#include <numbers>
#include <random>
#include <string>

#include "core/error.hpp"
#include "core/material.hpp"
#include "experiments/protocols/stiffness_test.hpp"
#include "experiments/protocols/tension_test.hpp"
#include "solvers/linear_solver.hpp"
#include "solvers/static_solver.hpp"
#include "strategies/hex2d.hpp"
#include "strategies/laminate.hpp"
#include "support/coupon_fixtures.hpp"

using namespace plydem;
using plydem::test::contains;
using plydem::test::error_message;

namespace {

constexpr double kDiameter = 0.05e-3;

CouponSpec small_spec(double angle) {
  CouponSpec spec;
  spec.material = load_material("eglass-my750");
  spec.ply_angle = angle;
  spec.length = 0.8e-3;
  spec.width = 0.4e-3;
  return spec;
}

Model small_coupon(double angle = 0.3) {
  return Hex2dStrategy().build(small_spec(angle)).model;
}

Model small_laminate() {
  const double pi = std::numbers::pi;
  return build_laminate(Hex2dStrategy(), {small_spec(0), {0.0, pi / 4, -pi / 4, pi / 2}, {}}).model;
}

// The tension test's static grips (free): ends within two diameters pulled apart along x, held
// in z and against tilting; the remaining rigid modes are pinned.
DofConstraints grips(const Model& m, double travel) {
  const Particles& p = m.particles;
  const double x_min = p.reference_position.col(0).minCoeff();
  const double x_max = p.reference_position.col(0).maxCoeff();
  DofConstraints c(p.size());
  for (int i = 0; i < p.size(); ++i) {
    const double x = p.reference_position(i, 0);
    const bool left = x <= x_min + 2 * kDiameter, right = x >= x_max - 2 * kDiameter;
    if (!left && !right) continue;
    c.fix(i, Dof::kUx, right ? travel : -travel);
    c.fix(i, Dof::kUz);
    c.fix(i, Dof::kThetaX);
    c.fix(i, Dof::kThetaY);
  }
  return c;
}

StaticSettings with(LinearSolverKind kind) {
  StaticSettings s;
  s.method = StaticMethod::kDirect;
  s.linear_solver = kind;
  s.pin_rigid_modes = true;
  return s;
}

DofArray state_of(const Particles& p) {
  DofArray s(p.size(), kDofsPerParticle);
  s << p.displacement, p.rotation;
  return s;
}

// max |a - b| over the translations and over the rotations, each relative to b's largest.
double relative_difference(const DofArray& a, const DofArray& b) {
  const double u =
      (a.leftCols(3) - b.leftCols(3)).abs().maxCoeff() / b.leftCols(3).abs().maxCoeff();
  const double t =
      (a.rightCols(3) - b.rightCols(3)).abs().maxCoeff() / b.rightCols(3).abs().maxCoeff();
  return std::max(u, t);
}

}  // namespace

TEST_CASE("names: auto, direct and cholmod parse; petsc and unknown names are clear errors") {
  for (LinearSolverKind kind :
       {LinearSolverKind::kAuto, LinearSolverKind::kDirect, LinearSolverKind::kCholmod})
    CHECK(parse_linear_solver(linear_solver_name(kind)) == kind);
  const std::string petsc = error_message([] { parse_linear_solver("petsc"); });
  CHECK(contains(petsc, "PETSc is not built into plydem yet"));
  const std::string unknown = error_message([] { parse_linear_solver("umfpack"); });
  CHECK(contains(unknown, "unknown linear solver 'umfpack'"));
  CHECK(contains(unknown, "auto, direct or cholmod"));
}

TEST_CASE("both factorizations solve a random sparse SPD system for several right-hand sides") {
  const int n = 400;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  std::uniform_int_distribution<int> pick(0, n - 1);
  std::vector<Eigen::Triplet<double>> t;
  Eigen::VectorXd diagonal = Eigen::VectorXd::Constant(n, 1.0);
  for (int k = 0; k < 4 * n; ++k) {
    const int i = pick(rng), j = pick(rng);
    if (i == j) continue;
    const double v = u(rng);
    t.emplace_back(std::max(i, j), std::min(i, j), v);
    diagonal(i) += std::abs(v);
    diagonal(j) += std::abs(v);
  }
  for (int i = 0; i < n; ++i) t.emplace_back(i, i, diagonal(i));
  Eigen::SparseMatrix<double> lower(n, n);
  lower.setFromTriplets(t.begin(), t.end());
  lower.makeCompressed();
  const Eigen::SparseMatrix<double> symmetric = lower.selfadjointView<Eigen::Lower>();
  const Eigen::MatrixXd full(symmetric);
  const Eigen::MatrixXd b = Eigen::MatrixXd::Random(n, 4);
  const Eigen::MatrixXd exact = full.llt().solve(b);
  for (LinearSolverKind kind :
       {LinearSolverKind::kDirect, LinearSolverKind::kCholmod, LinearSolverKind::kAuto}) {
    CAPTURE(linear_solver_name(kind));
    const std::unique_ptr<LinearSolver> solver = make_linear_solver(kind);
    solver->factor(lower, 1e-12);
    CHECK(solver->zero_pivots().empty());
    CHECK(solver->factor_entries() >= lower.nonZeros());
    Eigen::MatrixXd x = b;
    solver->solve_in_place(x);
    CHECK((x - exact).norm() / exact.norm() < 1e-12);
    // One column at a time from the same factor: the same as all at once.
    for (int c = 0; c < b.cols(); ++c) {
      Eigen::VectorXd y = b.col(c);
      solver->solve_in_place(y);
      CHECK((y - x.col(c)).norm() <= 1e-14 * x.col(c).norm());
    }
  }
}

TEST_CASE("CHOLMOD and the hand-written Cholesky agree to 1e-10 on a ply and a laminate") {
  for (const bool laminate : {false, true}) {
    CAPTURE(laminate);
    const Model built = laminate ? small_laminate() : small_coupon();
    const DofConstraints c = grips(built, 0.4e-6);
    Model direct = built, cholmod = built;
    const StaticResult rd = solve_static(direct, c, with(LinearSolverKind::kDirect));
    const StaticResult rc = solve_static(cholmod, c, with(LinearSolverKind::kCholmod));
    MESSAGE(rd.method_name, " vs ", rc.method_name, ", ", rd.free_dofs, " free dofs");
    CHECK(contains(rd.method_name, "supernodal Cholesky"));
    CHECK(contains(rc.method_name, "CHOLMOD"));
    CHECK(rc.free_dofs == rd.free_dofs);
    CHECK(relative_difference(state_of(cholmod.particles), state_of(direct.particles)) < 1e-10);
    CHECK(rc.strain_energy == doctest::Approx(rd.strain_energy).epsilon(1e-10));
    const double reaction = rd.reaction.abs().maxCoeff();
    CHECK((rc.reaction - rd.reaction).abs().maxCoeff() < 1e-10 * reaction);
    CHECK(rc.relative_residual < 1e-10);
    // kAuto (the default) keeps the hand-written solver where the factor fills in little, as in
    // these small coupons: the very same factorization.
    Model automatic = built;
    const StaticResult ra = solve_static(automatic, c, with(LinearSolverKind::kAuto));
    CHECK(ra.method_name == rd.method_name);
    CHECK((state_of(automatic.particles) == state_of(direct.particles)).all());
  }
}

TEST_CASE("a mechanism is refused with the same zero pivots by either solver") {
  // A chain without bending springs (see test_static_solver): 8 zero pivots.
  Model m;
  Particles& p = m.particles;
  p.resize(5);
  for (int i = 0; i < 5; ++i) p.reference_position(i, 0) = i * kDiameter;
  p.radius.setConstant(0.5 * kDiameter);
  p.mass.setConstant(1e-9);
  p.moment_of_inertia.setConstant(1e-19);
  p.volume.setConstant(1e-12);
  m.bonds.resize(4);
  for (int b = 0; b < 4; ++b) {
    m.bonds.first(b) = b;
    m.bonds.second(b) = b + 1;
    m.bonds.normal_stiffness(b) = 1e6;
    m.bonds.shear_stiffness(b) = 1e5;
    m.bonds.bending_stiffness(b) = 0;
    m.bonds.twisting_stiffness(b) = 1e-4;
    set_bond_geometry(p, m.bonds, b);
  }
  DofConstraints c(5);
  c.fix_particle(0);
  c.fix(4, Dof::kUx, 1e-7);
  for (LinearSolverKind kind : {LinearSolverKind::kDirect, LinearSolverKind::kCholmod}) {
    CAPTURE(linear_solver_name(kind));
    const std::string error = error_message([&] { solve_static(m, c, with(kind)); });
    CHECK(contains(error, "8 zero pivots"));
    CHECK(contains(error, "mechanism"));
  }
}

TEST_CASE("a factorization reused for several prescribed values equals fresh solves") {
  for (LinearSolverKind kind : {LinearSolverKind::kDirect, LinearSolverKind::kCholmod}) {
    CAPTURE(linear_solver_name(kind));
    const Model built = small_coupon(0.5);
    const DofConstraints pattern = grips(built, 0.0);
    const StaticSystem system(built, pattern, with(kind));
    CHECK(system.factorizations() == 1);
    for (int k = 1; k <= 3; ++k) {
      // Different travels and a lateral shift of the right grip: other values, same dofs.
      DofConstraints c = grips(built, 0.2e-6 * k);
      for (int i = 0; i < built.particles.size(); ++i)
        if (c.fixed(i, 0) && c.value(i, 0) > 0) c.value(i, 2) = 0.05e-6 * k;
      Model reused = built, fresh = built;
      const StaticResult r = system.solve(reused, c.value);
      const StaticResult f = solve_static(fresh, c, with(kind));
      CHECK(r.reused_factorization == (k > 1));
      CHECK(!f.reused_factorization);
      CHECK(relative_difference(state_of(reused.particles), state_of(fresh.particles)) < 1e-13);
      CHECK((r.reaction - f.reaction).abs().maxCoeff() <= 1e-12 * f.reaction.abs().maxCoeff());
    }
    CHECK(system.factorizations() == 1);
    CHECK(system.solves() == 3);
    // Values on dofs the system does not prescribe are ignored; non-finite ones are refused.
    DofArray bad = DofArray::Zero(built.particles.size(), kDofsPerParticle);
    bad(0, 0) = std::nan("");
    Model m = built;
    if (pattern.fixed(0, 0))
      CHECK(contains(error_message([&] { system.solve(m, bad); }), "not finite"));
    CHECK(contains(error_message([&] { system.solve(m, DofArray::Zero(3, 6)); }), "are for 3"));
  }
}

TEST_CASE("the specimen stiffness factors once for its three solves, by either solver") {
  const Model built = small_coupon(0.3);
  const SpecimenStiffness direct = measure_specimen_stiffness(built, 0, LinearSolverKind::kDirect);
  const SpecimenStiffness cholmod =
      measure_specimen_stiffness(built, 0, LinearSolverKind::kCholmod);
  CHECK(direct.factorizations == 1);
  CHECK(direct.solves == 3);
  CHECK(cholmod.factorizations == 1);
  CHECK(cholmod.solves == 3);
  CHECK((cholmod.stiffness - direct.stiffness).norm() < 1e-10 * direct.stiffness.norm());
}

TEST_CASE("the tension test's moduli with CHOLMOD equal the hand-written solver's to 1e-9") {
  TensionSettings settings;
  settings.coupon = small_spec(0);
  settings.coupon.length = 1.2e-3;
  settings.layup = {0.0, std::numbers::pi / 2};
  settings.linear_solver = LinearSolverKind::kDirect;
  const TensionResult direct = TensionTest(settings).run();
  settings.linear_solver = LinearSolverKind::kCholmod;
  const TensionResult cholmod = TensionTest(settings).run();
  auto same = [](double a, double b) { return std::abs(a - b) <= 1e-9 * std::abs(b); };
  CHECK(same(cholmod.dem.Ex, direct.dem.Ex));
  CHECK(same(cholmod.dem.Ey, direct.dem.Ey));
  CHECK(same(cholmod.dem.nu_xy, direct.dem.nu_xy));
  CHECK(same(cholmod.dem.Gxy, direct.dem.Gxy));
  CHECK(direct.specimen.factorizations == 1);
  CHECK(direct.specimen.solves == 3);
}
