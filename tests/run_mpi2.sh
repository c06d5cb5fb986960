#!/usr/bin/env bash
# Runs a doctest binary's cases on 2 MPI ranks (tests/CMakeLists.txt, test_linear_solver_mpi2).
# A failed case fails; an MPI that cannot start two ranks on this machine (no doctest output at
# all: a container without shared memory, say) is reported as a skip with mpiexec's words, since
# it says nothing about plydem. Usage: run_mpi2.sh MPIEXEC SKIP_CODE BINARY ARGS...
set -uo pipefail
mpiexec="$1" skip="$2"
shift 2
output=$("$mpiexec" -n 2 "$@" 2>&1)
status=$?
printf '%s\n' "$output"
if ! grep -q 'doctest.*Status:' <<< "$output"; then
  echo "run_mpi2: mpiexec did not start the test on 2 ranks (exit $status): skipped"
  exit "$skip"
fi
exit "$status"
