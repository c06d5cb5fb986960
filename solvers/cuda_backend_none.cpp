// A build without the CUDA backend (-DPLYDEM_CUDA=OFF, or no CUDA compiler found): asking for it is
// a clear error, never a silent run on the host.
#include "core/error.hpp"
#include "solvers/device_backend.hpp"

namespace plydem {

bool cuda_available(std::string* why) {
  if (why)
    *why =
        "this build of plydem has no CUDA backend (configure with -DPLYDEM_CUDA=ON where CUDA's "
        "nvcc is installed)";
  return false;
}

std::unique_ptr<DeviceBackend> make_cuda_backend() {
  std::string why;
  cuda_available(&why);
  throw Error("--backend cuda: " + why);
}

double cuda_copy_bandwidth(std::size_t) {
  make_cuda_backend();  // throws
  return 0;
}

}  // namespace plydem
