#include "solvers/linear_solver.hpp"

#include <fmt/format.h>

#include <cholmod.h>
#include <dlfcn.h>
#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <optional>

#include "core/error.hpp"
#include "core/machine_memory.hpp"
#include "core/units.hpp"
#include "solvers/machine_rates.hpp"
#include "solvers/sparse_cholesky.hpp"
#ifdef PLYDEM_HAVE_PETSC
#include "solvers/petsc_solver.hpp"
#endif

namespace plydem {
namespace {

class DirectSolver final : public LinearSolver {
 public:
  void factor(const SparseMatrix& lower, double pivot_tolerance) override {
    cholesky_.analyze(lower);
    cholesky_.factorize(lower, pivot_tolerance);
  }
  const std::vector<int>& zero_pivots() const override { return cholesky_.zero_pivots(); }
  Eigen::VectorXd pivots() const override { return cholesky_.pivots(); }
  void solve_in_place(Eigen::MatrixXd& b) const override { cholesky_.solve_in_place(b); }
  std::string name() const override { return "supernodal Cholesky (AMD on particles)"; }
  double factor_entries() const override { return static_cast<double>(cholesky_.factor_entries()); }
  double factor_flops() const override { return cholesky_.factor_flops(); }

 private:
  SupernodalCholesky cholesky_;
};

// A view of an Eigen lower triangle as a CHOLMOD matrix (no copy; CHOLMOD only reads it).
cholmod_sparse view_lower(const LinearSolver::SparseMatrix& lower) {
  require(lower.isCompressed(), "linear solver: the matrix must be in compressed storage");
  cholmod_sparse a{};
  a.nrow = static_cast<std::size_t>(lower.rows());
  a.ncol = static_cast<std::size_t>(lower.cols());
  a.nzmax = static_cast<std::size_t>(lower.nonZeros());
  a.p = const_cast<int*>(lower.outerIndexPtr());
  a.i = const_cast<int*>(lower.innerIndexPtr());
  a.x = const_cast<double*>(lower.valuePtr());
  a.stype = -1;  // symmetric, lower triangle stored
  a.itype = CHOLMOD_INT;
  a.xtype = CHOLMOD_REAL;
  a.dtype = CHOLMOD_DOUBLE;
  a.sorted = 1;
  a.packed = 1;
  return a;
}

// The entries and floating-point operations of the Cholesky factor of `lower` in its given order,
// from CHOLMOD's column counts (Gilbert, Ng and Peyton: time of the order of A's entries, where
// the hand-written analysis walks every entry of L): what kAuto decides by, before it analyses the
// matrix for the solver it takes. Simplicial counts: the supernodes' panels add their explicit
// zeros to these (a few percent).
struct FactorCounts {
  double entries = 0, flops = 0;
};

FactorCounts count_factor(const LinearSolver::SparseMatrix& lower) {
  cholmod_common common{};
  cholmod_start(&common);
  common.print = 0;
  common.nmethods = 1;
  common.method[0].ordering = CHOLMOD_NATURAL;
  common.postorder = 0;
  common.supernodal = CHOLMOD_SIMPLICIAL;
  cholmod_sparse a = view_lower(lower);
  cholmod_factor* symbolic = cholmod_analyze(&a, &common);
  const FactorCounts counts{common.lnz, common.fl};
  const bool failed = symbolic == nullptr;
  if (symbolic) cholmod_free_factor(&symbolic, &common);
  cholmod_finish(&common);
  require(!failed, "linear solver: CHOLMOD's count of the factor failed");
  return counts;
}

class CholmodSolver final : public LinearSolver {
 public:
  CholmodSolver() {
    cholmod_start(&common_);
    common_.print = 0;  // failures become plydem::Error, not text on stdout
    common_.supernodal = CHOLMOD_SUPERNODAL;
    common_.final_ll = 1;
  }
  ~CholmodSolver() override {
    if (factor_) cholmod_free_factor(&factor_, &common_);
    cholmod_finish(&common_);
  }
  CholmodSolver(const CholmodSolver&) = delete;
  CholmodSolver& operator=(const CholmodSolver&) = delete;

