// kPetsc (solvers/linear_solver.hpp): PETSc's CG + GAMG with the particles' rigid-body modes as
// near-null space, and the PETSc/MPI session. Compiled only when PETSc is found (CMakeLists.txt);
// linear_solver.cpp reaches it through solvers/petsc_solver.hpp.
//
// The matrix PETSc sees. The static solver hands over the Jacobi-scaled free-free block A (unit
// diagonal) in its own numbering of the free dofs. AMG with block size 6 wants every particle's
// six dofs, so the free dofs go back to their places among all 6n dofs (row = 6 * slot +
// component, the particles' slots sorted along the model's longest extent, so that each rank
// owns a slice of the coupon) and each prescribed dof becomes an identity row and column with a
// zero right-hand side: the same solution on the free dofs, and whole 6 x 6 blocks for the
// aggregation. The near-null space is the six rigid-body modes of the particles' reference
// positions about their centroid, in the scaled unknowns (y = u / s), orthonormalized.
//
// Mechanisms. CG converges on a singular but consistent system (a mechanism the load does not
// excite) without a sign of trouble, so factor() probes the hierarchy once: it solves A x = A r
// for a fixed pseudo-random r, which gives x = r unless A has a null space, where x misses r's
// component in it. Where max |x - r| > kMechanismProbe max |r|, or the probe does not converge,
// the matrix is factored by the hand-written Cholesky, which names the zero pivots as the direct
// solvers do (and solves, should it find none), unless its factor would not fit in memory: then
// the error says so, with the estimate. A matrix the layout calls positive definite by
// construction (UnknownLayout::positive_definite: every bond resists all six relative motions and
// the clusters' rigid modes are prescribed) has no mechanism and skips the probe.
#include "solvers/petsc_solver.hpp"

#include <fmt/format.h>
#include <petscksp.h>

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <numeric>
#include <optional>
#include <utility>
#include <vector>

#include "core/error.hpp"
#include "core/machine_memory.hpp"
#include "core/stopwatch.hpp"
#include "core/units.hpp"
#include "solvers/rank_exchange.hpp"
#include "solvers/sparse_cholesky.hpp"

