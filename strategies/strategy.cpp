#include "strategies/strategy.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <numbers>

#include "core/elasticity.hpp"
#include "core/error.hpp"
#include "core/stopwatch.hpp"
#include "core/units.hpp"

namespace plydem {

void CouponSpec::validate() const {
  const std::pair<const char*, double> sizes[] = {{"length", length},
                                                  {"width", width},
                                                  {"thickness", thickness},
                                                  {"particle diameter", particle_diameter}};
  for (const auto& [name, value] : sizes) {
    require(std::isfinite(value), fmt::format("coupon {} is not a finite number", name));
    require(value > 0,
            fmt::format("coupon {} must be positive, got {} mm", name, value * kMmPerMetre));
  }
  require(std::isfinite(ply_angle), "ply angle is not a finite number");
  require(length >= 4 * particle_diameter && width >= particle_diameter,
          fmt::format("a {} mm x {} mm coupon is too small for particles of diameter {} mm "
                      "(need length >= 4 and width >= 1 diameter)",
                      length * kMmPerMetre, width * kMmPerMetre, particle_diameter * kMmPerMetre));
}

namespace {

std::atomic<long> calibration_count{0};
std::atomic<long> build_count{0};

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
  const Stopwatch clock;
  coupon.validate();
  Calibration calibration = calibrate_coupon(coupon);
  count_build_work(1, 0);
  Specimen specimen = build(coupon, calibration);
  specimen.build_seconds = clock.seconds();
  return specimen;
}

Specimen Strategy::build(const CouponSpec& coupon, const Calibration& calibration) const {
  const Stopwatch clock;
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
  specimen.build_seconds = clock.seconds();
  return specimen;
}

std::optional<PackingEstimate> Strategy::estimate_packing(const CouponSpec& coupon) const {
  coupon.validate();
  const std::optional<UnitCell> found = unit_cell(Calibration{}, coupon.thickness);
  if (!found || found->basis.empty() || found->radius.empty()) return std::nullopt;
  const UnitCell& cell = *found;
  // The cell's length unit: its particle diameter is the coupon's.
  const double scale = coupon.particle_diameter / (2 * cell.radius[0]);
  const double area =
      std::abs(
          cell.lattice_vectors.col(0).head<2>().x() * cell.lattice_vectors.col(1).head<2>().y() -
          cell.lattice_vectors.col(0).head<2>().y() * cell.lattice_vectors.col(1).head<2>().x()) *
      scale * scale;
  const double spacing = std::sqrt(area);
  // Centres fill [r, L - r] x [r, W - r]; lattice points in an a x b rectangle, with half a
  // spacing for the rows its edges catch (exact on average between aligned and turned lattices).
  const double a = coupon.length - coupon.particle_diameter;
  const double b = coupon.width - coupon.particle_diameter;
  auto points = [&](double along, double across) {
    return std::max(0.0, along + 0.5 * spacing) * std::max(0.0, across + 0.5 * spacing) / area;
  };
  const double n = static_cast<double>(cell.basis.size());
  PackingEstimate e;
  e.particles = n * points(a, b);
  for (int k = 0; k < static_cast<int>(cell.bonds.size()); ++k) {
    const Eigen::Vector3d branch = cell.branch(k) * scale;
    e.bonds += points(a - std::abs(branch.x()), b - std::abs(branch.y()));
  }
  double z_min = cell.basis[0].z(), z_max = z_min;
  for (const Eigen::Vector3d& x : cell.basis) {
    z_min = std::min(z_min, x.z());
    z_max = std::max(z_max, x.z());
  }
  int top = 0, bottom = 0;
  std::vector<double> layer_heights;
  for (const Eigen::Vector3d& x : cell.basis) {
    top += x.z() >= z_max - cell.radius[0] ? 1 : 0;
    bottom += x.z() <= z_min + cell.radius[0] ? 1 : 0;
    bool seen = false;
    for (double z : layer_heights) seen = seen || std::abs(z - x.z()) < 1e-9 * cell.radius[0];
    if (!seen) layer_heights.push_back(x.z());
  }
  e.top_surface_particles = top * points(a, b);
  e.bottom_surface_density = bottom / area;
  e.layers = static_cast<int>(layer_heights.size());
  return e;
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