  void factor(const SparseMatrix& lower, double pivot_tolerance) override {
    require(lower.rows() == lower.cols(), "linear solver: the matrix is not square");
    fallback_.reset();
    if (factor_) cholmod_free_factor(&factor_, &common_);
    cholmod_sparse a = view_lower(lower);
    factor_ = cholmod_analyze(&a, &common_);
    check("analysis");
    cholmod_factorize(&a, factor_, &common_);
    const bool not_positive = common_.status == CHOLMOD_NOT_POSDEF;
    if (!not_positive) check("factorization");
    // The pivots d_k = L_kk^2 against A_kk (the first stored entry of each lower column).
    bool small_pivot = not_positive;
    if (!small_pivot) {
      const auto* super = static_cast<const int*>(factor_->super);
      const auto* pi = static_cast<const int*>(factor_->pi);
      const auto* px = static_cast<const int*>(factor_->px);
      const auto* perm = static_cast<const int*>(factor_->Perm);
      const auto* x = static_cast<const double*>(factor_->x);
      for (std::size_t s = 0; s < factor_->nsuper && !small_pivot; ++s) {
        const int rows = pi[s + 1] - pi[s];
        for (int k = super[s]; k < super[s + 1]; ++k) {
          const int j = k - super[s];
          const double l = x[px[s] + static_cast<std::ptrdiff_t>(j) * rows + j];
          const int original = perm[k];
          const double diagonal = lower.valuePtr()[lower.outerIndexPtr()[original]];
          if (l * l <= pivot_tolerance * diagonal) {
            small_pivot = true;
            break;
          }
        }
      }
    }
    if (small_pivot) {
      // One pass of the hand-written factorization names every zero pivot (see the header).
      fallback_.emplace();
      fallback_->factor(lower, pivot_tolerance);
    }
  }
  const std::vector<int>& zero_pivots() const override {
    static const std::vector<int> none;
    return fallback_ ? fallback_->zero_pivots() : none;
  }
  Eigen::VectorXd pivots() const override {
    require(fallback_.has_value(),
            "linear solver: CHOLMOD keeps no LDL^T pivots of a positive definite factor");
    return fallback_->pivots();
  }
  void solve_in_place(Eigen::MatrixXd& b) const override {
    if (fallback_) {
      fallback_->solve_in_place(b);
      return;
    }
    require(factor_ != nullptr && static_cast<Eigen::Index>(factor_->n) == b.rows(),
            "linear solver: solve before factor, or a right-hand side of the wrong size");
    if (b.cols() == 0 || b.rows() == 0) return;
    cholmod_dense rhs{};
    rhs.nrow = static_cast<std::size_t>(b.rows());
    rhs.ncol = static_cast<std::size_t>(b.cols());
    rhs.nzmax = rhs.nrow * rhs.ncol;
    rhs.d = rhs.nrow;
    rhs.x = b.data();
    rhs.xtype = CHOLMOD_REAL;
    rhs.dtype = CHOLMOD_DOUBLE;
    cholmod_common& common = common_;
    cholmod_dense* x = cholmod_solve(CHOLMOD_A, factor_, &rhs, &common);
    require(x != nullptr,
            fmt::format("linear solver: CHOLMOD's solve failed (status {})", common.status));
    std::memcpy(b.data(), x->x, sizeof(double) * rhs.nzmax);
    cholmod_free_dense(&x, &common);
  }
  std::string name() const override {
    if (fallback_) return fallback_->name();
    const int method = common_.selected;
    const char* order = method >= 0 && method <= CHOLMOD_MAXMETHODS
                            ? ordering_name(common_.method[method].ordering)
                            : "?";
    return fmt::format("CHOLMOD supernodal ({})", order);
  }
  double factor_entries() const override {
    if (fallback_) return fallback_->factor_entries();
    return factor_ ? static_cast<double>(factor_->xsize) : 0.0;
  }
  double factor_flops() const override {
    if (fallback_) return fallback_->factor_flops();
    return factor_ ? common_.fl : 0.0;
  }