namespace plydem {
namespace {

// The probe solves to a relative residual of kProbeTolerance (half the iterations of a solve to
// 1e-12) and takes the matrix as singular where max |x - r| > kMechanismProbe max |r|. Measured:
// the probe's error is 1.5e-6 to 6.3e-6 on the test coupons (tests/test_linear_solver.cpp) and
// 1.0e-5 on the [0/45/-45/90]s paper coupon (1.7e5 unknowns), while the mechanism of the tests (a
// chain without bending springs) leaves 0.81: r's component in the null space stays whole.
constexpr double kProbeTolerance = 1e-6;
constexpr double kMechanismProbe = 1e-3;

// A solve longer than this many seconds reports its progress, every as many seconds again.
constexpr double kProgressSeconds = 5;

bool we_initialized = false;  // by ensure_petsc(), finalized at exit
bool session_initialized = false;

void check(PetscErrorCode code, const char* what) {
  if (code == 0) return;
  const char* text = nullptr;
  PetscErrorMessage(code, &text, nullptr);
  throw Error(fmt::format("linear solver: PETSc's {} failed: {}", what, text ? text : "?"));
}

void quiet_errors() {
  // Errors come back as codes (then plydem::Error), not as tracebacks on stderr; PETSc's signal
  // handlers would turn a crash elsewhere into its own message.
  PetscPushErrorHandler(PetscReturnErrorHandler, nullptr);
  PetscPopSignalHandler();
}

void finalize_at_exit() {
  if (we_initialized) PetscFinalize();
}

void ensure_petsc() {
  PetscBool initialized = PETSC_FALSE;
  PetscInitialized(&initialized);
  if (initialized) return;
  check(PetscInitializeNoArguments(), "initialization");
  quiet_errors();
  we_initialized = true;
  std::atexit(finalize_at_exit);
}

// Sets a default into PETSc's options database unless the user's options set it.
void default_option(const char* name, const char* value) {
  PetscBool set = PETSC_FALSE;
  check(PetscOptionsHasName(nullptr, nullptr, name, &set), "options");
  if (!set) check(PetscOptionsSetValue(nullptr, name, value), "options");
}

// Each particle's slot (its block of six rows) is its place along the model's longest extent
// (slots_along_longest_extent), so that a rank's block is a slice across it, whose faces (the
// ghost rows) are the smallest, where the models' own order (ply by ply) would cut through the
// thickness; a rank's slots are its even share (slots_of_rank), the explicit engine's slices too
// (solvers/rank_exchange.hpp).
std::pair<int, int> rank_slots(int items) {
  return slots_of_rank(mpi_rank(), mpi_size(), items);
}

// splitmix64: a pseudo-random value in [-1, 1] of a row, the same on every rank.
double probe_value(std::uint64_t row) {
  std::uint64_t z = row + 0x9e3779b97f4a7c15ULL;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  z ^= z >> 31;
  return 2.0 * static_cast<double>(z >> 11) / static_cast<double>(1ULL << 53) - 1.0;
}

// The progress of one KSPSolve: residuals fall about geometrically, so the time left is the
// decades still to go at the rate of those done.
struct SolveProgress {
  Stopwatch since_start, since_report;
  double first_residual = 0;
  double target = 1e-12;  // relative
  const char* what = "solve";
};

PetscErrorCode report_progress(KSP /*ksp*/, PetscInt iteration, PetscReal residual, void* context) {
  auto& p = *static_cast<SolveProgress*>(context);
  if (iteration == 0) {
    p.first_residual = residual;
    return 0;
  }
  if (p.since_report.seconds() < kProgressSeconds) return 0;
  const double elapsed = p.since_start.seconds();
  p.since_report.restart();
  if (!is_root() || !(p.first_residual > 0)) return 0;
  const double relative = residual / p.first_residual;
  const double done = -std::log10(std::max(relative, 1e-300));
  const double to_go = -std::log10(p.target) - done;
  const std::string left =
      done > 0 && to_go > 0 ? fmt::format(", about {:.0f} s left", elapsed * to_go / done) : "";
  spdlog::info(
      "static solve: PETSc {}, iteration {}, residual {:.2e} of the first (target {:.0e}), "
      "{:.0f} s{}",
      p.what, static_cast<long>(iteration), relative, p.target, elapsed, left);
  return 0;
}

class PetscSolver final : public LinearSolver {
 public:
  PetscSolver() { ensure_petsc(); }
  ~PetscSolver() override { release(); }
  PetscSolver(const PetscSolver&) = delete;
  PetscSolver& operator=(const PetscSolver&) = delete;

  void set_layout(const UnknownLayout& layout) override { layout_ = layout; }

