#pragma once
/// \file
/// What the fuzz targets (tests/fuzz/fuzz_*.cpp, libFuzzer) and the regression test
/// (tests/test_fuzz_regressions.cpp) feed their inputs through: one function per reader. Each reads
/// the bytes as its reader's input, and returns normally when the reader accepted it or refused it
/// with plydem::Error; anything else (another exception, a crash, a sanitizer report, a hang) is a
/// bug.

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "core/error.hpp"

namespace plydem::fuzz {

/// Runs `read`; plydem::Error is a refusal, which is fine.
template <class F>
void refused_or_accepted(F&& read) {
  try {
    read();
  } catch (const Error&) {
  }
}

/// A material file's TOML text (core/material.hpp parse_material).
void material(std::string_view input);
/// An experiment config's TOML text (experiments/runner/experiment.hpp ExperimentConfig::parse),
/// then its getters and the known-key check.
void experiment_config(std::string_view input);
/// A layup string (strategies/laminate.hpp parse_layup), written back by format_layup.
void layup(std::string_view input);
/// A command line, one argument per line (or NUL-separated), after `plydem`: parsed, checked and
/// converted to settings as `plydem` does before it runs anything (plydem_command_line with
/// check_only), the coupon's memory estimated.
void command_line(std::string_view input);

/// Each entry lives in its own file (fuzz_TARGET.cpp), so that a fuzz target links only its
/// reader's sources (tests/fuzz/CMakeLists.txt).
/// The function for a target's name ("material", "experiment_config", "layup", "command_line");
/// nullptr for another name.
using Entry = void (*)(std::string_view);
Entry entry(const std::string& target);

}  // namespace plydem::fuzz