 private:
  static const char* ordering_name(int ordering) {
    switch (ordering) {
      case CHOLMOD_NATURAL:
        return "natural order";
      case CHOLMOD_GIVEN:
        return "given order";
      case CHOLMOD_AMD:
        return "AMD";
      case CHOLMOD_METIS:
        return "METIS";
      case CHOLMOD_NESDIS:
        return "nested dissection";
      case CHOLMOD_COLAMD:
        return "COLAMD";
      default:
        return "?";
    }
  }
  void check(const char* phase) const {
    if (common_.status == CHOLMOD_OUT_OF_MEMORY)
      throw Error(fmt::format("linear solver: CHOLMOD ran out of memory in the {}", phase));
    if (common_.status != CHOLMOD_OK)
      throw Error(
          fmt::format("linear solver: CHOLMOD's {} failed (status {})", phase, common_.status));
  }

  mutable cholmod_common common_{};  // CHOLMOD's workspace and statistics, also for solves
  cholmod_factor* factor_ = nullptr;
  std::optional<DirectSolver> fallback_;
};

}  // namespace

void LinearSolver::solve_in_place(Eigen::VectorXd& b) const {
  Eigen::MatrixXd m = std::move(b);
  solve_in_place(m);
  b = std::move(m);
}

const char* linear_solver_name(LinearSolverKind kind) {
  switch (kind) {
    case LinearSolverKind::kAuto:
      return "auto";
    case LinearSolverKind::kDirect:
      return "direct";
    case LinearSolverKind::kCholmod:
      return "cholmod";
    case LinearSolverKind::kPetsc:
      return "petsc";
  }
  return "?";
}

LinearSolverKind parse_linear_solver(std::string_view name) {
  for (LinearSolverKind kind :
       {LinearSolverKind::kAuto, LinearSolverKind::kDirect, LinearSolverKind::kCholmod})
    if (name == linear_solver_name(kind)) return kind;
  if (name == "petsc") {
    if (petsc_available()) return LinearSolverKind::kPetsc;
    throw Error(
        "linear solver 'petsc': this plydem was built without PETSc (install petsc-dev, "
        "scripts/setup, and configure again; the sanitizer build never has it); use auto, direct "
        "or cholmod");
  }
  throw Error(fmt::format("unknown linear solver '{}': use auto, direct, cholmod or petsc", name));
}

bool petsc_available() {
#ifdef PLYDEM_HAVE_PETSC
  return true;
#else
  return false;
#endif
}

void set_petsc_options(const std::string& options) {
#ifdef PLYDEM_HAVE_PETSC
  insert_petsc_options(options);
#else
  throw Error(fmt::format("PETSc options \"{}\": this plydem was built without PETSc", options));
#endif
}

ParallelSession::ParallelSession([[maybe_unused]] int* argc, [[maybe_unused]] char*** argv) {
#ifdef PLYDEM_HAVE_PETSC
  // Only under mpiexec (OpenMPI, MPICH and hydra set these): a single process starts PETSc
  // when a kPetsc solver is first made, and other commands never pay for MPI's start.
  if (std::getenv("OMPI_COMM_WORLD_SIZE") || std::getenv("PMI_SIZE"))
    start_petsc_session(argc, argv);
#endif
}

ParallelSession::~ParallelSession() {
#ifdef PLYDEM_HAVE_PETSC
  end_petsc_session();
#endif
}

int mpi_rank() {
#ifdef PLYDEM_HAVE_PETSC
  return petsc_rank();
#else
  return 0;
#endif
}

std::vector<char> rank_particles(const Eigen::Array<double, Eigen::Dynamic, 3>& position) {
#ifdef PLYDEM_HAVE_PETSC
  return petsc_rank_particles(position);
#else
  (void)position;
  return {};
#endif
}

void sum_over_ranks(double* values, int count) {
#ifdef PLYDEM_HAVE_PETSC
  petsc_sum_over_ranks(values, count);
#else
  (void)values;
  (void)count;
#endif
}

int mpi_size() {
#ifdef PLYDEM_HAVE_PETSC
  return petsc_size();
#else
  return 1;
#endif
}

bool optimized_blas() {
  // OpenBLAS exports openblas_get_config; the reference BLAS does not. CHOLMOD's libraries are
  // linked into this program, so its BLAS is loaded by now.
  static const bool found = dlsym(RTLD_DEFAULT, "openblas_get_config") != nullptr;
  return found;
}

namespace {

// The hand-written factor's panels (relaxed supernodes, with explicit zeros) over the entries
// CHOLMOD counts: 1.20-1.24 on the paper's plies and laminates.
constexpr double kSupernodalPanelShare = 1.25;

// What a choice of kAuto is made of.
struct AutoChoice {
  LinearSolverKind kind = LinearSolverKind::kDirect;
  std::string reason;
};

std::string seconds_text(double seconds) {
  return seconds < 0.1 ? fmt::format("{:.3f} s", seconds) : fmt::format("{:.2g} s", seconds);
}

// The cheapest of the solvers kAuto may take, by predict_linear_solvers, with the prediction.
AutoChoice cheapest(const AutoProblem& problem, bool iterative_allowed, bool direct_fits) {
  const MachineRates& rates = machine_rates();
  const AutoPrediction t = predict_linear_solvers(problem, rates);
  struct Candidate {
    LinearSolverKind kind;
    double seconds;
    const char* name;
    bool allowed;
  };
  const Candidate candidates[] = {
      {LinearSolverKind::kDirect, t.direct, "hand-written factor", direct_fits},
      {LinearSolverKind::kCholmod, t.cholmod, "CHOLMOD", direct_fits},
      {LinearSolverKind::kPetsc, t.petsc, "PETSc", iterative_allowed}};
  const Candidate* best = nullptr;
  for (const Candidate& c : candidates)
    if (c.allowed && (!best || c.seconds < best->seconds)) best = &c;
  if (!best) best = &candidates[0];  // --force: the hand-written factor
  std::string others;
  for (const Candidate& c : candidates)
    if (c.allowed && &c != best)
      others += fmt::format("{}{} {}", others.empty() ? "" : ", ", c.name, seconds_text(c.seconds));
  AutoChoice choice;
  choice.kind = best->kind;
  choice.reason = fmt::format(
      "chosen by auto: predicted {}{}{} for {} solve{}{} (a direct factor of {:.3g} entries, "
      "{:.3g} flops) on this machine ({}: {:.3g} GFLOP/s, Eigen {:.3g} GFLOP/s, memory {:.3g} "
      "GB/s; {})",
      seconds_text(best->seconds), others.empty() ? "" : " against ", others, problem.solves,
      problem.solves == 1 ? "" : "s",
      problem.ranks > 1 ? fmt::format(" on {} ranks", problem.ranks) : std::string(),
      problem.factor_entries, problem.factor_flops, rates.blas, rates.blas_gflops,
      rates.eigen_gflops, rates.memory_gbytes, rates.source);
  return choice;
}

// kAuto: CHOLMOD's counts of the factor measure the problem, the machine's rates price each
// solver (see the header); only the solver taken analyses the matrix.
class AutoSolver final : public LinearSolver {
 public:
  AutoSolver(LinearSolverUse use, bool force, int expected_solves)
      : use_(use), force_(force), solves_(expected_solves) {}
  void set_layout(const UnknownLayout& layout) override { layout_ = layout; }
  int iterations() const override { return chosen_ ? chosen_->iterations() : 0; }
  void factor(const SparseMatrix& lower, double pivot_tolerance) override {
    chosen_.reset();
    direct_.reset();
    const AutoChoice choice = decide(lower);
    reason_ = choice.reason;
    if (choice.kind != LinearSolverKind::kDirect) {
      direct_.reset();
      chosen_ = make_linear_solver(choice.kind);
      chosen_->set_layout(layout_);
      chosen_->factor(lower, pivot_tolerance);
    } else {
      if (!direct_) {
        direct_.emplace();
        direct_->analyze(lower);
      }
      direct_->factorize(lower, pivot_tolerance);
    }
  }
  const std::vector<int>& zero_pivots() const override {
    return chosen_ ? chosen_->zero_pivots() : direct_->zero_pivots();
  }
  Eigen::VectorXd pivots() const override {
    return chosen_ ? chosen_->pivots() : direct_->pivots();
  }
  void solve_in_place(Eigen::MatrixXd& b) const override {
    require(chosen_ || direct_, "linear solver: solve before factor");
    if (chosen_)
      chosen_->solve_in_place(b);
    else
      direct_->solve_in_place(b);
  }
  void solve_from(Eigen::VectorXd& x, const Eigen::VectorXd& b) const override {
    if (chosen_) {
      chosen_->solve_from(x, b);
    } else {
      x = b;
      LinearSolver::solve_in_place(x);
    }
  }
  std::string name() const override {
    if (!chosen_) return "supernodal Cholesky (AMD on particles)";
    return reason_.empty() ? chosen_->name() : fmt::format("{} ({})", chosen_->name(), reason_);
  }
  std::string choice() const override { return reason_; }
  double factor_entries() const override {
    if (chosen_) return chosen_->factor_entries();
    return direct_ ? static_cast<double>(direct_->factor_entries()) : 0.0;
  }
  double factor_flops() const override {
    if (chosen_) return chosen_->factor_flops();
    return direct_ ? direct_->factor_flops() : 0.0;
  }

