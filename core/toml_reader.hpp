#pragma once
/// \file
/// TOML text (toml++) read into a table with plydem's errors: the one place plydem includes
/// toml++, for the material files (core/material.cpp) and the experiment configs
/// (experiments/runner/experiment.cpp). Each keeps the words of its own syntax errors.

// Debian's libtomlplusplus-dev ships a compiled shared library, but its headers default to
// header-only mode (TOML_HEADER_ONLY=1) unless the build passes the flags from tomlplusplus.pc or
// the tomlplusplus::tomlplusplus CMake target (-DTOML_HEADER_ONLY=0 -DTOML_SHARED_LIB=1). Default
// to the compiled library so that a plain `-ltomlplusplus` link works and the parser is not
// re-instantiated in each translation unit; a build that sets the flags itself wins.
#ifndef TOML_HEADER_ONLY
#define TOML_HEADER_ONLY 0
#ifndef TOML_SHARED_LIB
#define TOML_SHARED_LIB 1
#endif
#endif
#include <toml++/toml.h>

#include <functional>
#include <optional>
#include <string>
#include <string_view>

namespace plydem {

/// Where a TOML text stops parsing, and why (toml++'s words).
struct TomlSyntaxError {
  toml::source_index line = 0;
  toml::source_index column = 0;
  std::string_view description;
};

/// The message of the plydem::Error that a syntax error becomes.
using TomlErrorMessage = std::function<std::string(const TomlSyntaxError&)>;

/// The table of `text`, which came from `origin` (the file name toml++ keeps in its source
/// regions); a syntax error throws plydem::Error(message(error)).
toml::table parse_toml(std::string_view text, std::string_view origin,
                       const TomlErrorMessage& message);

/// The table of the file `path`, read by toml++; errors as parse_toml().
toml::table parse_toml_file(const std::string& path, const TomlErrorMessage& message);

/// A TOML number as a double: a floating-point value or an integer (E1 = 45600000000 is a fine
/// modulus); nothing for any other type.
std::optional<double> toml_number(const toml::node& node);

}  // namespace plydem
