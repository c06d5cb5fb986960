#include "solvers/machine_rates.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <dlfcn.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <optional>
#include <thread>
#include <vector>

#include <Eigen/Dense>

#include "core/stopwatch.hpp"
#include "solvers/linear_solver.hpp"
#ifdef PLYDEM_HAVE_PETSC
#include "solvers/petsc_solver.hpp"
#endif

namespace plydem {
namespace {

// Repeats of each micro-benchmark; the best one counts (the others may meet a busy core).
constexpr int kRepeats = 3;
// Arrays of the memory benchmark: three of 2^21 doubles (48 MiB), more than the caches hold.
constexpr Eigen::Index kStreamLength = Eigen::Index{1} << 21;
// A product shorter than this many seconds is timed again at a larger size (a fast BLAS's threads
// need a large product to show their rate).
constexpr double kShortProduct = 0.01;

using Dgemm = void (*)(const char*, const char*, const int*, const int*, const int*, const double*,
                       const double*, const int*, const double*, const int*, const double*, double*,
                       const int*);

Eigen::MatrixXd test_matrix(int n, double shift) {
  Eigen::MatrixXd m(n, n);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) m(i, j) = 1.0 / (1.0 + i + 2 * j + shift);
  return m;
}

template <typename Product>
double product_gflops(Product product) {
  double best = 0;
  for (const int n : {256, 768}) {
    const Eigen::MatrixXd a = test_matrix(n, 0), b = test_matrix(n, 1);
    Eigen::MatrixXd c = Eigen::MatrixXd::Zero(n, n);
    double fastest = 1e300;
    for (int r = 0; r < kRepeats; ++r) {
      const Stopwatch clock;
      product(a, b, c);
      fastest = std::min(fastest, clock.seconds());
    }
    best = 2.0 * n * n * n / std::max(fastest, 1e-9) / 1e9;
    if (fastest > kShortProduct) break;
  }
  return best;
}

Dgemm loaded_dgemm() {
  // CHOLMOD's libraries are linked into the program, so its BLAS is loaded by now.
  return reinterpret_cast<Dgemm>(dlsym(RTLD_DEFAULT, "dgemm_"));
}

std::string blas_name() {
  using Config = char* (*)();
  using Threads = int (*)();
  const auto config = reinterpret_cast<Config>(dlsym(RTLD_DEFAULT, "openblas_get_config"));
  if (!config) return "reference BLAS";
  const auto threads = reinterpret_cast<Threads>(dlsym(RTLD_DEFAULT, "openblas_get_num_threads"));
  return fmt::format("OpenBLAS ({}, {} threads)", config(), threads ? threads() : 0);
}

std::string processor_name() {
  std::ifstream info("/proc/cpuinfo");
  std::string line;
  while (std::getline(info, line))
    if (line.rfind("model name", 0) == 0) {
      const auto colon = line.find(':');
      if (colon != std::string::npos) return line.substr(line.find_first_not_of(' ', colon + 1));
    }
  return "unknown processor";
}

std::string machine_key(const std::string& blas) {
  return fmt::format("{} | {} cores | {} | {} rank{}", processor_name(),
                     std::thread::hardware_concurrency(), blas, mpi_size(),
                     mpi_size() > 1 ? "s" : "");
}

std::optional<std::filesystem::path> cache_file() {
  if (const char* set = std::getenv("PLYDEM_MACHINE_RATES")) {
    if (std::string(set) == "none" || std::string(set).empty()) return std::nullopt;
    return std::filesystem::path(set);
  }
  if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg && *xdg)
    return std::filesystem::path(xdg) / "plydem" / "machine_rates.json";
  if (const char* home = std::getenv("HOME"); home && *home)
    return std::filesystem::path(home) / ".cache" / "plydem" / "machine_rates.json";
  return std::nullopt;
}

nlohmann::json read_cache(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) return nlohmann::json::object();
  const nlohmann::json j = nlohmann::json::parse(in, nullptr, false);
  return j.is_object() ? j : nlohmann::json::object();
}