 private:
  // The choice from the counts (the header): memory first, then the predicted time. Where the
  // counted factor seems not to fit, the hand-written analysis says exactly (and is kept).
  AutoChoice decide(const SparseMatrix& lower) {
    const FactorCounts counts = count_factor(lower);
    AutoProblem problem;
    problem.unknowns = std::max<double>(1.0, static_cast<double>(lower.rows()));
    problem.nonzeros = static_cast<double>(lower.nonZeros());
    problem.factor_entries = counts.entries;
    problem.factor_flops = counts.flops;
    problem.solves = solves_;
    problem.ranks = mpi_size();
    const double fill = problem.factor_entries / problem.unknowns;
    // Every rank holds its own factor, whose panels hold more than the entries counted.
    double bytes =
        direct_factor_bytes(kSupernodalPanelShare * problem.factor_entries) * problem.ranks;
    const MachineMemory memory = machine_memory();
    bool fits = bytes <= kAutoMemoryShare * memory.available;
    if (!fits) {
      direct_.emplace();
      direct_->analyze(lower);
      bytes = direct_factor_bytes(static_cast<double>(direct_->factor_entries())) * problem.ranks;
      fits = bytes <= kAutoMemoryShare * memory.available;
    }
    const bool iterative_allowed = petsc_available() && use_ == LinearSolverUse::kFewSolves;
    if (!fits && iterative_allowed)
      return {LinearSolverKind::kPetsc, fmt::format("chosen by auto: a direct factor would need "
                                                    "{:.2f} GB",
                                                    bytes / kBytesPerGB)};
    if (!fits && !force_)
      throw Error(fmt::format(
          "static solve: the direct factor of these {:.0f} unknowns needs about {:.2f} GB "
          "(symbolic analysis: {:.3g} entries, {:.0f} per unknown, with its workspace{}), more "
          "than the {:.2f} GB available ({}); {}",
          problem.unknowns, bytes / kBytesPerGB, problem.factor_entries, fill,
          problem.ranks > 1 ? fmt::format(", on each of {} ranks", problem.ranks) : "",
          memory.available / kBytesPerGB, memory.source,
          use_ == LinearSolverUse::kManySolves
              ? "this solver updates a direct factor, so it cannot switch to an iterative one: "
                "make the model smaller or the particles larger"
              : "this plydem has no iterative linear solver (PETSc: install petsc-dev and "
                "configure again); make the model smaller or the particles larger"));
    // A factorization this small takes a fraction of a second whatever the machine: no rates.
    if (problem.factor_flops <= kAutoSmallFactorFlops)
      return {LinearSolverKind::kDirect,
              fmt::format("chosen by auto: a small direct factor ({:.3g} flops, {:.0f} entries "
                          "per unknown)",
                          problem.factor_flops, fill)};
    return cheapest(problem, iterative_allowed, fits || force_);
  }

