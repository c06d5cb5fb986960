#pragma once
/// \file
/// The PETSc side of solvers/linear_solver.hpp, for linear_solver.cpp only: defined in
/// petsc_solver.cpp, which is compiled when PETSc is found (PLYDEM_HAVE_PETSC).

#include <memory>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "solvers/linear_solver.hpp"

namespace plydem {

/// kPetsc: CG + GAMG with the rigid-body near-null space (linear_solver.hpp).
std::unique_ptr<LinearSolver> make_petsc_solver();
/// PetscOptionsInsertString, initializing PETSc first if needed.
void insert_petsc_options(const std::string& options);
/// PetscInitialize / PetscFinalize for ParallelSession (no-ops if PETSc is already up or was
/// started elsewhere).
void start_petsc_session(int* argc, char*** argv);
void end_petsc_session();
/// The particles whose rows this rank hands to PETSc (1 = its own), `position` every particle's:
/// its even share of them in the order of their coordinate along the longest extent; empty on
/// one rank. Starts PETSc if it is not up.
std::vector<char> petsc_rank_particles(const Eigen::Array<double, Eigen::Dynamic, 3>& position);
/// Every rank's `count` values summed, on every rank (MPI_Allreduce; nothing with one rank).
void petsc_sum_over_ranks(double* values, int count);
/// Rank 0's `count` values to every rank of PETSC_COMM_WORLD (MPI_Bcast; nothing with one rank).
void broadcast_from_root(double* values, int count);
/// MPI rank and size of PETSC_COMM_WORLD; 0 and 1 before PETSc is initialized.
int petsc_rank();
int petsc_size();

}  // namespace plydem