std::optional<MachineRates> cached(const std::filesystem::path& file, const std::string& key) {
  const nlohmann::json j = read_cache(file);
  const auto it = j.find(key);
  if (it == j.end() || !it->is_object()) return std::nullopt;
  MachineRates r;
  r.eigen_gflops = it->value("eigen_gflops", 0.0);
  r.blas_gflops = it->value("blas_gflops", 0.0);
  r.memory_gbytes = it->value("memory_gbytes", 0.0);
  if (!(r.eigen_gflops > 0 && r.blas_gflops > 0 && r.memory_gbytes > 0)) return std::nullopt;
  r.source = fmt::format("cached in {}", file.string());
  return r;
}

// Adds this machine's entry; written to a file of its own and renamed over the cache, so that
// processes measuring at once leave a whole file. Returns whether it was written.
bool keep(const std::filesystem::path& file, const MachineRates& r) {
  std::error_code error;
  std::filesystem::create_directories(file.parent_path(), error);
  nlohmann::json j = read_cache(file);
  j[r.key] = {{"eigen_gflops", r.eigen_gflops},
              {"blas_gflops", r.blas_gflops},
              {"memory_gbytes", r.memory_gbytes}};
  const std::filesystem::path part = file.string() + fmt::format(".{}", getpid());
  {
    std::ofstream out(part);
    if (!(out << j.dump(2) << '\n')) return false;
  }
  std::filesystem::rename(part, file, error);
  if (error) std::filesystem::remove(part, error);
  return !error;
}

void share_from_root(MachineRates& r) {
#ifdef PLYDEM_HAVE_PETSC
  if (mpi_size() <= 1) return;
  double values[3] = {r.eigen_gflops, r.blas_gflops, r.memory_gbytes};
  broadcast_from_root(values, 3);
  r.eigen_gflops = values[0];
  r.blas_gflops = values[1];
  r.memory_gbytes = values[2];
  if (!is_root()) r.source = "rank 0's";
#else
  (void)r;
#endif
}

}  // namespace

MachineRates measure_machine_rates() {
  const Stopwatch clock;
  MachineRates r;
  r.blas = blas_name();
  r.key = machine_key(r.blas);
  r.eigen_gflops = product_gflops([](const Eigen::MatrixXd& a, const Eigen::MatrixXd& b,
                                     Eigen::MatrixXd& c) { c.noalias() = a * b; });
  const Dgemm dgemm = loaded_dgemm();
  r.blas_gflops =
      !dgemm ? r.eigen_gflops
             : product_gflops([dgemm](const Eigen::MatrixXd& a, const Eigen::MatrixXd& b,
                                      Eigen::MatrixXd& c) {
                 const int n = static_cast<int>(a.rows());
                 const double one = 1, zero = 0;
                 dgemm("N", "N", &n, &n, &n, &one, a.data(), &n, b.data(), &n, &zero, c.data(), &n);
               });
  Eigen::VectorXd a = Eigen::VectorXd::Zero(kStreamLength);
  const Eigen::VectorXd b = Eigen::VectorXd::Constant(kStreamLength, 1.0);
  const Eigen::VectorXd c = Eigen::VectorXd::Constant(kStreamLength, 2.0);
  double fastest = 1e300;
  for (int k = 0; k < kRepeats; ++k) {
    const Stopwatch stream;
    a.noalias() = b + 0.5 * c;
    fastest = std::min(fastest, stream.seconds());
    volatile double sink = a(k);  // the sums are used
    (void)sink;
  }
  r.memory_gbytes =
      3.0 * sizeof(double) * static_cast<double>(kStreamLength) / std::max(fastest, 1e-9) / 1e9;
  r.source = fmt::format("measured in {:.2f} s", clock.seconds());
  return r;
}

MachineRates machine_rates_from(const std::string& file) {
  const std::string blas = blas_name();
  const std::string key = machine_key(blas);
  MachineRates r;
  if (is_root()) {
    if (!file.empty())
      if (std::optional<MachineRates> found = cached(file, key)) r = *found;
    if (!(r.eigen_gflops > 0)) {
      r = measure_machine_rates();
      if (!file.empty() && keep(file, r)) r.source += fmt::format(", kept in {}", file);
    }
  }
  share_from_root(r);
  r.blas = blas;
  r.key = key;
  return r;
}

const MachineRates& machine_rates() {
  static std::once_flag once;
  static MachineRates rates;
  std::call_once(once, [] {
    const std::optional<std::filesystem::path> file = cache_file();
    rates = machine_rates_from(file ? file->string() : std::string());
  });
  return rates;
}

}  // namespace plydem
