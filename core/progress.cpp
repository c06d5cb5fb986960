#include "core/progress.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <utility>

#include "core/error.hpp"

namespace plydem {

namespace {
std::atomic<double> interval_seconds{2.0};
}  // namespace

void set_progress_interval(double seconds) {
  require(std::isfinite(seconds) && seconds >= 0,
          fmt::format("the progress interval must be a non-negative number of seconds, got {}",
                      seconds));
  interval_seconds = seconds;
}

double progress_interval() {
  return interval_seconds.load();
}

ProgressMeter::ProgressMeter(std::string what, double total, std::string unit)
    : what_(std::move(what)),
      unit_(std::move(unit)),
      total_(total),
      interval_(progress_interval()) {}

void ProgressMeter::update(double done) {
  update(done, std::string());
}

void ProgressMeter::update(double done, const std::string& detail) {
  if (since_report_.seconds() < interval_) return;
  if (!spdlog::default_logger_raw()->should_log(spdlog::level::info)) return;
  const double elapsed = since_start_.seconds();
  since_report_.restart();
  reported_ = true;
  const std::string tail = detail.empty() ? std::string() : ", " + detail;
  if (total_ > 0) {
    const double fraction = std::min(1.0, std::max(0.0, done / total_));
    const std::string left =
        fraction > 0 ? fmt::format(", about {:.0f} s left", elapsed * (1 - fraction) / fraction)
                     : std::string();
    if (unit_.empty()) {
      spdlog::info("{}: {:.0f}%, {:.0f} s{}{}", what_, 100 * fraction, elapsed, left, tail);
    } else {
      spdlog::info("{}: {:.0f} of {:.0f} {} ({:.0f}%), {:.0f} s{}{}", what_, done, total_, unit_,
                   100 * fraction, elapsed, left, tail);
    }
  } else {
    spdlog::info("{}: {:.0f} {}, {:.0f} s{}", what_, done, unit_, elapsed, tail);
  }
}

}  // namespace plydem