  void factor(const SparseMatrix& lower, double pivot_tolerance) override {
    require(lower.rows() == lower.cols(), "linear solver: the matrix is not square");
    require(lower.isCompressed(), "linear solver: the matrix must be in compressed storage");
    release();
    fallback_.reset();
    n_ = static_cast<int>(lower.rows());
    number_rows();
    assemble(lower);
    set_near_null_space();
    check(KSPCreate(PETSC_COMM_WORLD, &ksp_), "KSPCreate");
    check(KSPSetOperators(ksp_, a_, a_), "KSPSetOperators");
    check(KSPSetType(ksp_, KSPCG), "KSPSetType");
    PC pc = nullptr;
    check(KSPGetPC(ksp_, &pc), "KSPGetPC");
    check(PCSetType(pc, PCGAMG), "PCSetType");
    PetscReal threshold = -1;  // keep every connection in the aggregation graph
    check(PCGAMGSetThreshold(pc, &threshold, 1), "PCGAMGSetThreshold");
    check(KSPSetTolerances(ksp_, kRelativeTolerance, 1e-300, PETSC_DEFAULT, 100000),
          "KSPSetTolerances");
    default_option("-mg_levels_ksp_type", "chebyshev");
    default_option("-mg_levels_pc_type", "jacobi");
    check(KSPSetFromOptions(ksp_), "options (KSPSetFromOptions)");
    check(KSPMonitorSet(ksp_, report_progress, &progress_, nullptr), "KSPMonitorSet");
    const Stopwatch setup_clock;
    check(KSPSetUp(ksp_), "setup of the preconditioner (KSPSetUp)");
    const double setup_seconds = setup_clock.seconds();
    if (setup_seconds > kProgressSeconds && is_root())
      spdlog::info("static solve: PETSc's AMG hierarchy for {} unknowns set up in {:.1f} s", n_,
                   setup_seconds);
    check(MatCreateVecs(a_, &x_, &b_), "MatCreateVecs");
    check(VecScatterCreateToAll(x_, &to_all_, &all_), "VecScatterCreateToAll");
    if (!layout_.positive_definite && probe_finds_null_space()) {
      if (layout_.own_rows_only)
        throw Error(fmt::format(
            "static solve: PETSc's probe finds the stiffness singular (the probe solve missed by "
            "{:.3g} of its size): the free dofs form a mechanism. Naming its dofs needs the whole "
            "matrix on one process, and each of the {} MPI ranks assembled its own rows only: "
            "run the same on one rank (without mpiexec) to have it named",
            probe_error_, mpi_size()));
      // The hand-written Cholesky names the zero pivots, in the order given (the particles' own,
      // with more fill than a fill-reducing one): its symbolic analysis says first whether the
      // factor fits.
      fallback_.emplace();
      fallback_->analyze(lower);
      const double bytes = 8.0 * static_cast<double>(fallback_->factor_entries());
      const MachineMemory memory = machine_memory();
      if (bytes > 0.8 * memory.available) {
        fallback_.reset();
        throw Error(fmt::format(
            "static solve: PETSc's probe finds the stiffness singular (the probe solve missed by "
            "{:.3g} of its size): the free dofs form a mechanism. Naming its dofs needs a direct "
            "factor of {:.1f} GB in this order, more than the {:.1f} GB available ({}); run "
            "--linear-solver cholmod or direct, which order the dofs to fill in less",
            probe_error_, bytes / kBytesPerGB, memory.available / kBytesPerGB, memory.source));
      }
      fallback_->factorize(lower, pivot_tolerance);
    }
  }
  const std::vector<int>& zero_pivots() const override {
    static const std::vector<int> none;
    return fallback_ ? fallback_->zero_pivots() : none;
  }
  Eigen::VectorXd pivots() const override {
    require(fallback_.has_value(), "linear solver: PETSc's CG keeps no pivots");
    return fallback_->pivots();
  }
  void solve_in_place(Eigen::MatrixXd& b) const override {
    if (fallback_) {
      fallback_->solve_in_place(b);
      return;
    }
    require(ksp_ != nullptr && b.rows() == n_,
            "linear solver: solve before factor, or a right-hand side of the wrong size");
    iterations_ = 0;
    for (Eigen::Index c = 0; c < b.cols(); ++c) {
      Eigen::VectorXd column = b.col(c);
      solve_one(column, nullptr);
      b.col(c) = column;
    }
  }
  void solve_from(Eigen::VectorXd& x, const Eigen::VectorXd& b) const override {
    if (fallback_) {
      x = b;
      fallback_->solve_in_place(x);
      return;
    }
    require(ksp_ != nullptr && b.rows() == n_ && x.rows() == n_,
            "linear solver: solve before factor, or a right-hand side of the wrong size");
    iterations_ = 0;
    const Eigen::VectorXd guess = x;
    x = b;
    solve_one(x, &guess);
  }
  int iterations() const override { return iterations_; }
  std::string name() const override {
    if (fallback_) return "supernodal Cholesky (after PETSc's probe found a null space)";
    KSPType ksp = nullptr;
    PCType pc = nullptr;
    PC p = nullptr;
    if (ksp_) {
      KSPGetType(ksp_, &ksp);
      KSPGetPC(ksp_, &p);
      PCGetType(p, &pc);
    }
    return fmt::format("PETSc {} + {} (block size {}{}, {} rank{})", ksp ? ksp : "?", pc ? pc : "?",
                       block_, block_ == 6 ? ", rigid-body near-null space" : "", mpi_size(),
                       mpi_size() > 1 ? "s" : "");
  }
  double factor_entries() const override {
    return fallback_ ? static_cast<double>(fallback_->factor_entries()) : 0.0;
  }

