#pragma once
/// \file
/// The one exception type plydem throws for bad input or an impossible request. Its message names
/// the problem in the user's terms; the command line prints it and exits non-zero.

#include <stdexcept>
#include <string>

namespace plydem {

class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& message) : std::runtime_error(message) {}
};

/// Throws Error(message) unless `condition` holds.
inline void require(bool condition, const std::string& message) {
  if (!condition) throw Error(message);
}

}  // namespace plydem
