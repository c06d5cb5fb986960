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

// kAuto: the hand-written symbolic analysis decides (see the header).
class AutoSolver final : public LinearSolver {
 public:
  AutoSolver(LinearSolverUse use, bool force) : use_(use), force_(force) {}
  void set_layout(const UnknownLayout& layout) override { layout_ = layout; }
  int iterations() const override { return cholmod_ ? cholmod_->iterations() : 0; }
  void factor(const SparseMatrix& lower, double pivot_tolerance) override {
    cholmod_.reset();
    direct_.emplace();
    direct_->analyze(lower);
    const double unknowns = std::max<double>(1.0, static_cast<double>(lower.rows()));
    const double fill = static_cast<double>(direct_->factor_entries()) / unknowns;
    const double bytes = direct_factor_bytes(static_cast<double>(direct_->factor_entries()));
    const MachineMemory memory = machine_memory();
    const bool fits = bytes <= kAutoMemoryShare * memory.available;
    const bool iterative_allowed = petsc_available() && use_ == LinearSolverUse::kFewSolves;
    const bool dense = fill > kAutoCholmodFill;
    if (iterative_allowed && (!fits || mpi_size() > 1 || (dense && !optimized_blas()))) {
      direct_.reset();
      cholmod_ = make_linear_solver(LinearSolverKind::kPetsc);
      reason_ =
          !fits ? fmt::format("chosen by auto: a direct factor would need {:.2f} GB",
                              bytes / kBytesPerGB)
          : mpi_size() > 1
              ? "chosen by auto: distributed over the MPI ranks"
              : fmt::format("chosen by auto: a direct factor would fill {:.0f} entries per unknown",
                            fill);
    } else if (!fits && !force_) {
      throw Error(fmt::format(
          "static solve: the direct factor of these {:.0f} unknowns needs about {:.2f} GB "
          "(symbolic analysis: {:.3g} entries, {:.0f} per unknown, with its workspace), more "
          "than the {:.2f} GB available ({}); {}",
          unknowns, bytes / kBytesPerGB, static_cast<double>(direct_->factor_entries()), fill,
          memory.available / kBytesPerGB, memory.source,
          use_ == LinearSolverUse::kManySolves
              ? "this solver updates a direct factor, so it cannot switch to an iterative one: "
                "make the model smaller or the particles larger"
              : "this plydem has no iterative linear solver (PETSc: install petsc-dev and "
                "configure again); make the model smaller or the particles larger"));
    } else if (dense && optimized_blas()) {
      direct_.reset();  // its symbolic structure is large too
      cholmod_ = std::make_unique<CholmodSolver>();
    }
    if (cholmod_) {
      cholmod_->set_layout(layout_);
      cholmod_->factor(lower, pivot_tolerance);
    } else {
      direct_->factorize(lower, pivot_tolerance);
    }
  }
  const std::vector<int>& zero_pivots() const override {
    return cholmod_ ? cholmod_->zero_pivots() : direct_->zero_pivots();
  }
  Eigen::VectorXd pivots() const override {
    return cholmod_ ? cholmod_->pivots() : direct_->pivots();
  }
  void solve_in_place(Eigen::MatrixXd& b) const override {
    require(cholmod_ || direct_, "linear solver: solve before factor");
    if (cholmod_)
      cholmod_->solve_in_place(b);
    else
      direct_->solve_in_place(b);
  }
  std::string name() const override {
    if (!cholmod_) return "supernodal Cholesky (AMD on particles)";
    return reason_.empty() ? cholmod_->name() : fmt::format("{} ({})", cholmod_->name(), reason_);
  }
  double factor_entries() const override {
    if (cholmod_) return cholmod_->factor_entries();
    return direct_ ? static_cast<double>(direct_->factor_entries()) : 0.0;
  }

 private:
  LinearSolverUse use_;
  bool force_;
  UnknownLayout layout_;
  std::optional<SupernodalCholesky> direct_;
  std::unique_ptr<LinearSolver> cholmod_;  // CHOLMOD or PETSc where kAuto picks one
  std::string reason_;                     // why PETSc, for name()
};

}  // namespace

double direct_factor_bytes(double factor_entries) {
  return (1 + kDirectFactorWorkspace) * factor_entries * sizeof(double);
}

std::unique_ptr<LinearSolver> make_linear_solver(LinearSolverKind kind, LinearSolverUse use,
                                                 bool force) {
  switch (kind) {
    case LinearSolverKind::kAuto:
      return std::make_unique<AutoSolver>(use, force);
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
