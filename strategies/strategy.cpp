#include "strategies/strategy.hpp"

#include <fmt/format.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <numbers>

#include "core/elasticity.hpp"
#include "core/error.hpp"

namespace plydem {

void CouponSpec::validate() const {
  const std::pair<const char*, double> sizes[] = {{"length", length},
                                                  {"width", width},
                                                  {"thickness", thickness},
                                                  {"particle diameter", particle_diameter}};
  for (const auto& [name, value] : sizes) {
    require(std::isfinite(value), fmt::format("coupon {} is not a finite number", name));
    require(value > 0, fmt::format("coupon {} must be positive, got {} mm", name, value * 1e3));
  }
  require(std::isfinite(ply_angle), "ply angle is not a finite number");
  require(length >= 4 * particle_diameter && width >= particle_diameter,
          fmt::format("a {} mm x {} mm coupon is too small for particles of diameter {} mm "
                      "(need length >= 4 and width >= 1 diameter)",
                      length * 1e3, width * 1e3, particle_diameter * 1e3));
}

namespace {

std::atomic<long> calibration_count{0};
std::atomic<long> build_count{0};

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

BuildStatistics build_statistics() {
  return {calibration_count.load(), build_count.load()};
}

void count_build_work(long calibrations, long builds) {
  calibration_count += calibrations;
  build_count += builds;
}

Calibration Strategy::calibrate_coupon(const CouponSpec& coupon) const {
  return calibrate(coupon.material, coupon.ply_angle, coupon.thickness);
}

std::string Strategy::calibration_key(const CouponSpec& coupon) const {
  const Material& m = coupon.material;
  // Hexadecimal floats: equal keys mean equal numbers, bit for bit.
  std::string key =
      fmt::format("{}|{:a}|{:a}|{:a}|{:a}|{:a}|{:a}|angle {:a}|thickness {:a}", m.name, m.E1, m.E2,
                  m.G12, m.nu12, m.nu23, m.density, coupon.ply_angle, coupon.thickness);
  for (const StrategyOption& option : options()) {
    key += fmt::format("|{} {:a}", option.name, option.value);
  }
  return key;
}

Specimen Strategy::build(const CouponSpec& coupon) const {
  const auto start = std::chrono::steady_clock::now();
  coupon.validate();
  Calibration calibration = calibrate_coupon(coupon);
  count_build_work(1, 0);
  Specimen specimen = build(coupon, calibration);
  specimen.build_seconds = seconds_since(start);
  return specimen;
}

Specimen Strategy::build(const CouponSpec& coupon, const Calibration& calibration) const {
  const auto start = std::chrono::steady_clock::now();
  coupon.validate();
  if (calibration.target.norm() > 0) {
    const Eigen::Matrix3d target =
        rotate_reduced_stiffness(reduced_stiffness(coupon.material), coupon.ply_angle);
    require((calibration.target - target).norm() <= 1e-12 * target.norm(),
            fmt::format("the calibration given for the coupon of material '{}' at {:.4g} deg has "
                        "another target stiffness: it was computed for another ply",
                        coupon.material.name, coupon.ply_angle * 180 / std::numbers::pi));
  }
  Specimen specimen;
  specimen.model = assemble(coupon, calibration);
  specimen.ply_calibrations.push_back(calibration);
  count_build_work(0, 1);
  specimen.build_seconds = seconds_since(start);
  return specimen;
}

void Strategy::set_option(const std::string& name, double value) {
  std::string known;
  for (const StrategyOption& option : options()) {
    known += known.empty() ? option.name : fmt::format(", {}", option.name);
  }
  throw Error(fmt::format(
      "this strategy has no option '{}' (value {}); {}", name, value,
      known.empty() ? std::string("it takes no options") : fmt::format("its options: {}", known)));
}

}  // namespace plydem