  LinearSolverUse use_;
  bool force_;
  int solves_;
  UnknownLayout layout_;
  std::optional<SupernodalCholesky> direct_;
  std::unique_ptr<LinearSolver> chosen_;  // CHOLMOD or PETSc where kAuto picks one
  std::string reason_;                    // why, for name() and choice()
};

}  // namespace

namespace {

// kAuto's model (predict_linear_solvers), fitted on the development VM (2 cores of an AMD EPYC;
// Eigen's product 13 GFLOP/s, the reference BLAS 5, OpenBLAS 34 on one thread and 46 on two,
// memory 29 GB/s: solvers/machine_rates.hpp) to the paper's coupons (the 0 deg ply of 3.8e3, 3e4
// and 1e5 particles, [0/90/0] and [0/45/-45/90]s; bench/static_solve) by every solver. Times
// scale with the machine's rates: a factorization with its kernel's, the work around it with
// Eigen's (the processor's speed at scalar code), solves and PETSc's sweeps with memory.
// The hand-written factorization: its flops at this share of Eigen's product rate, and its
// assembly and extend-add, this many operations per factor entry (CHOLMOD's count: the
// supernodes' panels hold about 1.2 times as many).
constexpr double kDirectFlopShare = 1.0;
constexpr double kDirectEntryFlops = 480;
// CHOLMOD: the flops in the order given (METIS takes fewer on laminates: that is in the share)
// at this share of the BLAS's rate, and its ordering and analysis, this many per unknown.
constexpr double kCholmodFlopShare = 0.6;
constexpr double kCholmodUnknownFlops = 9.4e4;
// A solve with a factor streams it twice (forward, backward): bytes per factor entry counted.
constexpr double kSolveBytesPerEntry = 100;
// PETSc's setup (aggregation, prolongators, Galerkin products) and each CG iteration (a V-cycle of
// Chebyshev-Jacobi sweeps), in bytes streamed per stored entry of the lower triangle; and its
// iterations to 1e-12 from zero, which grow with the factor's fill (entries counted per unknown;
// measured: 22-27 on single plies, 50-80; 30 on [0/90/0], 280; 57 on [0/45/-45/90]s, 730).
constexpr double kPetscSetupBytes = 2.37e4;
constexpr double kPetscIterationBytes = 355;
double petsc_iterations(double fill) {
  return 18 + 0.053 * fill;
}

}  // namespace

AutoPrediction predict_linear_solvers(const AutoProblem& p, const MachineRates& rates) {
  const double eigen = rates.eigen_gflops * 1e9, blas = rates.blas_gflops * 1e9;
  const double memory = rates.memory_gbytes * 1e9;
  const double solves = std::max(1, p.solves);
  const double solving = solves * kSolveBytesPerEntry * p.factor_entries / memory;
  AutoPrediction t;
  t.direct = p.factor_flops / (kDirectFlopShare * eigen) +
             kDirectEntryFlops * p.factor_entries / eigen + solving;
  t.cholmod = p.factor_flops / (kCholmodFlopShare * blas) +
              kCholmodUnknownFlops * p.unknowns / eigen + solving;
  const double fill = p.factor_entries / std::max(1.0, p.unknowns);
  t.petsc = (kPetscSetupBytes + solves * petsc_iterations(fill) * kPetscIterationBytes) *
            p.nonzeros / memory / std::max(1, p.ranks);
  return t;
}

double direct_factor_bytes(double factor_entries) {
  return (1 + kDirectFactorWorkspace) * factor_entries * sizeof(double);
}

std::unique_ptr<LinearSolver> make_linear_solver(LinearSolverKind kind, LinearSolverUse use,
                                                 bool force, int expected_solves) {
  switch (kind) {
    case LinearSolverKind::kAuto:
      return std::make_unique<AutoSolver>(use, force, expected_solves);
    case LinearSolverKind::kCholmod:
      return std::make_unique<CholmodSolver>();
    case LinearSolverKind::kPetsc:
#ifdef PLYDEM_HAVE_PETSC
      return make_petsc_solver();
#else
      throw Error("linear solver 'petsc': this plydem was built without PETSc");
#endif
    case LinearSolverKind::kDirect:
      break;
  }
  return std::make_unique<DirectSolver>();
}

}  // namespace plydem
