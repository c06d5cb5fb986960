#include "strategies/specimen.hpp"

#include <fmt/format.h>

#include "core/error.hpp"
#include "core/progress.hpp"
#include "core/stopwatch.hpp"

namespace plydem {

FamilyStiffnessRule parallel_bond_rule(double bond_radius) {
  return [bond_radius](double normal, double shear) {
    const double r2 = bond_radius * bond_radius;
    return FamilyStiffness{normal, shear, normal * r2 / 4.0, shear * r2 / 2.0};
  };
}

Model assemble_specimen(const SpecimenLayout& layout,
                        const std::vector<FamilyCalibration>* families) {
  const int n = static_cast<int>(layout.position.rows());
  require(n >= 2, "the coupon holds fewer than two particles");
  const int bond_count = static_cast<int>(layout.pairs.size());
  require(layout.family.empty() || static_cast<int>(layout.family.size()) == bond_count,
          "a specimen layout needs one family per bond");

  Model model;
  model.thickness = layout.thickness;
  model.description = layout.description;
  Particles& p = model.particles;
  p.resize(n);
  p.reference_position = layout.position;
  const double mass = layout.density * layout.particle_volume;
  p.radius.setConstant(layout.radius);
  p.volume.setConstant(layout.particle_volume);
  p.mass.setConstant(mass);
  p.moment_of_inertia.setConstant(0.4 * mass * layout.radius * layout.radius);  // solid sphere

  Bonds& bonds = model.bonds;
  bonds.resize(bond_count);
  // The springs scale with the bond radius only through bending and twisting.
  const FamilyStiffnessRule rule = parallel_bond_rule(layout.radius);
  ProgressMeter meter("building the coupon: bonds", bond_count, "bonds");
  for (int b = 0; b < bond_count; ++b) {
    if (b % 4096 == 0) meter.update(b);
    bonds.first(b) = layout.pairs[b].first;
    bonds.second(b) = layout.pairs[b].second;
    const int f = layout.family.empty() ? 0 : layout.family[b];
    bonds.family(b) = f;
    if (families) {
      if (!(f >= 0 && f < static_cast<int>(families->size()))) {
        throw Error(fmt::format("bond {} has family {}, but the calibration has {} families", b, f,
                                families->size()));
      }
      const FamilyStiffness& k = (*families)[f].stiffness;
      const FamilyStiffness full = rule(k.normal, k.shear);
      bonds.normal_stiffness(b) = full.normal;
      bonds.shear_stiffness(b) = full.shear;
      bonds.bending_stiffness(b) = full.bending;
      bonds.twisting_stiffness(b) = full.twisting;
    }
    set_bond_geometry(p, bonds, b);
  }
  return model;
}

const Calibration& SpecimenBuilder::calibration(const CouponSpec& coupon) {
  coupon.validate();
  const std::string key = strategy_.calibration_key(coupon);
  auto it = calibrations_.find(key);
  if (it == calibrations_.end()) {
    it = calibrations_.emplace(key, strategy_.calibrate_coupon(coupon)).first;
    ++statistics_.calibrations;
    count_build_work(1, 0);
  }
  return it->second;
}

std::string SpecimenBuilder::ply_key(const CouponSpec& coupon) const {
  // Hexadecimal floats: equal keys mean equal numbers, bit for bit.
  return fmt::format("{}|length {:a}|width {:a}|diameter {:a}|edges {}",
                     strategy_.calibration_key(coupon), coupon.length, coupon.width,
                     coupon.particle_diameter, coupon.complete_boundary_cells ? 1 : 0);
}

const Specimen& SpecimenBuilder::ply(const CouponSpec& coupon) {
  coupon.validate();
  const std::string key = ply_key(coupon);
  auto it = plies_.find(key);
  if (it == plies_.end()) it = plies_.emplace(key, build(coupon)).first;
  return it->second;
}

Specimen SpecimenBuilder::build(const CouponSpec& coupon) {
  const Stopwatch clock;
  const Calibration& cal = calibration(coupon);
  Specimen specimen = strategy_.build(coupon, cal);
  ++statistics_.builds;
  specimen.build_seconds = clock.seconds();
  return specimen;
}

}  // namespace plydem
