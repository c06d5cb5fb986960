#pragma once
/// \file
/// What a test will need before it builds anything: the particles and bonds of its coupon (from
/// the strategy's unit cell, Strategy::estimate_packing; a laminate multiplies by its plies and
/// adds the interface bonds) and the memory they and the solver take, checked against what the
/// machine has left (core/machine_memory.hpp). A coupon that does not fit is refused in
/// milliseconds with the estimate, instead of swapping for minutes and then failing.
///
/// The memory counted (bytes):
///  - the model: every field of Particles and Bonds (core/model.hpp, one row each), times the
///    models a test holds at once (the tension test keeps the built coupon, both pulled ones and
///    the specimen-stiffness copy: 4);
///  - the build: the packing's positions and bond pairs, once;
///  - a static solve: K as the assembly's 6 x 6 blocks (one per particle and per bond) and as its
///    lower triangle in compressed columns (21 entries per particle, 36 per bond), and the sparse
///    Cholesky factor L, 8 bytes per entry. L is a stated bound, not a symbolic analysis (that
///    needs the built coupon): the nested-dissection growth of a planar graph, entries =
///    c n z l log2(m) with n unknowns, z the mean coordination (2 bonds / particles), l the
///    particle layers through the thickness (all plies), m = particles / l, and c =
///    kFactorFillCoefficient, above every factor measured: hex2d plies 0.94 (the paper's coupon)
///    and 1.41 (20 x 5 mm), [0/90/0] 1.35, [0/45/-45/90]s 0.98, hcp 1.79; and
///    kDirectFactorWorkspace of it again for the fronts and the update stack. Against the peak RSS
///    of `plydem tension`: the paper's coupon 56 / 38 MB, 20 x 5 mm 855 / 524 MB, [0/90/0] 3 x 1 mm
///    181 / 129 MB, hcp 5 x 2 mm 808 / 687 MB, [0/45/-45/90]s 4 x 1.5 mm 2.84 / 2.12 GB (estimate /
///    measured);
///  - explicit dynamics: the integrator's own copy of the particles and bonds (kernel order);
///  - the events solver: the factor plus its Woodbury update, two n x max_update_rank blocks;
///  - PETSc (static solves with --linear-solver petsc, or auto where PETSc is built: it takes over
///    where the factor does not fit, solvers/linear_solver.hpp): both triangles of K in AIJ
///    (12 bytes per entry, 36 per particle and 72 per bond) times kPetscMemoryFactor for the AMG
///    hierarchy, its prolongators and the Krylov vectors. Against the peak RSS of
///    plydem_static_bench on the [0/45/-45/90]s paper coupon: 394 MiB measured, of which about
///    250 MB PETSc's; the AIJ bound is 126 MB there (measured nonzeros: 6.7e6, the bound 1.05e7).

#include <string>
#include <vector>

#include "solvers/linear_solver.hpp"
#include "strategies/laminate.hpp"
#include "strategies/strategy.hpp"

namespace plydem {

/// The coefficient c of the factor bound above.
inline constexpr double kFactorFillCoefficient = 2.0;

/// PETSc's memory as a multiple of its fine-level AIJ matrix (see the file comment).
inline constexpr double kPetscMemoryFactor = 2.0;

/// What a test does with its coupon after building it.
enum class SolverUse {
  kStatic,    ///< static solves (the tension test's default, the specimen stiffness)
  kExplicit,  ///< explicit dynamics (and the static solves of the specimen stiffness)
  kEvents     ///< the events solver to failure (one factorization, Woodbury updates)
};

struct ResourceEstimate {
  bool known = false;    ///< false: the strategy cannot estimate its packing (no unit cell)
  double particles = 0;  ///< of one coupon
  double bonds = 0;      ///< of one coupon, interface bonds included
  double interface_bonds = 0;
  int plies = 1;
  int models_held = 1;        ///< coupons held at once
  double model_bytes = 0;     ///< all the models held, and the build's packing
  double matrix_bytes = 0;    ///< K (static and events)
  double factor_entries = 0;  ///< of L, the bound above (static and events)
  double petsc_bytes = 0;     ///< PETSc's matrix and AMG hierarchy, where PETSc may solve
  double solver_bytes = 0;    ///< K, L and the Woodbury blocks, or the integrator's copy
  double total_bytes = 0;
  std::string solver;  ///< what solver_bytes counts, for messages
};

/// Bytes of one row of Particles and of Bonds: the sizes of their declared fields.
double particle_row_bytes();
double bond_row_bytes();

/// The estimate for `coupon` (one ply) or, for a non-empty `layup`, the laminate of those plies
/// with `interface` (its lateral radius), built by `strategy`, used by `solver` while
/// `models_held` coupons exist; `update_rank` is the events solver's max_update_rank;
/// `linear_solver` is the static solves' (a direct factor, PETSc, or the smaller of the two for
/// kAuto where PETSc is built). Throws plydem::Error for a bad coupon.
ResourceEstimate estimate_resources(const Strategy& strategy, const CouponSpec& coupon,
                                    const std::vector<double>& layup,
                                    const InterfaceStiffness& interface, SolverUse solver,
                                    int models_held, int update_rank = 0,
                                    LinearSolverKind linear_solver = LinearSolverKind::kAuto);

/// One line: particles, bonds and memory with its parts, e.g. "4.6e+07 particles, 1.4e+08 bonds,
/// about 830 GB (models 37 GB, sparse Cholesky factor 780 GB ...)".
std::string format_estimate(const ResourceEstimate& estimate);

/// Throws plydem::Error with the estimate and the machine's available memory when the estimate
/// exceeds it, unless `force`; `force_hint` names how to force it (e.g. "--force"). Whatever
/// `force` says, refuses more particles or bonds than plydem's 32-bit indices hold. Logs the
/// estimate (info) above 1 GB. Does nothing for an unknown estimate.
void check_resources(const ResourceEstimate& estimate, bool force, const std::string& force_hint);

}  // namespace plydem