 private:
  static constexpr double kRelativeTolerance = 1e-12;

  // The padded numbering (file comment) and this rank's rows.
  void number_rows() {
    const bool blocks = !layout_.dofs.empty();
    if (blocks) {
      require(static_cast<int>(layout_.dofs.size()) == n_ && layout_.scale.size() == n_,
              "linear solver: the layout does not match the matrix");
    }
    block_ = blocks ? 6 : 1;
    const int items = blocks ? static_cast<int>(layout_.position.rows()) : n_;
    rows_ = block_ * items;
    if (blocks) slot_of_ = slots_along_longest_extent(layout_.position);
    row_of_.resize(n_);
    for (int k = 0; k < n_; ++k)
      row_of_[k] = blocks ? 6 * slot_of_[layout_.dofs[k] / 6] + layout_.dofs[k] % 6 : k;
    const auto [first, end] = rank_slots(items);
    first_ = block_ * first;
    end_ = block_ * end;
  }

  // This rank's rows of the padded symmetric matrix, in compressed rows with global columns.
  void assemble(const SparseMatrix& lower) {
    const int local = end_ - first_;
    std::vector<PetscInt> count(local + 1, 0);
    std::vector<char> free_row(local, 0);
    for (int k = 0; k < n_; ++k)
      if (row_of_[k] >= first_ && row_of_[k] < end_) free_row[row_of_[k] - first_] = 1;
    auto owned = [&](int row) { return row >= first_ && row < end_; };
    for (int j = 0; j < n_; ++j)
      for (SparseMatrix::InnerIterator it(lower, j); it; ++it) {
        const int i = static_cast<int>(it.row());
        if (i < j) continue;
        if (owned(row_of_[i])) ++count[row_of_[i] - first_ + 1];
        if (i != j && owned(row_of_[j])) ++count[row_of_[j] - first_ + 1];
      }
    for (int r = 0; r < local; ++r)
      if (!free_row[r]) ++count[r + 1];  // the identity row of a prescribed dof
    std::partial_sum(count.begin(), count.end(), count.begin());
    std::vector<PetscInt> column(count[local]);
    std::vector<PetscScalar> value(count[local]);
    std::vector<PetscInt> next(count.begin(), count.end() - 1);
    auto put = [&](int row, int col, double v) {
      const PetscInt at = next[row - first_]++;
      column[at] = col;
      value[at] = v;
    };
    for (int j = 0; j < n_; ++j)
      for (SparseMatrix::InnerIterator it(lower, j); it; ++it) {
        const int i = static_cast<int>(it.row());
        if (i < j) continue;
        if (owned(row_of_[i])) put(row_of_[i], row_of_[j], it.value());
        if (i != j && owned(row_of_[j])) put(row_of_[j], row_of_[i], it.value());
      }
    for (int r = 0; r < local; ++r)
      if (!free_row[r]) put(first_ + r, first_ + r, 1.0);
    for (int r = 0; r < local; ++r) {  // PETSc wants each row's columns sorted
      std::vector<std::pair<PetscInt, PetscScalar>> row;
      for (PetscInt at = count[r]; at < count[r + 1]; ++at) row.emplace_back(column[at], value[at]);
      std::sort(row.begin(), row.end());
      for (PetscInt at = count[r]; at < count[r + 1]; ++at)
        std::tie(column[at], value[at]) = row[at - count[r]];
    }
    check(MatCreate(PETSC_COMM_WORLD, &a_), "MatCreate");
    check(MatSetSizes(a_, local, local, rows_, rows_), "MatSetSizes");
    check(MatSetType(a_, MATAIJ), "MatSetType");
    check(MatSetBlockSize(a_, block_), "MatSetBlockSize");
    check(MatSeqAIJSetPreallocationCSR(a_, count.data(), column.data(), value.data()),
          "assembly (MatSeqAIJSetPreallocationCSR)");
    check(MatMPIAIJSetPreallocationCSR(a_, count.data(), column.data(), value.data()),
          "assembly (MatMPIAIJSetPreallocationCSR)");
    check(MatSetOption(a_, MAT_SPD, PETSC_TRUE), "MatSetOption");
  }

