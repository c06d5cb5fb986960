#include "strategies/hex2d.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "core/elasticity.hpp"
#include "core/error.hpp"
#include "core/units.hpp"
#include "packings/hexagonal_layer.hpp"
#include "strategies/boundary_cells.hpp"
#include "strategies/calibration.hpp"
#include "strategies/registry.hpp"
#include "strategies/specimen.hpp"

namespace plydem {
namespace {}  // namespace

std::array<FamilyStiffness, 3> hexagonal_springs_eq27(const Eigen::Matrix3d& c, double thickness) {
  const double s3 = std::sqrt(3.0);
  const double c11 = c(0, 0), c22 = c(1, 1), c12 = c(0, 1), c16 = c(0, 2), c26 = c(1, 2),
               c66 = c(2, 2);
  const double d = thickness;
  std::array<FamilyStiffness, 3> k{};
  // eq. (27), corrected: k_n2,3 use C12 + C22, not C11 + C22 (ERRATA §2).
  k[0].normal = s3 / 6.0 * (3 * c11 + 2 * c12 - c22) * d;
  k[1].normal = s3 / 3.0 * (c12 + c22 + s3 * c16 + s3 * c26) * d;
  k[2].normal = s3 / 3.0 * (c12 + c22 - s3 * c16 - s3 * c26) * d;
  k[0].shear = 2.0 * s3 / 3.0 * (3 * c66 - c22) * d;
  k[1].shear = s3 / 3.0 * (c22 - 3 * c12 + 3 * s3 * c16 - s3 * c26) * d;
  k[2].shear = s3 / 3.0 * (c22 - 3 * c12 - 3 * s3 * c16 + s3 * c26) * d;
  return k;
}

std::array<FamilyStiffness, 3> hexagonal_springs_eq27_as_printed(const Eigen::Matrix3d& c,
                                                                 double thickness) {
  std::array<FamilyStiffness, 3> k = hexagonal_springs_eq27(c, thickness);
  const double s3 = std::sqrt(3.0);
  const double c16_26 = s3 * (c(0, 2) + c(1, 2));
  k[1].normal = s3 / 3.0 * (c(0, 0) + c(1, 1) + c16_26) * thickness;
  k[2].normal = s3 / 3.0 * (c(0, 0) + c(1, 1) - c16_26) * thickness;
  return k;
}

HexagonalRelaxedSprings hexagonal_springs_relaxed(const Eigen::Matrix3d& c, double thickness) {
  const std::array<FamilyStiffness, 3> affine = hexagonal_springs_eq27(c, thickness);
  HexagonalRelaxedSprings k;
  const double sum = affine[0].shear + affine[1].shear + affine[2].shear;
  for (int i = 0; i < 3; ++i) {
    k.normal[i] = affine[i].normal;
    k.weight[i] = (2 * sum / 3 - affine[i].shear) / 3;
  }
  k.reachable = std::all_of(k.normal.begin(), k.normal.end(), [](double v) { return v > 0; }) &&
                std::all_of(k.weight.begin(), k.weight.end(), [](double v) { return v > 0; });
  if (!k.reachable) return k;
  // w_jk = k_j k_k / K gives k_i^2 / K = w_ij w_ik / w_jk.
  std::array<double, 3> root{};
  for (int i = 0; i < 3; ++i) {
    root[i] = std::sqrt(k.weight[(i + 1) % 3] * k.weight[(i + 2) % 3] / k.weight[i]);
  }
  const double sqrt_total = root[0] + root[1] + root[2];
  for (int i = 0; i < 3; ++i) k.shear[i] = sqrt_total * root[i];
  return k;
}

std::string hexagonal_relaxed_limits(const Eigen::Matrix3d& c) {
  const double c11 = c(0, 0) * kGPaPerPa, c22 = c(1, 1) * kGPaPerPa, c12 = c(0, 1) * kGPaPerPa,
               c66 = c(2, 2) * kGPaPerPa;
  std::string violated;
  auto check = [&](bool holds, const std::string& condition) {
    if (!holds) violated += fmt::format("{}{}", violated.empty() ? "" : "; ", condition);
  };
  // In the fibre frame (C16 = C26 = 0): k_n1 > 0, k_n2,3 > 0, w_1 > 0, w_2,3 > 0.
  check(3 * c11 + 2 * c12 > c22,
        fmt::format("3*C11 + 2*C12 > C22 (here {:.4g} <= {:.4g} GPa)", 3 * c11 + 2 * c12, c22));
  check(c12 + c22 > 0, fmt::format("C12 + C22 > 0 (here {:.4g} GPa)", c12 + c22));
  check(c66 < c22 - 2 * c12,
        fmt::format("C66 < C22 - 2*C12 (here C66 = {:.4g} >= {:.4g} GPa: the fibre bonds' shear "
                    "springs would have to stop the spin, which freely spinning particles only "
                    "approach as k_s1 grows without bound)",
                    c66, c22 - 2 * c12));
  check(4 * c66 > c22 + c12,
        fmt::format("4*C66 > C22 + C12 (here {:.4g} <= {:.4g} GPa)", 4 * c66, c22 + c12));
  return fmt::format(
      "a hexagonal layer of spinning particles with the fibre along a bond family needs, in the "
      "fibre frame, {}",
      violated.empty() ? std::string("every spring positive") : violated);
}

std::string Hex2dStrategy::description() const {
  return "extended 2D hexagonal layer (paper Sec. 3.3): 6 neighbours, family 1 along the fibre, "
         "corrected eq. (27) then relaxed calibration";
}

Calibration Hex2dStrategy::calibrate(const Material& material, double ply_angle,
                                     double thickness) const {
  validate(material);
  require(std::isfinite(ply_angle), "ply angle is not finite");
  require(std::isfinite(thickness) && thickness > 0,
          fmt::format("ply thickness must be positive, got {} m", thickness));
  Calibration cal;
  cal.method = "hex2d: corrected eq. (27) inverted for spinning particles (closed form)";
  cal.lattice_angle = ply_angle;  // family 1 along the fibre
  cal.target = rotate_reduced_stiffness(reduced_stiffness(material), ply_angle);
  // In the lattice frame the target is the ply's own Q whatever the ply angle.
  const Eigen::Matrix3d target_lattice = rotate_reduced_stiffness(cal.target, -cal.lattice_angle);
  const HexagonalLayer lattice_frame(1.0, 0.0);  // stiffness is independent of the spacing
  const UnitCell cell = lattice_frame.unit_cell(thickness);
  const FamilyStiffnessRule rule = parallel_bond_rule(0.5);
  const HexagonalRelaxedSprings springs = hexagonal_springs_relaxed(target_lattice, thickness);
  if (!springs.reachable) {
    // The nearest reachable stiffness: the relaxed layer's stiffness is linear in (k_n, w), and
    // k_n, w >= 0 is the closure of what non-negative springs give, so the nearest is a
    // non-negative least squares (w at 0 is the limit of a fibre family's k_s growing without
    // bound).
    Eigen::Matrix3d basis[6];
    Eigen::Matrix<double, 6, 6> a;
    for (int j = 0; j < 6; ++j) {
      std::vector<FamilyStiffness> k(3);
      for (int f = 0; f < 3; ++f) {
        if (j < 3) k[f].normal = f == j ? 1.0 : 0.0;
        // w opposite family j - 3: the affine shear springs D_i = 2(w_ij + w_ik) - w_jk.
        if (j >= 3) k[f].shear = f == j - 3 ? -1.0 : 2.0;
      }
      basis[j] = in_plane_block(affine_stiffness(cell, k));
      a.col(j) = frobenius_entries(basis[j]);
    }
    const Eigen::VectorXd x = non_negative_least_squares(a, frobenius_entries(target_lattice));
    Unreachable refusal;
    refusal.strategy = "hex2d";
    refusal.material = material.name;
    refusal.ply_angle = ply_angle;
    refusal.frame = "fibre frame";
    refusal.target = target_lattice;
    for (int j = 0; j < 6; ++j) refusal.nearest += x(j) * basis[j];
    refusal.reason = hexagonal_relaxed_limits(target_lattice);
    refuse_unreachable(std::move(refusal), material, thickness);
  }
  std::vector<FamilyStiffness> start_families;
  for (int f = 0; f < 3; ++f) {
    start_families.push_back(rule(springs.normal[f], springs.shear[f]));
  }
  // The closed form is exact; Gauss-Newton only polishes its round-off.
  const RelaxedCalibration relaxed =
      calibrate_relaxed_layer(cell, target_lattice, start_families, rule);
  const char* names[3] = {"1 (0 deg, fibre)", "2 (+60 deg)", "3 (+120 deg)"};
  for (int f = 0; f < 3; ++f) {
    cal.families.push_back(
        {names[f], cal.lattice_angle + f * std::numbers::pi / 3.0, relaxed.families[f]});
  }
  // A reachable target is reached: anything else is a bug, not the user's ply.
  if (!(relaxed.relative_error < 1e-9) ||
      !std::all_of(relaxed.families.begin(), relaxed.families.end(),
                   [](const FamilyStiffness& k) { return k.normal > 0 && k.shear > 0; })) {
    throw std::logic_error(fmt::format(
        "hex2d: the relaxed inverse of eq. (27) missed material '{}' at {:.4g} deg (relative "
        "error {:.3g})",
        material.name, ply_angle / kDegree, relaxed.relative_error));
  }
  cal.affine = rotate_reduced_stiffness(in_plane_block(affine_stiffness(cell, relaxed.families)),
                                        cal.lattice_angle);
  cal.relaxed = rotate_reduced_stiffness(relaxed.relaxed, cal.lattice_angle);
  cal.relaxed_error = relative_difference(cal.relaxed, cal.target);
  return cal;
}

Model Hex2dStrategy::assemble(const CouponSpec& coupon, const Calibration& cal) const {
  const HexagonalLayer layer(coupon.particle_diameter, cal.lattice_angle);
  SpecimenLayout layout;
  layout.position = layer.fill_rectangle(coupon.length, coupon.width);
  const HexagonalLayer::Graph graph = layer.bond_graph(layout.position);
  layout.pairs = graph.pairs;
  layout.family = graph.family;
  layout.radius = 0.5 * coupon.particle_diameter;
  layout.particle_volume = layer.cell_area() * coupon.thickness;
  layout.density = coupon.material.density;
  layout.thickness = coupon.thickness;
  layout.description = fmt::format("hex2d layer, ply angle {:.4g} deg, {} particles",
                                   coupon.ply_angle / kDegree, layout.position.rows());
  Model model = assemble_specimen(layout, &cal.families);
  treat_free_edges(model, coupon, cal, *unit_cell(cal, coupon.thickness),
                   HexagonalLayer::kFamilyCount, edge_treatment_);
  model.check_consistency();
  return model;
}

std::vector<StrategyOption> Hex2dStrategy::options() const {
  return {edge_treatment_option(edge_treatment_)};
}

void Hex2dStrategy::set_option(const std::string& name, double value) {
  if (name != "edge_equilibrium") {
    Strategy::set_option(name, value);
    return;
  }
  edge_treatment_ = parse_edge_treatment("hex2d", value);
}

BoundaryCompletion Hex2dStrategy::boundary_completion() const {
  return {HexagonalLayer::kFamilyCount, 2};
}

std::optional<UnitCell> Hex2dStrategy::unit_cell(const Calibration& calibration,
                                                 double thickness) const {
  // calibrate() solves on a cell of unit spacing with the bond radius 1/2 (parallel_bond_rule);
  // assemble() numbers the coupon's families as HexagonalLayer at the same lattice angle.
  return HexagonalLayer(1.0, calibration.lattice_angle).unit_cell(thickness);
}

std::string Hex2dPaperStrategy::description() const {
  return "hex2d as the paper prints it: lattice along x, eq. (27) as printed (C11 + C22), no "
         "relaxation; for comparison, not for use";
}

Calibration Hex2dPaperStrategy::calibrate(const Material& material, double ply_angle,
                                          double thickness) const {
  validate(material);
  require(std::isfinite(ply_angle), "ply angle is not finite");
  require(std::isfinite(thickness) && thickness > 0,
          fmt::format("ply thickness must be positive, got {} m", thickness));
  Calibration cal;
  cal.method = "hex2d-paper: eq. (27) as printed, particles assumed not to spin";
  cal.target = rotate_reduced_stiffness(reduced_stiffness(material), ply_angle);
  const UnitCell cell = HexagonalLayer(1.0, 0.0).unit_cell(thickness);
  const FamilyStiffnessRule rule = parallel_bond_rule(0.5);
  // The paper's lattice has family 1 along x; for the 90 deg ply it swaps x and y (Sec. 3.3),
  // which turns the lattice by 90 deg.
  std::string refused;
  for (const double lattice_angle : {0.0, std::numbers::pi / 2}) {
    const Eigen::Matrix3d in_lattice = rotate_reduced_stiffness(cal.target, -lattice_angle);
    const auto springs = hexagonal_springs_eq27_as_printed(in_lattice, thickness);
    std::vector<FamilyStiffness> families;
    for (int f = 0; f < 3 && refused.empty(); ++f) {
      if (!(springs[f].normal > 0 && springs[f].shear >= 0)) {
        refused = fmt::format("family {} at {:g} deg: k_n = {:.4g} N/m, k_s = {:.4g} N/m", f + 1,
                              (lattice_angle + f * std::numbers::pi / 3) / kDegree,
                              springs[f].normal, springs[f].shear);
      }
      families.push_back(rule(springs[f].normal, springs[f].shear));
    }
    if (!refused.empty() && lattice_angle == 0) {
      refused.clear();
      continue;
    }
    if (!refused.empty()) {
      throw Error(fmt::format(
          "hex2d-paper: eq. (27) as printed gives a negative spring for material '{}' at {:.4g} "
          "deg with the lattice along x and along y ({}): a negative spring makes the lattice "
          "unstable, so it is not run (the paper's remark on 30 and 90 deg; the strategy hex2d "
          "turns the lattice with the fibre instead)",
          material.name, ply_angle / kDegree, refused));
    }
    cal.lattice_angle = lattice_angle;
    const char* names[3] = {"1", "2 (+60 deg)", "3 (+120 deg)"};
    for (int f = 0; f < 3; ++f) {
      cal.families.push_back({names[f], lattice_angle + f * std::numbers::pi / 3, families[f]});
    }
    cal.affine =
        rotate_reduced_stiffness(in_plane_block(affine_stiffness(cell, families)), lattice_angle);
    cal.relaxed =
        rotate_reduced_stiffness(in_plane_block(relaxed_stiffness(cell, families)), lattice_angle);
    cal.relaxed_error = relative_difference(cal.relaxed, cal.target);
    break;
  }
  return cal;
}

void register_hex2d(Registry& registry) {
  registry.add("hex2d", Hex2dStrategy().description(),
               [] { return std::make_unique<Hex2dStrategy>(); });
  registry.add("hex2d-paper", Hex2dPaperStrategy().description(),
               [] { return std::make_unique<Hex2dPaperStrategy>(); });
}

}  // namespace plydem
