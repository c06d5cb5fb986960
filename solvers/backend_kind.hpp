#pragma once
/// \file
/// The explicit integrator's backends by name, as a user chooses them (ExplicitSettings::backend,
/// `--backend`, Python's `backend`, a config's `explicit.backend`), like OpenMM's platforms: the
/// same run loop (solvers/explicit_integrator.hpp) over one backend interface (solvers/
/// explicit_backend.hpp), each backend holding the state in its own layout. No Eigen here: nvcc
/// compiles this header.

#include <string>
#include <vector>

namespace plydem {

/// Where the explicit integrator's cycles run.
enum class ExplicitBackend {
  kCpu,   ///< the host's SIMD kernel in kernel order, OpenMP threads (the default)
  kCuda,  ///< a CUDA device (a build with -DPLYDEM_CUDA=ON and a device present)
  /// the CUDA kernel's code (solvers/particle_step.hpp) run on the host, one particle at a time:
  /// the device's code path without a device (for tests and checks; slow)
  kDeviceEmulation,
  /// the plain loops over the model's own arrays: a scatter pass over the bonds
  /// (contacts/bond_kernel.hpp compute_bond_forces), then the shared update; one thread (slow)
  kReference,
};

/// "cpu", "cuda", "emulation", "reference".
const char* to_string(ExplicitBackend backend);
/// What the backend is, in a sentence (for `--help` and `plydem backends`).
const char* describe(ExplicitBackend backend);
/// Parses one of backend_choices(); throws plydem::Error naming them for anything else.
ExplicitBackend parse_backend(const std::string& name);
/// Every backend's name, in the order the command line's `--backend`, Python and the configs
/// offer them: "cpu", "cuda", "emulation", "reference".
const std::vector<std::string>& backend_choices();
/// parse_backend (the same choices; kept for the callers that named the user's choice apart).
ExplicitBackend parse_backend_choice(const std::string& name);
/// Every choice with what it is, quoted with `quote`: "'cpu' (SIMD kernel, OpenMP threads),
/// 'cuda' (...), 'emulation' (...) or 'reference' (...)", for help texts (--backend, Python).
std::string backend_help(const std::string& quote = "");
/// Whether the backend can run here; `why` gets the reason when it cannot (cuda: no CUDA backend
/// in this build, or no device).
bool backend_available(ExplicitBackend backend, std::string* why = nullptr);

}  // namespace plydem