  // The six rigid-body modes in the scaled unknowns (file comment); prescribed dofs take the
  // mean scale of their component over the free dofs.
  void set_near_null_space() {
    if (block_ != 6) return;
    const auto& x = layout_.position;
    const int particles = static_cast<int>(x.rows());
    const Eigen::RowVector3d centroid = x.colwise().mean().matrix();
    Eigen::VectorXd mean_scale = Eigen::VectorXd::Zero(6), counted = Eigen::VectorXd::Zero(6);
    for (int k = 0; k < n_; ++k) {
      mean_scale(row_of_[k] % 6) += layout_.scale(k);
      counted(row_of_[k] % 6) += 1;
    }
    for (int c = 0; c < 6; ++c) mean_scale(c) = counted(c) > 0 ? mean_scale(c) / counted(c) : 1.0;
    Eigen::VectorXd scale(rows_);
    for (int r = 0; r < rows_; ++r) scale(r) = mean_scale(r % 6);
    for (int k = 0; k < n_; ++k) scale(row_of_[k]) = layout_.scale(k);
    Eigen::MatrixXd modes = Eigen::MatrixXd::Zero(rows_, 6);
    for (int i = 0; i < particles; ++i) {
      const Eigen::Vector3d d = (x.row(i).matrix() - centroid).transpose();
      const int slot = slot_of_[i];
      for (int e = 0; e < 3; ++e) {
        modes(6 * slot + e, e) = 1;  // translation along e
        const Eigen::Vector3d axis = Eigen::Vector3d::Unit(e);
        const Eigen::Vector3d u = axis.cross(d);  // rotation about e: u = e x (x - x0), theta = e
        for (int c = 0; c < 3; ++c) modes(6 * slot + c, 3 + e) = u(c);
        modes(6 * slot + 3 + e, 3 + e) = 1;
      }
    }
    modes.array().colwise() /= scale.array();
    const Eigen::HouseholderQR<Eigen::MatrixXd> qr(modes);
    const Eigen::MatrixXd q = qr.householderQ() * Eigen::MatrixXd::Identity(rows_, 6);
    Vec vectors[6];
    for (int m = 0; m < 6; ++m) {
      check(MatCreateVecs(a_, &vectors[m], nullptr), "MatCreateVecs");
      PetscScalar* v = nullptr;
      check(VecGetArray(vectors[m], &v), "VecGetArray");
      for (int r = first_; r < end_; ++r) v[r - first_] = q(r, m);
      check(VecRestoreArray(vectors[m], &v), "VecRestoreArray");
    }
    MatNullSpace space = nullptr;
    check(MatNullSpaceCreate(PETSC_COMM_WORLD, PETSC_FALSE, 6, vectors, &space),
          "MatNullSpaceCreate");
    check(MatSetNearNullSpace(a_, space), "MatSetNearNullSpace");
    MatNullSpaceDestroy(&space);
    for (Vec& v : vectors) VecDestroy(&v);
  }

