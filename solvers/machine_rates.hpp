#pragma once
/// \file
/// How fast this machine runs the kernels the linear solvers spend their time in, for kAuto's
/// predictions (solvers/linear_solver.hpp): measured at first use by three micro-benchmarks (about
/// 0.1 s with OpenBLAS, 0.3 s with the reference BLAS), and kept per machine in a cache file, so
/// that a later run reads them instead.
///
/// - Eigen's dense product on one thread: the kernel of the hand-written supernodal Cholesky
///   (solvers/sparse_cholesky.hpp; the build defines EIGEN_DONT_PARALLELIZE);
/// - dgemm of the BLAS that CHOLMOD calls, with the BLAS's own threads: Debian's reference BLAS
///   (one thread, no vector kernels) or OpenBLAS (all cores, the processor's widest vectors),
///   whichever libblas.so.3 the process loaded (the Debian alternative, or LD_LIBRARY_PATH);
/// - one thread streaming memory (a = b + s c over arrays larger than the caches): PETSc's CG and
///   algebraic multigrid, and a factor's triangular solves, are bound by it.
///
/// The cache: $PLYDEM_MACHINE_RATES when set ("none": measure in every process, read and write no
/// file), else $XDG_CACHE_HOME/plydem/machine_rates.json, else $HOME/.cache/plydem/
/// machine_rates.json; one entry per machine key (processor model, cores, the BLAS and its thread
/// count), so that switching the BLAS measures again. A file that cannot be read or written is
/// ignored (measured then). Under mpiexec rank 0 measures or reads, and its rates serve every rank,
/// so that all ranks predict, and choose, alike.

#include <string>

namespace plydem {

struct MachineRates {
  double eigen_gflops = 0;   ///< Eigen's dense matrix product, one thread [GFLOP/s]
  double blas_gflops = 0;    ///< the loaded BLAS's dgemm, its own threads [GFLOP/s]
  double memory_gbytes = 0;  ///< one thread streaming memory [GB/s]
  std::string blas;          ///< e.g. "OpenBLAS (0.3.21 ..., 2 threads)" or "reference BLAS"
  std::string key;           ///< the machine key of the cache
  /// "measured in 0.12 s" (and "kept in FILE" where it was written), or "cached in FILE".
  std::string source;
};

/// This machine's rates (above): read from the cache, or measured on first use in this process
/// and written to it; the same object for the life of the process.
const MachineRates& machine_rates();

/// The micro-benchmarks alone, measured now (no cache).
MachineRates measure_machine_rates();

/// This machine's rates from the cache file `file` (its entry for this machine), or measured and
/// added to it; "" for no file. machine_rates() is machine_rates_from(the file above), once.
MachineRates machine_rates_from(const std::string& file);

}  // namespace plydem
