// The linear solvers behind the static solve (solvers/linear_solver.hpp): CHOLMOD, PETSc's CG +
// GAMG (where built) and the hand-written supernodal Cholesky give the same solutions on a ply and
// a laminate, the same mechanism diagnosis, the same tension-test moduli; one factorization (or AMG
// hierarchy) serves many right-hand sides exactly as fresh solves do (StaticSystem, the specimen
// stiffness' three solves); PETSc on 2 MPI ranks, each assembling its own rows, gives the
// 1-process answer and refuses a mechanism (its own ctest entry, run with mpiexec -n 2); unknown
// solver names are clear errors.
#include <doctest/doctest.h>
#include <fmt/format.h>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "contacts/bond_opening.hpp"
#include "core/error.hpp"
#include "core/material.hpp"
#include "experiments/protocols/stiffness.hpp"
#include "experiments/protocols/tension.hpp"
#include "solvers/cracks.hpp"
#include "solvers/linear_solver.hpp"
#include "solvers/machine_rates.hpp"
#include "solvers/static_solver.hpp"
#include "strategies/hex2d.hpp"
#include "strategies/laminate.hpp"
#include "support/coupon_fixtures.hpp"
#include "support/test_support.hpp"

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

// The solvers of this build: PETSc where it is built in.
std::vector<LinearSolverKind> every_solver() {
  std::vector<LinearSolverKind> kinds = {LinearSolverKind::kDirect, LinearSolverKind::kCholmod};
  if (petsc_available()) kinds.push_back(LinearSolverKind::kPetsc);
  return kinds;
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

TEST_CASE("names: auto, direct, cholmod and petsc parse; unknown names are clear errors") {
  for (LinearSolverKind kind :
       {LinearSolverKind::kAuto, LinearSolverKind::kDirect, LinearSolverKind::kCholmod})
    CHECK(parse_linear_solver(linear_solver_name(kind)) == kind);
  if (petsc_available()) {
    CHECK(parse_linear_solver("petsc") == LinearSolverKind::kPetsc);
    // Options PETSc cannot use come out as errors of the solve; a later option overrides.
    const Model built = small_coupon();
    const DofConstraints c = grips(built, 0.4e-6);
    Model m = built;
    set_petsc_options("-ksp_type nosuch");
    const std::string bad =
        error_message([&] { solve_static(m, c, with(LinearSolverKind::kPetsc)); });
    CHECK(contains(bad, "PETSc's options (KSPSetFromOptions) failed"));
    set_petsc_options("-ksp_type cg");
    CHECK(solve_static(m, c, with(LinearSolverKind::kPetsc)).iterations > 0);
  } else {
    const std::string petsc = error_message([] { parse_linear_solver("petsc"); });
    CHECK(contains(petsc, "built without PETSc"));
    CHECK(contains(error_message([] { set_petsc_options("-ksp_rtol 1e-9"); }),
                   "built without PETSc"));
    CHECK(contains(error_message([] { make_linear_solver(LinearSolverKind::kPetsc); }),
                   "built without PETSc"));
  }
  const std::string unknown = error_message([] { parse_linear_solver("umfpack"); });
  CHECK(contains(unknown, "unknown linear solver 'umfpack'"));
  CHECK(contains(unknown, "auto, direct, cholmod or petsc"));
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

TEST_CASE("CHOLMOD, PETSc and the hand-written Cholesky agree on a ply and a laminate") {
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
    // PETSc's CG + GAMG (rtol 1e-12 on the scaled system): the same state to 1e-8.
    if (petsc_available()) {
      Model petsc = built;
      const StaticResult rp = solve_static(petsc, c, with(LinearSolverKind::kPetsc));
      MESSAGE(rp.method_name, ": ", rp.iterations, " iterations");
      CHECK(contains(rp.method_name, "PETSc cg + gamg (block size 6, rigid-body near-null"));
      CHECK(rp.iterations > 0);
      CHECK(relative_difference(state_of(petsc.particles), state_of(direct.particles)) < 1e-8);
      CHECK(rp.strain_energy == doctest::Approx(rd.strain_energy).epsilon(1e-10));
      CHECK((rp.reaction - rd.reaction).abs().maxCoeff() < 1e-8 * reaction);
      CHECK(rp.relative_residual < 1e-11);
    }
    // kAuto (the default) keeps the hand-written solver where the factor fills in little, as in
    // these small coupons: the very same factorization.
    Model automatic = built;
    const StaticResult ra = solve_static(automatic, c, with(LinearSolverKind::kAuto));
    CHECK(ra.method_name == rd.method_name);
    CHECK((state_of(automatic.particles) == state_of(direct.particles)).all());
  }
}

TEST_CASE("auto: a direct factor that does not fit goes to PETSc for few solves, else is refused") {
  // The symbolic analysis knows the factor's size before any numeric work; with the available
  // memory set below it (PLYDEM_AVAILABLE_MEMORY, core/machine_memory.hpp), kAuto must not factor.
  const Model built = small_laminate();
  const DofConstraints c = grips(built, 1e-6);
  Model direct = built;
  const StaticResult rd = solve_static(direct, c, with(LinearSolverKind::kDirect));
  const double needed = direct_factor_bytes(rd.factor_entries);
  REQUIRE(needed > 1e5);
  const char* before = std::getenv("PLYDEM_AVAILABLE_MEMORY");
  const std::string saved = before ? before : "";
  setenv("PLYDEM_AVAILABLE_MEMORY", fmt::format("{:.0f}", needed / 2).c_str(), 1);

  StaticSettings many = with(LinearSolverKind::kAuto);
  many.linear_solver_use = LinearSolverUse::kManySolves;  // the events solver's use
  Model m = built;
  const std::string refused = error_message([&] { solve_static(m, c, many); });
  CHECK(contains(refused, "direct factor"));
  CHECK(contains(refused, fmt::format("{:.2f} GB", needed / 1e9)));
  CHECK(contains(refused, "PLYDEM_AVAILABLE_MEMORY"));
  CHECK(contains(refused, "updates a direct factor"));

  Model few = built;
  if (petsc_available()) {
    const StaticResult ra = solve_static(few, c, with(LinearSolverKind::kAuto));
    CHECK(contains(ra.method_name, "PETSc"));
    CHECK(contains(ra.method_name, "a direct factor would need"));
    CHECK(ra.iterations > 0);
    CHECK(relative_difference(state_of(few.particles), state_of(direct.particles)) < 1e-8);
  } else {
    const std::string none =
        error_message([&] { solve_static(few, c, with(LinearSolverKind::kAuto)); });
    CHECK(contains(none, "no iterative linear solver"));
  }
  if (before)
    setenv("PLYDEM_AVAILABLE_MEMORY", saved.c_str(), 1);
  else
    unsetenv("PLYDEM_AVAILABLE_MEMORY");
}

TEST_CASE("auto prices each solver by the machine's rates, the factor and the solves") {
  // The paper's [0/45/-45/90]s coupon (bench/static_solve): 173,251 unknowns, 3.44e6 stored
  // entries, a factor of 1.26e8 entries and 1.9e11 flops in AMD's order on particles; and its 0 deg
  // ply of 3e4 particles.
  AutoProblem laminate;
  laminate.unknowns = 173251;
  laminate.nonzeros = 3.44e6;
  laminate.factor_entries = 1.26e8;
  laminate.factor_flops = 1.9e11;
  AutoProblem ply;
  ply.unknowns = 181981;
  ply.nonzeros = 1.71e6;
  ply.factor_entries = 1.48e7;
  ply.factor_flops = 2.46e9;
  // The development VM with the reference BLAS and with OpenBLAS on its two cores; a machine of
  // many cores with OpenBLAS.
  MachineRates reference, openblas, many_cores;
  reference.eigen_gflops = openblas.eigen_gflops = 13;
  many_cores.eigen_gflops = 20;
  reference.blas_gflops = 5;
  openblas.blas_gflops = 46;
  many_cores.blas_gflops = 1000;
  reference.memory_gbytes = openblas.memory_gbytes = 29;
  many_cores.memory_gbytes = 40;
  for (const MachineRates* rates : {&reference, &openblas}) {
    const AutoPrediction t = predict_linear_solvers(laminate, *rates);
    MESSAGE("laminate: direct ", t.direct, " s, CHOLMOD ", t.cholmod, " s, PETSc ", t.petsc, " s");
    CHECK(t.petsc < t.cholmod);
    CHECK(t.petsc < t.direct);
    // As measured: PETSc 5 s (setup and 57 iterations), the hand-written factor 20 s.
    CHECK(t.petsc == doctest::Approx(5.1).epsilon(0.2));
    CHECK(t.direct == doctest::Approx(20).epsilon(0.2));
    const AutoPrediction p = predict_linear_solvers(ply, *rates);
    CHECK(p.direct < p.cholmod);
    CHECK(p.direct < p.petsc);
  }
  CHECK(predict_linear_solvers(laminate, reference).cholmod >
        3 * predict_linear_solvers(laminate, openblas).cholmod);
  const AutoPrediction fast = predict_linear_solvers(laminate, many_cores);
  CHECK(fast.cholmod < fast.petsc);
  // More solves cost each solver its solves; more ranks divide PETSc's work alone.
  AutoProblem three = laminate, two_ranks = laminate;
  three.solves = 3;
  two_ranks.ranks = 2;
  const AutoPrediction one = predict_linear_solvers(laminate, reference);
  const AutoPrediction more = predict_linear_solvers(three, reference);
  CHECK(more.direct > one.direct);
  CHECK(more.petsc - one.petsc > 4 * (more.direct - one.direct));
  const AutoPrediction shared = predict_linear_solvers(two_ranks, reference);
  CHECK(shared.petsc == doctest::Approx(one.petsc / 2));
  CHECK(shared.direct == one.direct);
}

TEST_CASE("the machine's rates are measured once and read back from the cache") {
  const std::string file = fmt::format("{}/plydem_machine_rates_{}.json",
                                       std::filesystem::temp_directory_path().string(), getpid());
  std::filesystem::remove(file);
  const MachineRates first = machine_rates_from(file);
  CHECK(first.eigen_gflops > 0);
  CHECK(first.blas_gflops > 0);
  CHECK(first.memory_gbytes > 0);
  CHECK(contains(first.source, "measured"));
  CHECK(contains(first.source, "kept in"));
  CHECK(contains(first.key, first.blas));
  const MachineRates again = machine_rates_from(file);
  CHECK(contains(again.source, "cached in"));
  CHECK(again.eigen_gflops == first.eigen_gflops);
  CHECK(again.blas_gflops == first.blas_gflops);
  CHECK(again.memory_gbytes == first.memory_gbytes);
  // A damaged file is measured again, and replaced.
  std::ofstream(file) << "{ not json";
  CHECK(contains(machine_rates_from(file).source, "measured"));
  CHECK(contains(machine_rates_from(file).source, "cached in"));
  std::filesystem::remove(file);
  // No file: measured every time.
  CHECK(machine_rates_from("").source.find("kept") == std::string::npos);
}

TEST_CASE("auto takes the hand-written factor of a small problem and says so") {
  const Model built = small_coupon(0.3);
  const DofConstraints c = grips(built, 1e-6);
  Model m = built;
  const StaticResult r = solve_static(m, c, with(LinearSolverKind::kAuto));
  CHECK(r.factor_flops > 0);
  CHECK(r.factor_flops <= kAutoSmallFactorFlops);
  CHECK(contains(r.linear_solver_choice, "chosen by auto: a small direct factor"));
  CHECK(contains(r.method_name, "supernodal Cholesky"));
  // A solver the caller names is not a choice.
  Model d = built;
  CHECK(solve_static(d, c, with(LinearSolverKind::kDirect)).linear_solver_choice.empty());
}

namespace {

// A chain of five particles without bending springs (see test_static_solver), held at one end
// and pulled at the other: a mechanism with 8 zero pivots.
Model unbent_chain() {
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
  return m;
}

DofConstraints chain_ends() {
  DofConstraints c(5);
  c.fix_particle(0);
  c.fix(4, Dof::kUx, 1e-7);
  return c;
}

}  // namespace

TEST_CASE("a mechanism is refused with the same zero pivots by every solver") {
  Model m = unbent_chain();
  const DofConstraints c = chain_ends();
  CHECK_FALSE(free_motions_are_rigid(m));  // so PETSc probes, and finds it
  for (LinearSolverKind kind : every_solver()) {
    CAPTURE(linear_solver_name(kind));
    const std::string error = error_message([&] { solve_static(m, c, with(kind)); });
    CHECK(contains(error, "8 zero pivots"));
    CHECK(contains(error, "mechanism"));
  }
  // With bending springs every bond resists all six relative motions: a rigid chain.
  m.bonds.bending_stiffness.setConstant(1e-4);
  CHECK(free_motions_are_rigid(m));
  m.bonds.normal_stiffness(2) = 0;
  CHECK_FALSE(free_motions_are_rigid(m));
  // Broken, the middle bond leaves two rigid pieces in one bonded cluster: not rigid.
  m.bonds.normal_stiffness(2) = 1e6;
  open_bond(m.bonds, 2, BondState::kBrokenTension);
  CHECK_FALSE(free_motions_are_rigid(m));
}

TEST_CASE(
    "free motions: plies tied by interface point bonds are one rigid body; single ties are not") {
  // The laminate's interface bonds have no bending or twisting stiffness; hundreds of them tie
  // each pair of plies at non-collinear points, so the laminate moves only rigidly and PETSc need
  // not probe for mechanisms.
  Model m = small_laminate();
  const Bonds& b = m.bonds;
  int point_bonds = 0;
  for (int k = 0; k < b.size(); ++k)
    if (!(b.bending_stiffness(k) > 0 && b.twisting_stiffness(k) > 0)) ++point_bonds;
  REQUIRE(point_bonds > 0);
  CHECK(free_motions_are_rigid(m));
  // A broken bond has no stiffness: where intact bonds still join its particles (the events
  // solver's cracked coupons) the laminate is one rigid body as before, and PETSc skips the probe;
  // a crack through the whole laminate leaves two pieces that only broken bonds join: not rigid.
  Model one_broken = m;
  open_bond(one_broken.bonds, 0, BondState::kBrokenTension);
  CHECK(free_motions_are_rigid(one_broken));
  // The crack through every ply on a plane between two columns of particles near the middle.
  const auto& x = m.particles.reference_position;
  std::vector<double> columns(x.col(0).begin(), x.col(0).end());
  std::sort(columns.begin(), columns.end());
  columns.erase(std::unique(columns.begin(), columns.end(),
                            [](double a, double c) { return std::abs(a - c) < 1e-12; }),
                columns.end());
  REQUIRE(columns.size() > 2);
  const double middle = 0.5 * (columns[columns.size() / 2 - 1] + columns[columns.size() / 2]);
  Model cut_through = m;
  REQUIRE(cut_transverse_crack(cut_through, middle, 0, 3).size() > 1);
  CHECK_FALSE(free_motions_are_rigid(cut_through));
  // Without bending springs in the plies every pair of particles is tied at one point only: the
  // test cannot tell (each particle may spin about its single contacts), so PETSc probes.
  m.bonds.bending_stiffness.setZero();
  CHECK_FALSE(free_motions_are_rigid(m));
}

TEST_CASE("a factorization reused for several prescribed values equals fresh solves") {
  for (LinearSolverKind kind : every_solver()) {
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

TEST_CASE("the specimen stiffness factors once for its three solves, by every solver") {
  const Model built = small_coupon(0.3);
  const SpecimenStiffness direct = measure_specimen_stiffness(built, 0, LinearSolverKind::kDirect);
  CHECK(direct.factorizations == 1);
  CHECK(direct.solves == 3);
  for (LinearSolverKind kind : every_solver()) {
    CAPTURE(linear_solver_name(kind));
    const SpecimenStiffness other = measure_specimen_stiffness(built, 0, kind);
    CHECK(other.factorizations == 1);
    CHECK(other.solves == 3);
    CHECK((other.stiffness - direct.stiffness).norm() < 1e-9 * direct.stiffness.norm());
  }
}

namespace {

// The tension test of a small [0/90] coupon by `kind`.
TensionResult cross_ply_tension(LinearSolverKind kind) {
  TensionSettings settings;
  settings.coupon = small_spec(0);
  settings.coupon.length = 1.2e-3;
  settings.layup = {0.0, std::numbers::pi / 2};
  settings.linear_solver = kind;
  return TensionTest(settings).run();
}

// Ex, Ey, nu_xy and Gxy of `other` equal `reference`'s to `tolerance` (relative).
void check_same_moduli(const TensionResult& other, const TensionResult& reference,
                       double tolerance) {
  auto same = [&](double a, double b) { return std::abs(a - b) <= tolerance * std::abs(b); };
  CHECK(same(other.dem.Ex, reference.dem.Ex));
  CHECK(same(other.dem.Ey, reference.dem.Ey));
  CHECK(same(other.dem.nu_xy, reference.dem.nu_xy));
  CHECK(same(other.dem.Gxy, reference.dem.Gxy));
}

}  // namespace

TEST_CASE("the tension test's moduli with CHOLMOD equal the hand-written solver's to 1e-9") {
  const TensionResult direct = cross_ply_tension(LinearSolverKind::kDirect);
  check_same_moduli(cross_ply_tension(LinearSolverKind::kCholmod), direct, 1e-9);
  CHECK(direct.specimen.factorizations == 1);
  CHECK(direct.specimen.solves == 3);
}

// Its own ctest entry (tests/CMakeLists.txt), run as mpiexec -n 2: each rank builds the same model
// and assembles and hands PETSc the rows of its half of the particles; the gathered solution equals
// the hand-written Cholesky's on one process, and the tension test's moduli equal the 1-process
// direct ones.
TEST_CASE("PETSc on 2 MPI ranks gives the 1-process solution") {
  if (!petsc_available()) {
    plydem::test::skip("this build has no PETSc");
    return;
  }
  const Model built = small_laminate();
  const DofConstraints c = grips(built, 0.4e-6);
  Model direct = built, petsc = built;
  const StaticResult rd = solve_static(direct, c, with(LinearSolverKind::kDirect));
  const StaticResult rp = solve_static(petsc, c, with(LinearSolverKind::kPetsc));
  MESSAGE("rank ", mpi_rank(), " of ", mpi_size(), ": ", rp.method_name, ", assembled ",
          rp.rank_stiffness_nonzeros, " of ", rp.stiffness_nonzeros, " entries");
  CHECK(mpi_size() == 2);
  CHECK(contains(rp.method_name, "2 ranks"));
  CHECK(relative_difference(state_of(petsc.particles), state_of(direct.particles)) < 1e-8);
  // Each rank assembled the rows of its own half of the particles (and the diagonal blocks of
  // all), not the whole matrix; the counts and the residual are the whole system's.
  CHECK(rp.stiffness_nonzeros == rd.stiffness_nonzeros);
  CHECK(rd.rank_stiffness_nonzeros == rd.stiffness_nonzeros);
  CHECK(rp.rank_stiffness_nonzeros < 0.7 * static_cast<double>(rp.stiffness_nonzeros));
  CHECK(rp.relative_residual < 1e-10);

  check_same_moduli(cross_ply_tension(LinearSolverKind::kPetsc),
                    cross_ply_tension(LinearSolverKind::kDirect), 1e-8);
}

// Also run as mpiexec -n 2: a rank holds only its own rows, so PETSc's probe refuses the
// mechanism without naming its dofs, and says where they are named.
TEST_CASE("PETSc on 2 MPI ranks refuses a mechanism and says to name it on one rank") {
  if (!petsc_available()) {
    plydem::test::skip("this build has no PETSc");
    return;
  }
  Model m = unbent_chain();
  const std::string error =
      error_message([&] { solve_static(m, chain_ends(), with(LinearSolverKind::kPetsc)); });
  CHECK(contains(error, "mechanism"));
  CHECK(contains(error, "on one rank"));
}