  bool probe_finds_null_space() {
    Vec r = nullptr;
    check(VecDuplicate(x_, &r), "VecDuplicate");
    PetscScalar* v = nullptr;
    check(VecGetArray(r, &v), "VecGetArray");
    for (int row = first_; row < end_; ++row) v[row - first_] = 0;
    for (int k = 0; k < n_; ++k)
      if (row_of_[k] >= first_ && row_of_[k] < end_) v[row_of_[k] - first_] = probe_value(k);
    check(VecRestoreArray(r, &v), "VecRestoreArray");
    check(MatMult(a_, r, b_), "MatMult");
    check(VecSet(x_, 0), "VecSet");
    // The probe's own tolerance (and that of the user's options otherwise), then the solves'.
    PetscReal rtol = 0, abstol = 0, dtol = 0;
    PetscInt max_iterations = 0;
    check(KSPGetTolerances(ksp_, &rtol, &abstol, &dtol, &max_iterations), "KSPGetTolerances");
    check(KSPSetTolerances(ksp_, kProbeTolerance, abstol, dtol, max_iterations),
          "KSPSetTolerances");
    start_progress("probe for mechanisms", kProbeTolerance);
    check(KSPSolve(ksp_, b_, x_), "probe solve (KSPSolve)");
    check(KSPSetTolerances(ksp_, rtol, abstol, dtol, max_iterations), "KSPSetTolerances");
    KSPConvergedReason reason = KSP_CONVERGED_ITERATING;
    check(KSPGetConvergedReason(ksp_, &reason), "KSPGetConvergedReason");
    PetscReal r_max = 0, error = 0;
    check(VecNorm(r, NORM_INFINITY, &r_max), "VecNorm");
    check(VecAXPY(x_, -1, r), "VecAXPY");
    check(VecNorm(x_, NORM_INFINITY, &error), "VecNorm");
    VecDestroy(&r);
    probe_error_ = r_max > 0 ? error / r_max : 0;
    return reason < 0 || !(probe_error_ <= kMechanismProbe);
  }

  // This rank's rows of `values` (the unknowns' numbering) into `target` (prescribed rows 0).
  void scatter_to(Vec target, const Eigen::VectorXd& values) const {
    PetscScalar* v = nullptr;
    check(VecGetArray(target, &v), "VecGetArray");
    for (int row = first_; row < end_; ++row) v[row - first_] = 0;
    for (int k = 0; k < n_; ++k)
      if (row_of_[k] >= first_ && row_of_[k] < end_) v[row_of_[k] - first_] = values(k);
    check(VecRestoreArray(target, &v), "VecRestoreArray");
  }

  // Solves for the right-hand side `y`, into `y`; CG starts from `guess` where given, else 0.
  void solve_one(Eigen::VectorXd& y, const Eigen::VectorXd* guess) const {
    scatter_to(b_, y);
    if (guess) {
      scatter_to(x_, *guess);
    } else {
      check(VecSet(x_, 0), "VecSet");
    }
    check(KSPSetInitialGuessNonzero(ksp_, guess ? PETSC_TRUE : PETSC_FALSE),
          "KSPSetInitialGuessNonzero");
    PetscReal rtol = 0;
    check(KSPGetTolerances(ksp_, &rtol, nullptr, nullptr, nullptr), "KSPGetTolerances");
    start_progress("solve", rtol);
    check(KSPSolve(ksp_, b_, x_), "solve (KSPSolve)");
    KSPConvergedReason reason = KSP_CONVERGED_ITERATING;
    check(KSPGetConvergedReason(ksp_, &reason), "KSPGetConvergedReason");
    PetscInt its = 0;
    KSPGetIterationNumber(ksp_, &its);
    iterations_ += static_cast<int>(its);
    if (reason < 0) {
      PetscReal residual = 0;
      KSPGetResidualNorm(ksp_, &residual);
      throw Error(fmt::format(
          "linear solver: PETSc's {} did not converge ({} after {} iterations, residual norm "
          "{:.3g}); the free dofs may form a mechanism (--linear-solver direct names it), or the "
          "options ask for too much",
          name(), KSPConvergedReasons[reason], its, residual));
    }
    check(VecScatterBegin(to_all_, x_, all_, INSERT_VALUES, SCATTER_FORWARD), "VecScatter");
    check(VecScatterEnd(to_all_, x_, all_, INSERT_VALUES, SCATTER_FORWARD), "VecScatter");
    const PetscScalar* all = nullptr;
    check(VecGetArrayRead(all_, &all), "VecGetArrayRead");
    for (int k = 0; k < n_; ++k) y(k) = all[row_of_[k]];
    check(VecRestoreArrayRead(all_, &all), "VecRestoreArrayRead");
  }

