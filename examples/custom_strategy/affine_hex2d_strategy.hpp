#pragma once
// hex2d-affine: the strategy of this example, used by its own program (custom_strategy.cpp) and by
// its plug-in (plugin.cpp), which `plydem --plugin` loads into the installed command.
//
// It is the Hex2D layer with the corrected eq. (27) springs as they are, without the relaxed
// correction: the closed form assumes that particles do not spin (ERRATA §3), so the model comes
// out slightly softer than its target, and the calibration report says by how much.
#include <fmt/format.h>

#include <numbers>
#include <string>
#include <vector>

#include "core/elasticity.hpp"
#include "core/error.hpp"
#include "core/homogenizer.hpp"
#include "packings/hexagonal_layer.hpp"
#include "strategies/hex2d.hpp"

namespace custom {

// Hex2dStrategy builds each coupon with calibrate_coupon(), which asks calibrate() for the springs
// by default, so overriding calibrate() is enough.
class AffineHex2dStrategy : public plydem::Hex2dStrategy {
 public:
  std::string description() const override {
    return "hexagonal layer with the corrected eq. (27) springs as they are (no spin "
           "relaxation): an example of a user-registered strategy";
  }

  plydem::Calibration calibrate(const plydem::Material& material, double ply_angle,
                                double thickness) const override {
    plydem::validate(material);
    plydem::Calibration cal;
    cal.method = "corrected eq. (27), affine (particles assumed not to spin)";
    cal.lattice_angle = ply_angle;  // family 1 along the fibre keeps the shear springs >= 0
    cal.target = plydem::rotate_reduced_stiffness(plydem::reduced_stiffness(material), ply_angle);
    const Eigen::Matrix3d in_lattice = plydem::rotate_reduced_stiffness(cal.target, -ply_angle);
    const plydem::UnitCell cell = plydem::HexagonalLayer(1.0, 0.0).unit_cell(thickness);
    std::vector<plydem::FamilyStiffness> families;
    for (const plydem::FamilyStiffness& k : plydem::hexagonal_springs_eq27(in_lattice, thickness)) {
      plydem::require(k.normal > 0 && k.shear >= 0,
                      "eq. (27) gives a negative spring for this material");
      // The unit cell has spacing 1 and bond radius 1/2: k_b = k_n / 16, k_t = k_s / 8.
      families.push_back({k.normal, k.shear, k.normal / 16, k.shear / 8});
    }
    for (int f = 0; f < 3; ++f) {
      cal.families.push_back(
          {fmt::format("{}", f + 1), ply_angle + f * std::numbers::pi / 3, families[f]});
    }
    cal.affine = plydem::rotate_reduced_stiffness(
        plydem::in_plane_block(plydem::affine_stiffness(cell, families)), ply_angle);
    // What the engine will simulate: spins relaxed.
    cal.relaxed = plydem::rotate_reduced_stiffness(
        plydem::in_plane_block(plydem::relaxed_stiffness(cell, families)), ply_angle);
    cal.relaxed_error = plydem::relative_difference(cal.relaxed, cal.target);
    return cal;
  }
};

}  // namespace custom
