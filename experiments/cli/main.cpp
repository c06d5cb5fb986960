// The plydem program: the command line (experiments/cli/plydem_main.cpp) on every MPI rank.
#include <iostream>

#include "experiments/cli/command_line.hpp"
#include "solvers/linear_solver.hpp"

int main(int argc, char** argv) {
  // Under mpiexec -n N every rank runs the command (solvers/linear_solver.hpp, ParallelSession);
  // only rank 0 prints.
  const plydem::ParallelSession session(&argc, &argv);
  if (!plydem::is_root()) {
    std::cout.setstate(std::ios::badbit);
    std::cerr.setstate(std::ios::badbit);
  }
  return plydem_command_line(argc, argv, false);
}
