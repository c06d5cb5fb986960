#pragma once
/// \file
/// The plydem command line without its main() (experiments/cli/main.cpp), so that the program, the
/// fuzz target tests/fuzz/fuzz_command_line.cpp and test_fuzz_regressions share one compiled copy.

/// Runs `plydem` with these arguments and returns its exit status (0 done, CLI11's code for a
/// parse error, 2 plydem::Error, 3 an internal error). `check_only` parses, refuses what does not
/// apply, converts the options to the tests' settings and estimates the coupon's memory, and
/// returns there: nothing runs and no plug-in is loaded.
int plydem_command_line(int argc, char** argv, bool check_only);
