#pragma once
/// \file
/// Wall-clock seconds of a phase (std::chrono::steady_clock): the one stopwatch behind the
/// phase timings the solvers, strategies and benchmarks report.
///
///   Stopwatch phase;
///   assemble();
///   seconds.assembly = phase.lap();  // and the next phase starts now
///   factorize();
///   seconds.factorization = phase.seconds();

#include <chrono>

namespace plydem {

class Stopwatch {
 public:
  using Clock = std::chrono::steady_clock;

  /// Starts now.
  Stopwatch() : start_(Clock::now()) {}

  /// Seconds since the start.
  double seconds() const { return std::chrono::duration<double>(Clock::now() - start_).count(); }

  /// Seconds since the start, and starts again now.
  double lap() {
    const Clock::time_point now = Clock::now();
    const double elapsed = std::chrono::duration<double>(now - start_).count();
    start_ = now;
    return elapsed;
  }

  /// Starts again now.
  void restart() { start_ = Clock::now(); }

 private:
  Clock::time_point start_;
};

/// Seconds since `start`, for code that keeps time points of Stopwatch::Clock (a progress meter's
/// last report, a run's start held in a struct).
inline double seconds_since(Stopwatch::Clock::time_point start) {
  return std::chrono::duration<double>(Stopwatch::Clock::now() - start).count();
}

/// Seconds from `from` to `to`.
inline double seconds_between(Stopwatch::Clock::time_point from, Stopwatch::Clock::time_point to) {
  return std::chrono::duration<double>(to - from).count();
}

}  // namespace plydem
