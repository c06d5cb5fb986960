#include "strategies/hcp.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/elasticity.hpp"
#include "core/error.hpp"
#include "core/units.hpp"
#include "packings/hcp_lamina.hpp"
#include "strategies/calibration.hpp"
#include "strategies/registry.hpp"
#include "strategies/specimen.hpp"

namespace plydem {
namespace {

// Bending and twisting of a circular parallel bond of radius R carrying contact stiffnesses k_n,
// k_s (eqs. 1-2): k_b = k_n R^2/4, k_t = k_s R^2/2, as for hex2d. In the three-particle cell the
// particles of different layers turn differently under a uniform strain, so these enter the
// relaxed stiffness and the calibration.
// Eq. (24): the in-plane bonds along the fibre (family 0) form group 0, every other bond group 1.
constexpr int kGroupCount = 2;
int group_of(int family) {
  return family == 0 ? 0 : 1;
}
const char* const kGroupNames[kGroupCount] = {"fibre (in-plane along the fibre)",
                                              "matrix (in-plane at +-60 deg and inclined)"};

// Inclined families are named by the angle of their in-plane projection.
const char* const kFamilyLabels[HcpLamina::kFamilyCount] = {
    "1 (fibre)",         "2 (+60 deg)",       "3 (+120 deg)",
    "4 (inclined, +30)", "5 (inclined, +90)", "6 (inclined, +150)"};

// The lamina cell with its six families merged into the two groups of eq. (24).
UnitCell grouped_cell(UnitCell cell) {
  for (UnitCell::Bond& bond : cell.bonds) bond.family = group_of(bond.family);
  cell.family_count = kGroupCount;
  return cell;
}

std::vector<FamilyStiffness> expand_groups(const std::vector<FamilyStiffness>& groups) {
  std::vector<FamilyStiffness> families;
  for (int f = 0; f < HcpLamina::kFamilyCount; ++f) families.push_back(groups[group_of(f)]);
  return families;
}

// The six independent entries of a symmetric 3x3 in-plane stiffness.
Eigen::Matrix<double, 6, 1> independent_entries(const Eigen::Matrix3d& c) {
  Eigen::Matrix<double, 6, 1> v;
  v << c(0, 0), c(1, 1), c(0, 1), c(0, 2), c(1, 2), c(2, 2);
  return v;
}

// Springs from a parameter vector (k_n, k_s per group).
std::vector<FamilyStiffness> groups_of(const Eigen::VectorXd& p, const FamilyStiffnessRule& rule) {
  std::vector<FamilyStiffness> groups;
  for (int g = 0; 2 * g < p.size(); ++g) groups.push_back(rule(p(2 * g), p(2 * g + 1)));
  return groups;
}

// Least-squares fit of the affine lattice sum (linear in the springs) to the target: the start of
// the relaxed calibration. Exact for an orthotropic target in the lattice frame.
Eigen::VectorXd affine_fit(const UnitCell& cell, const Eigen::Matrix3d& target,
                           const FamilyStiffnessRule& rule) {
  const int unknowns = 2 * cell.family_count;
  Eigen::MatrixXd columns(6, unknowns);
  for (int k = 0; k < unknowns; ++k) {
    Eigen::VectorXd unit = Eigen::VectorXd::Zero(unknowns);
    unit(k) = 1.0;
    columns.col(k) =
        independent_entries(in_plane_block(affine_stiffness(cell, groups_of(unit, rule))));
  }
  return columns.completeOrthogonalDecomposition().solve(independent_entries(target));
}

std::string gpa(double pascal) {
  return fmt::format("{:.4g}", pascal * kGPaPerPa);
}

void validate_ply(double ply_angle, double thickness) {
  require(std::isfinite(ply_angle), "ply angle is not finite");
  require(std::isfinite(thickness) && thickness > 0,
          fmt::format("ply thickness must be positive, got {} m", thickness));
}

// Families, affine and relaxed stiffness in the specimen frame, from the six-family cell of the
// lamina turned with the ply (not the grouped cell the springs were solved on).
void finish_calibration(Calibration& cal, const HcpLamina& lamina, double thickness,
                        const std::vector<FamilyStiffness>& groups) {
  const std::vector<FamilyStiffness> families = expand_groups(groups);
  for (int f = 0; f < HcpLamina::kFamilyCount; ++f) {
    cal.families.push_back({kFamilyLabels[f], lamina.family_angle(f), families[f]});
  }
  const UnitCell cell = lamina.unit_cell(thickness);
  cal.affine = in_plane_block(affine_stiffness(cell, families));
  cal.relaxed = in_plane_block(relaxed_stiffness(cell, families));
  cal.relaxed_error = relative_difference(cal.relaxed, cal.target);
}

}  // namespace

Eigen::Matrix<double, 5, 4> hcp_eq26_matrix(double radius, double layer_spacing,
                                            double volume_per_particle) {
  require(radius > 0 && layer_spacing > 0 && volume_per_particle > 0,
          "eq. (26): radius, layer spacing and volume must be positive");
  const double R = radius, c = layer_spacing;
  const double inclined_length2 = 4 * R * R / 3 + c * c;
  const double s2 = (4 * R * R / 3) / inclined_length2;  // sin^2(theta), eq. (25)
  const double s4 = s2 * s2, c2 = 1 - s2;
  // Eq. (22) sums over the 12 neighbours of one particle: each bond counted once is 1/(2V) of
  // that sum (ERRATA §2), weighted by its own squared length.
  const double wp = 4 * R * R / (2 * volume_per_particle);
  const double wi = inclined_length2 / (2 * volume_per_particle);
  Eigen::Matrix<double, 5, 4> m;
  // Rows C1111, C1122, C2222, C2233, C1212; columns k_N1, k_T1, k_N2, k_T2.
  // clang-format off
  m << 2 * wp, 0,      wp / 4 + wi * 9 * s4 / 4,     wp * 3 / 4 + wi * (3 * s2 - 9 * s4 / 4),
       0,      0,      wp * 3 / 4 + wi * 3 * s4 / 4, -(wp * 3 / 4 + wi * 3 * s4 / 4),
       0,      0,      wp * 9 / 4 + wi * 9 * s4 / 4, wp * 3 / 4 + wi * (3 * s2 - 9 * s4 / 4),
       0,      0,      wi * 3 * s2 * c2,             -wi * 3 * s2 * c2,
       0,      wp / 2, wp * 3 / 4 + wi * 3 * s4 / 4, wp / 4 + wi * (3 * s2 / 2 - 3 * s4 / 4);
  // clang-format on
  // With wp = wi (every bond equally long) C1212's k_T2 coefficient is the corrected
  // (1/4 + 3/2 sin^2 - 3/4 sin^4) of ERRATA §2.
  return m;
}

double hcp_eq26_ratio(double layer_spacing_radii) {
  const Eigen::Matrix<double, 5, 4> m = hcp_eq26_matrix(1.0, layer_spacing_radii, 1.0);
  return m(3, 2) / m(1, 2);
}

double hcp_eq26_printed_ratio_bound() {
  // As printed, C2233/C1122 = 3 x (1 - x) / (3/4 (1 + x^2)) with x = sin^2(theta); its derivative
  // vanishes where x^2 + 2x - 1 = 0.
  const double x = std::sqrt(2.0) - 1.0;
  return 4 * x * (1 - x) / (1 + x * x);
}

int complete_boundary_cells_by_class(const Particles& particles, Bonds& bonds,
                                     const std::vector<int>& bond_class,
                                     const std::vector<int>& bulk_count) {
  const int classes = static_cast<int>(bulk_count.size());
  require(classes > 0 && static_cast<int>(bond_class.size()) == bonds.size(),
          "boundary-cell completion needs one class per bond");
  const int n = particles.size();
  std::vector<int> count(static_cast<size_t>(n) * classes, 0);
  for (int b = 0; b < bonds.size(); ++b) {
    const int k = bond_class[b];
    if (!(k >= 0 && k < classes && bulk_count[k] > 0))
      throw Error(fmt::format("bond {} has class {} without a bulk count", b, k));
    ++count[static_cast<size_t>(bonds.first(b)) * classes + k];
    ++count[static_cast<size_t>(bonds.second(b)) * classes + k];
  }
  int changed = 0;
  for (int b = 0; b < bonds.size(); ++b) {
    const int k = bond_class[b];
    const double share_i = static_cast<double>(bulk_count[k]) /
                           count[static_cast<size_t>(bonds.first(b)) * classes + k];
    const double share_j = static_cast<double>(bulk_count[k]) /
                           count[static_cast<size_t>(bonds.second(b)) * classes + k];
    const double factor = 0.5 * (share_i + share_j);
    if (factor == 1.0) continue;
    bonds.normal_stiffness(b) *= factor;
    bonds.shear_stiffness(b) *= factor;
    bonds.bending_stiffness(b) *= factor;
    bonds.twisting_stiffness(b) *= factor;
    ++changed;
  }
  return changed;
}

// --- the shared part: option c, the lamina, the coupon ---------------------------------------

HcpStrategyBase::HcpStrategyBase()
    : layer_spacing_radii_(HcpLamina::close_packed_layer_spacing(2.0)) {}

std::vector<StrategyOption> HcpStrategyBase::options() const {
  const auto [lower, upper] = HcpLamina::layer_spacing_limits();
  return {{"c", layer_spacing_radii_,
           fmt::format("spacing of the three layers along z, in particle radii (default {:.6g}, "
                       "close packed; between {:.4g} and {:.4g})",
                       HcpLamina::close_packed_layer_spacing(2.0), 2 * lower, 2 * upper)}};
}

void HcpStrategyBase::set_option(const std::string& name, double value) {
  if (name != "c") {
    Strategy::set_option(name, value);  // throws, listing the known options
    return;
  }
  // The lamina checks the spacing against the neighbour shells (in units of the diameter).
  HcpLamina(2.0, value, 0.0);
  layer_spacing_radii_ = value;
}

Model HcpStrategyBase::assemble(const CouponSpec& coupon, const Calibration& cal) const {
  const double radius = 0.5 * coupon.particle_diameter;
  const HcpLamina lamina(coupon.particle_diameter, layer_spacing_radii_ * radius,
                         cal.lattice_angle);
  const HcpLamina::Sites sites = lamina.fill_rectangle(coupon.length, coupon.width);
  const HcpLamina::Graph graph = lamina.bond_graph(sites);
  SpecimenLayout layout;
  layout.position = sites.position;
  layout.pairs = graph.pairs;
  layout.family = graph.family;
  layout.radius = radius;
  // The three layers stand for the ply thickness: each particle for a third of its cell's column.
  layout.particle_volume = lamina.cell_area() * coupon.thickness / HcpLamina::kLayerCount;
  layout.density = coupon.material.density;
  layout.thickness = coupon.thickness;
  layout.description = fmt::format(
      "three-layer HCP lamina (c = {:.4g} radii), ply angle {:.4g} deg, "
      "{} particles",
      layer_spacing_radii_, coupon.ply_angle / kDegree, sites.position.rows());
  Model model = assemble_specimen(layout, &cal.families);
  if (coupon.complete_boundary_cells) {
    // Completion classes: each in-plane family (2 bonds per particle in the bulk) and the inclined
    // bonds between each pair of adjacent layers (3 per particle in the bulk of the lamina).
    std::vector<int> bond_class(graph.pairs.size());
    for (std::size_t b = 0; b < graph.pairs.size(); ++b) {
      const auto [i, j] = graph.pairs[b];
      const int f = graph.family[b];
      bond_class[b] = HcpLamina::is_inclined(f) ? HcpLamina::kInPlaneFamilyCount +
                                                      std::min(sites.layer(i), sites.layer(j))
                                                : f;
    }
    complete_boundary_cells_by_class(model.particles, model.bonds, bond_class, {2, 2, 2, 3, 3});
  }
  model.check_consistency();
  return model;
}

std::optional<UnitCell> HcpStrategyBase::unit_cell(const Calibration& calibration,
                                                   double thickness) const {
  // finish_calibration() computes the calibration's relaxed stiffness on this cell.
  return HcpLamina(1.0, 0.5 * layer_spacing_radii_, calibration.lattice_angle).unit_cell(thickness);
}

// --- hcp: exact on the relaxed lamina -------------------------------------------------------

std::string HcpStrategy::description() const {
  return "three-layer HCP lamina (paper Sec. 3.2): 12 neighbours, eq. (24) bond groups, fibre "
         "along a bond family, springs solved on the relaxed lamina (plane stress)";
}

Calibration HcpStrategy::calibrate(const Material& material, double ply_angle,
                                   double thickness) const {
  validate(material);
  validate_ply(ply_angle, thickness);
  Calibration cal;
  cal.method = "hcp: eq. (24) groups, affine least squares then relaxed Gauss-Newton on the lamina";
  cal.lattice_angle = ply_angle;  // family 1 along the fibre
  cal.target = rotate_reduced_stiffness(reduced_stiffness(material), ply_angle);
  // In the lattice frame the target is the ply's own Q whatever the ply angle. The lamina's
  // stiffness does not depend on the particle size: a cell of unit spacing.
  const Eigen::Matrix3d target_lattice = rotate_reduced_stiffness(cal.target, -cal.lattice_angle);
  const HcpLamina lattice_frame(1.0, 0.5 * layer_spacing_radii_, 0.0);
  const UnitCell cell = grouped_cell(lattice_frame.unit_cell(thickness));
  const FamilyStiffnessRule rule = parallel_bond_rule(0.5);
  const Eigen::VectorXd start = affine_fit(cell, target_lattice, rule);
  // Unreachable targets (negative springs, an unstable cell) are refused with the nearest
  // stiffness non-negative springs can give.
  auto refuse = [&](const std::string& why) {
    const RelaxedCalibration nearest =
        nearest_non_negative_layer(cell, target_lattice, groups_of(start, rule), rule);
    Unreachable refusal;
    refusal.strategy = "hcp";
    refusal.material = material.name;
    refusal.ply_angle = ply_angle;
    refusal.reason = fmt::format("non-negative springs cannot give it: {}", why);
    refusal.frame = "fibre frame";
    refusal.target = target_lattice;
    refusal.nearest = nearest.relaxed;
    refuse_unreachable(std::move(refusal), material, thickness);
  };
  RelaxedCalibration relaxed;
  try {
    relaxed = calibrate_relaxed_layer(cell, target_lattice, groups_of(start, rule), rule);
  } catch (const Error& e) {
    std::string why = e.what();
    for (int g = 0; g < kGroupCount; ++g) {
      if (start(2 * g) < 0 || start(2 * g + 1) < 0) {
        why = fmt::format(
            "the affine lattice sum alone needs k_n = {:.4g} N/m, k_s = {:.4g} N/m "
            "for the {} bonds",
            start(2 * g), start(2 * g + 1), kGroupNames[g]);
      }
    }
    refuse(why);
  }
  for (int g = 0; g < kGroupCount; ++g) {
    const FamilyStiffness& k = relaxed.families[g];
    if (!(k.normal > 0 && k.shear >= 0)) {
      refuse(fmt::format("the {} bonds would need k_n = {:.4g} N/m, k_s = {:.4g} N/m",
                         kGroupNames[g], k.normal, k.shear));
    }
  }
  if (!(relaxed.relative_error < 1e-9)) {
    // Gauss-Newton stopped short with non-negative springs: the least-squares minimum of the
    // relaxed stiffness is not the target (a reachable target converges: tests/test_calibration).
    refuse(
        fmt::format("the relaxed lamina's least squares stops at relative error {:.3g} with "
                    "non-negative springs",
                    relaxed.relative_error));
  }
  finish_calibration(cal, HcpLamina(1.0, 0.5 * layer_spacing_radii_, cal.lattice_angle), thickness,
                     relaxed.families);
  return cal;
}

// --- hcp-eq26: the corrected closed form, reported as it is ---------------------------------

std::string HcpEq26Strategy::description() const {
  return "three-layer HCP lamina with the springs of the corrected eq. (26) in least squares "
         "(3D constants; does not reach Q-bar, reports the relaxed stiffness it has)";
}

Calibration HcpEq26Strategy::calibrate(const Material& material, double ply_angle,
                                       double thickness) const {
  validate(material);
  validate_ply(ply_angle, thickness);
  const Matrix6d c3 = stiffness_3d(material);  // fibre along axis 1
  Eigen::Matrix<double, 5, 1> goal;
  goal << c3(0, 0), c3(0, 1), c3(1, 1), c3(1, 2), c3(5, 5);
  // A cell of unit spacing (R = 1/2). The crystal of eq. (26) has a volume 2 sqrt(3) R^2 c per
  // particle; in the lamina the three layers stand for the ply thickness, so each particle stands
  // for 2 sqrt(3) R^2 delta/3 = cell area x delta/3 (the springs scale with this volume).
  const double radius = 0.5, c = 0.5 * layer_spacing_radii_;
  const HcpLamina lattice_frame(1.0, c, 0.0);
  const double volume = lattice_frame.cell_area() * thickness / HcpLamina::kLayerCount;
  const Eigen::Matrix<double, 5, 4> m = hcp_eq26_matrix(radius, c, volume);
  const Eigen::Vector4d k = m.colPivHouseholderQr().solve(goal);
  const double residual = (m * k - goal).norm() / goal.norm();

  const std::string ply =
      fmt::format("material '{}' at {:.4g} deg", material.name, ply_angle / kDegree);
  if (!(k.minCoeff() >= 0 && k(0) > 0 && k(2) > 0)) {
    // Why: C2233 and C1122 are both proportional to k_N2 - k_T2, so their ratio is geometry alone;
    // and C1212 - C1122 is a positive combination of the shear springs.
    const Eigen::Matrix<double, 1, 4> shear_row = m.row(4) - m.row(1);
    const bool shear_positive =
        shear_row(0) == 0 && shear_row(2) == 0 && shear_row(1) > 0 && shear_row(3) > 0;
    std::string shear_reason;
    if (shear_positive && goal(4) < goal(1)) {
      shear_reason = fmt::format(
          "; and in eq. (26) C1212 - C1122 is a positive combination of k_T1 and k_T2 alone, so "
          "non-negative shear springs need C1212 >= C1122 at any c, but here C1212 = {} < "
          "C1122 = {} GPa",
          gpa(goal(4)), gpa(goal(1)));
    }
    throw Error(fmt::format(
        "hcp-eq26: the corrected eq. (26) has no solution with non-negative springs for {}: its "
        "least-squares solution at c = {:.4g} radii is k_N1 = {:.4g}, k_T1 = {:.4g}, k_N2 = "
        "{:.4g}, "
        "k_T2 = {:.4g} N/m with a residual of {:.3g} of the target. Eq. (26) fixes C2233/C1122 by "
        "the geometry: {:.3f} at this c (eq. 26 as printed, every bond 2R long, allows at most "
        "{:.3f} at any c), against {:.3f} for this material{}. Use hcp, which solves the lamina's "
        "plane-stress stiffness.",
        ply, layer_spacing_radii_, k(0), k(1), k(2), k(3), residual,
        hcp_eq26_ratio(layer_spacing_radii_), hcp_eq26_printed_ratio_bound(), goal(3) / goal(1),
        shear_reason));
  }
  Calibration cal;
  cal.lattice_angle = ply_angle;
  cal.target = rotate_reduced_stiffness(reduced_stiffness(material), ply_angle);
  const FamilyStiffnessRule rule = parallel_bond_rule(radius);
  finish_calibration(cal, HcpLamina(1.0, c, cal.lattice_angle), thickness,
                     {rule(k(0), k(1)), rule(k(2), k(3))});
  cal.method = fmt::format(
      "hcp-eq26: corrected eq. (26) in least squares on the 3D stiffness (residual {:.3g}); the "
      "relaxed lamina misses the plane-stress target by {:.3g}",
      residual, cal.relaxed_error);
  return cal;
}

void register_hcp(Registry& registry) {
  registry.add("hcp", HcpStrategy().description(), [] { return std::make_unique<HcpStrategy>(); });
  registry.add("hcp-eq26", HcpEq26Strategy().description(),
               [] { return std::make_unique<HcpEq26Strategy>(); });
}

}  // namespace plydem