  void start_progress(const char* what, double target) const {
    progress_ = SolveProgress{};
    progress_.what = what;
    progress_.target = target;
  }

  void release() {
    if (to_all_) VecScatterDestroy(&to_all_);
    if (all_) VecDestroy(&all_);
    if (x_) VecDestroy(&x_);
    if (b_) VecDestroy(&b_);
    if (ksp_) KSPDestroy(&ksp_);
    if (a_) MatDestroy(&a_);
  }

  UnknownLayout layout_;
  int n_ = 0, rows_ = 0, block_ = 1, first_ = 0, end_ = 0;
  std::vector<int> row_of_;   // unknown -> row of the padded matrix
  std::vector<int> slot_of_;  // particle -> its block of six rows (number_rows())
  Mat a_ = nullptr;
  KSP ksp_ = nullptr;
  Vec x_ = nullptr, b_ = nullptr, all_ = nullptr;
  VecScatter to_all_ = nullptr;
  double probe_error_ = 0;
  mutable int iterations_ = 0;
  mutable SolveProgress progress_;  // KSPMonitorSet holds its address
  std::optional<SupernodalCholesky> fallback_;
};

}  // namespace

std::unique_ptr<LinearSolver> make_petsc_solver() {
  return std::make_unique<PetscSolver>();
}

void insert_petsc_options(const std::string& options) {
  ensure_petsc();
  check(PetscOptionsInsertString(nullptr, options.c_str()),
        fmt::format("options \"{}\"", options).c_str());
}

void start_petsc_session(int* argc, char*** argv) {
  PetscBool initialized = PETSC_FALSE;
  PetscInitialized(&initialized);
  if (initialized) return;
  // PETSc's own options come from --petsc-options, not from the command line plydem parses.
  int no_arguments = 1;
  char* program = (*argv)[0];
  char* arguments[] = {program, nullptr};
  char** pointer = arguments;
  check(PetscInitialize(&no_arguments, &pointer, nullptr, nullptr), "initialization");
  (void)argc;
  quiet_errors();
  session_initialized = true;
}

void end_petsc_session() {
  if (session_initialized) PetscFinalize();
  session_initialized = false;
}

std::vector<char> petsc_rank_particles(const Eigen::Array<double, Eigen::Dynamic, 3>& position) {
  ensure_petsc();  // MPI's ranks are known once PETSc is up (the solver would start it anyway)
  if (petsc_size() <= 1) return {};
  const std::vector<int> slot_of = slots_along_longest_extent(position);
  const auto [first, end] = rank_slots(static_cast<int>(position.rows()));
  std::vector<char> own(slot_of.size(), 0);
  for (std::size_t i = 0; i < slot_of.size(); ++i)
    own[i] = slot_of[i] >= first && slot_of[i] < end ? 1 : 0;
  return own;
}

void petsc_sum_over_ranks(double* values, int count) {
  if (petsc_size() <= 1) return;
  MPI_Allreduce(MPI_IN_PLACE, values, count, MPI_DOUBLE, MPI_SUM, PETSC_COMM_WORLD);
}

void broadcast_from_root(double* values, int count) {
  if (petsc_size() <= 1) return;
  MPI_Bcast(values, count, MPI_DOUBLE, 0, PETSC_COMM_WORLD);
}

int petsc_rank() {
  PetscBool initialized = PETSC_FALSE;
  PetscInitialized(&initialized);
  if (!initialized) return 0;
  PetscMPIInt rank = 0;
  MPI_Comm_rank(PETSC_COMM_WORLD, &rank);
  return rank;
}

int petsc_size() {
  PetscBool initialized = PETSC_FALSE;
  PetscInitialized(&initialized);
  if (!initialized) return 1;
  PetscMPIInt size = 1;
  MPI_Comm_size(PETSC_COMM_WORLD, &size);
  return size;
}

}  // namespace plydem
