#pragma once
/// \file
/// Progress of long phases on the log (spdlog, info: the command line's stderr), throttled: a
/// phase that ends within progress_interval() seconds (default 2) says nothing, a longer one says
/// what it does, how far it is and, where the total is known, about how long it has left, once per
/// interval. `plydem --quiet` raises the log level above info, which silences it; an interval of 0
/// reports every update (tests).
///
///   ProgressMeter meter("building the coupon: lattice rows", rows, "rows");
///   for (long i = 0; i < rows; ++i) { ...; meter.update(i + 1); }

#include <string>

#include "core/stopwatch.hpp"

namespace plydem {

/// Seconds before a phase's first report and between reports (process-wide; default 2). Throws
/// plydem::Error for a negative or non-finite value.
void set_progress_interval(double seconds);
double progress_interval();

class ProgressMeter {
 public:
  /// `what` the phase ("factorizing K (182,000 unknowns)"); `total` its work in `unit`s, <= 0 when
  /// unknown (then no time left is given); an empty `unit` reports percentages only.
  ProgressMeter(std::string what, double total, std::string unit);
  /// `done` of the total so far: logs one line when due (see the file comment).
  void update(double done);
  /// The same with `detail` appended to the line ("relative error 3e-4").
  void update(double done, const std::string& detail);
  /// Whether the meter has written a line.
  bool reported() const { return reported_; }

 private:
  std::string what_, unit_;
  double total_ = 0;
  double interval_ = 2;
  Stopwatch since_start_, since_report_;
  bool reported_ = false;
};

}  // namespace plydem
