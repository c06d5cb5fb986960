#include "strategies/square.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>

#include "core/elasticity.hpp"
#include "core/error.hpp"
#include "core/units.hpp"
#include "packings/square_layer.hpp"
#include "strategies/boundary_cells.hpp"
#include "strategies/calibration.hpp"
#include "strategies/registry.hpp"
#include "strategies/specimen.hpp"

namespace plydem {
namespace {

// Bending and twisting of a circular parallel bond of radius R (the particle radius, as for
// hex2d, also on the diagonals) carrying contact stiffnesses k_n = A kbar_n, k_s = A kbar_s
// (eqs. 1-2): k_b = k_n R^2/4, k_t = k_s R^2/2. A uniform strain of a one-particle lattice never
// loads them, so they do not enter the calibration.
const char* family_name(int family) {
  static const char* names[SquareLayer::kFamilyCount] = {"axial x", "axial y", "diagonal +45",
                                                         "diagonal 135"};
  return names[family];
}

bool all_non_negative(const std::array<FamilyStiffness, 4>& k) {
  for (const FamilyStiffness& f : k)
    if (!(f.normal >= 0 && f.shear >= 0)) return false;
  return true;
}

std::vector<FamilyStiffness> with_rule(const std::array<FamilyStiffness, 4>& springs,
                                       const FamilyStiffnessRule& rule) {
  std::vector<FamilyStiffness> families;
  for (const FamilyStiffness& k : springs) families.push_back(rule(k.normal, k.shear));
  return families;
}

// The springs of the printed eq. (33) that are negative, for square-paper's refusal.
std::string negative_springs(const std::array<FamilyStiffness, 4>& k) {
  std::string out;
  for (int f = 0; f < SquareLayer::kFamilyCount; ++f) {
    if (k[f].normal < 0) {
      out += fmt::format("{}k_n {} = {:.4g} N/m", out.empty() ? "" : ", ", family_name(f),
                         k[f].normal);
    }
  }
  if (k[0].shear < 0) {
    out += fmt::format("{}k_s = {:.4g} N/m (C66 < C12)", out.empty() ? "" : ", ", k[0].shear);
  }
  return out;
}

// The conditions of square_springs_non_negative that `c` (lattice frame) violates, in words.
std::string violated_conditions(const Eigen::Matrix3d& c) {
  const double gpa = kGPaPerPa;
  const double c11 = c(0, 0), c22 = c(1, 1), c12 = c(0, 1), c66 = c(2, 2);
  const double c16 = std::abs(0.5 * (c(0, 2) + c(1, 2)));
  struct Condition {
    const char* text;
    double margin;
  };
  const Condition conditions[] = {{"C66 >= C12", c66 - c12},
                                  {"C11 >= C12", c11 - c12},
                                  {"C22 >= C12", c22 - c12},
                                  {"C66 >= |C16|", c66 - c16},
                                  {"C11 + C12 >= 2 |C16|", c11 + c12 - 2 * c16},
                                  {"C22 + C12 >= 2 |C16|", c22 + c12 - 2 * c16}};
  std::string out;
  for (const Condition& condition : conditions) {
    if (condition.margin < 0) {
      out += fmt::format("{}{}", out.empty() ? "" : ", ", condition.text);
    }
  }
  return fmt::format(
      "it needs {} (here C11 = {:.4g}, C22 = {:.4g}, C12 = {:.4g}, C16 = {:.4g}, "
      "C66 = {:.4g} GPa)",
      out, c11 * gpa, c22 * gpa, c12 * gpa, c16 * gpa, c66 * gpa);
}

// The stiffness (in the frame of `target`) nearest to `target` in the Frobenius norm that a
// square layer with non-negative springs reaches when its x axis lies at `lattice_angle` in that
// frame. Non-negative least squares over the springs of square_springs_non_negative's family
// (k_nx, k_ny, k_n+, k_n-, axial k_s, diagonal k_s), which relaxes nothing: the optimum is the
// unconstrained least-squares solution on its own support, so trying every support (64) finds it.
Eigen::Matrix3d nearest_achievable(const Eigen::Matrix3d& target, double lattice_angle,
                                   double thickness) {
  const UnitCell cell = SquareLayer(1.0, lattice_angle).unit_cell(thickness);
  constexpr int kParameters = 6;
  Eigen::Matrix<double, 9, kParameters> columns;
  for (int p = 0; p < kParameters; ++p) {
    std::vector<FamilyStiffness> k(SquareLayer::kFamilyCount);
    if (p < 4) {
      k[p].normal = 1.0;
    } else {
      k[2 * (p - 4)].shear = k[2 * (p - 4) + 1].shear = 1.0;  // axial, then diagonal pair
    }
    const Eigen::Matrix3d c = in_plane_block(affine_stiffness(cell, k));
    columns.col(p) = Eigen::Map<const Eigen::Matrix<double, 9, 1>>(c.data());
  }
  const Eigen::Matrix<double, 9, 1> goal =
      Eigen::Map<const Eigen::Matrix<double, 9, 1>>(target.data());
  double best = std::numeric_limits<double>::infinity();
  Eigen::Matrix<double, 9, 1> best_fit = Eigen::Matrix<double, 9, 1>::Zero();
  for (int support = 0; support < (1 << kParameters); ++support) {
    Eigen::MatrixXd a(9, std::popcount(static_cast<unsigned>(support)));
    for (int p = 0, col = 0; p < kParameters; ++p)
      if (support & (1 << p)) a.col(col++) = columns.col(p);
    Eigen::Matrix<double, 9, 1> fit = Eigen::Matrix<double, 9, 1>::Zero();
    if (a.cols() > 0) {
      const Eigen::VectorXd x = a.completeOrthogonalDecomposition().solve(goal);
      if ((x.array() < 0).any()) continue;
      fit = a * x;
    }
    const double distance = (fit - goal).norm();
    if (distance < best) {
      best = distance;
      best_fit = fit;
    }
  }
  return Eigen::Map<const Eigen::Matrix3d>(best_fit.data());
}

void check_ply(const Material& material, double ply_angle, double thickness) {
  validate(material);
  require(std::isfinite(ply_angle), "ply angle is not finite");
  require(std::isfinite(thickness) && thickness > 0,
          fmt::format("ply thickness must be positive, got {} m", thickness));
}

// Affine and relaxed stiffness of the calibrated layer, on a cell turned as the coupon's lattice.
void fill_stiffness(Calibration& cal, double thickness) {
  const UnitCell cell = SquareLayer(1.0, cal.lattice_angle).unit_cell(thickness);
  std::vector<FamilyStiffness> k;
  for (const FamilyCalibration& f : cal.families) k.push_back(f.stiffness);
  cal.affine = in_plane_block(affine_stiffness(cell, k));
  cal.relaxed = in_plane_block(relaxed_stiffness(cell, k));
  cal.relaxed_error = relative_difference(cal.relaxed, cal.target);
}

// The cell the calibration's relaxed stiffness is computed on, turned as the coupon's lattice.
UnitCell layer_cell(const Calibration& cal, double thickness) {
  return SquareLayer(1.0, cal.lattice_angle).unit_cell(thickness);
}

// Particles on the lattice sites of the rectangle, masses from the cell area l^2, bonds to the
// eight neighbours with the calibrated stiffness of their family.
Model build_square_coupon(const CouponSpec& coupon, const Calibration& cal, const std::string& name,
                          EdgeTreatment edges) {
  const SquareLayer layer(coupon.particle_diameter, cal.lattice_angle);
  SpecimenLayout layout;
  layout.position = layer.fill_rectangle(coupon.length, coupon.width);
  const SquareLayer::Graph graph = layer.bond_graph(layout.position);
  layout.pairs = graph.pairs;
  layout.family = graph.family;
  layout.radius = 0.5 * coupon.particle_diameter;
  layout.particle_volume = layer.cell_area() * coupon.thickness;
  layout.density = coupon.material.density;
  layout.thickness = coupon.thickness;
  layout.description =
      fmt::format("{} layer, ply angle {:.4g} deg, lattice at {:.4g} deg, {} particles", name,
                  coupon.ply_angle / kDegree, cal.lattice_angle / kDegree, layout.position.rows());
  Model model = assemble_specimen(layout, &cal.families);
  treat_free_edges(model, coupon, cal, layer_cell(cal, coupon.thickness), SquareLayer::kFamilyCount,
                   edges);
  model.check_consistency();
  return model;
}

}  // namespace

std::array<FamilyStiffness, 4> square_springs_eq33(const Eigen::Matrix3d& c, double thickness) {
  const double c16 = c(0, 2), c26 = c(1, 2);
  if (std::abs(c16 - c26) > 1e-9 * c.norm()) {
    throw Error(fmt::format(
        "a square lattice has C16 = C26 in its own frame, but the stiffness has C16 = {:.6g} and "
        "C26 = {:.6g} GPa there",
        c16 * kGPaPerPa, c26 * kGPaPerPa));
  }
  std::array<FamilyStiffness, 4> k = square_springs_eq33_as_printed(c, thickness);
  // ERRATA §2: the diagonals carry C16 = C26 = (k_n+ - k_n-) / (2 delta).
  const double split = 0.5 * (c16 + c26) * thickness;
  k[2].normal += split;
  k[3].normal -= split;
  return k;
}

std::array<FamilyStiffness, 4> square_springs_eq33_as_printed(const Eigen::Matrix3d& c,
                                                              double thickness) {
  const double c11 = c(0, 0), c22 = c(1, 1), c12 = c(0, 1), c66 = c(2, 2);
  const double d = thickness;
  const double diagonal = (c12 + 2 * c66) * d / 3.0;  // k_n2
  const double shear = 2.0 * (c66 - c12) * d / 3.0;   // k_s, shared by all bonds
  std::array<FamilyStiffness, 4> k{};
  k[0].normal = (3 * c11 + c12 - 4 * c66) * d / 3.0;  // k_n1 ("k_n11" as printed)
  k[1].normal = (c12 + 3 * c22 - 4 * c66) * d / 3.0;  // k_n3
  k[2].normal = diagonal;
  k[3].normal = diagonal;
  for (FamilyStiffness& f : k) f.shear = shear;
  return k;
}

std::optional<std::array<FamilyStiffness, 4>> square_springs_non_negative(const Eigen::Matrix3d& c,
                                                                          double thickness) {
  const std::array<FamilyStiffness, 4> eq33 = square_springs_eq33(c, thickness);
  if (all_non_negative(eq33)) return eq33;
  // The exact, non-relaxing family: k_sd = diagonal shear, k_sa = axial shear (each pair equal).
  const double d = thickness;
  const double c11 = c(0, 0) * d, c22 = c(1, 1) * d, c12 = c(0, 1) * d, c66 = c(2, 2) * d;
  const double c16 = 0.5 * (c(0, 2) + c(1, 2)) * d;
  const double lowest = std::max(0.0, std::abs(c16) - c12);
  const double highest = std::min({c66 - c12, 0.5 * (c11 - c12), 0.5 * (c22 - c12)});
  if (!(lowest <= highest)) return std::nullopt;
  const double diagonal_shear = std::clamp(eq33[2].shear, lowest, highest);
  const double diagonal_normal = c12 + diagonal_shear;  // (k_n+ + k_n-) / 2
  std::array<FamilyStiffness, 4> k{};
  k[0] = {c11 - c12 - 2 * diagonal_shear, 2 * (c66 - diagonal_normal), 0, 0};
  k[1] = {c22 - c12 - 2 * diagonal_shear, k[0].shear, 0, 0};
  k[2] = {diagonal_normal + c16, diagonal_shear, 0, 0};
  k[3] = {diagonal_normal - c16, diagonal_shear, 0, 0};
  // The bounds hold up to rounding; a spring that should be zero may come out at -1e-20.
  for (FamilyStiffness& f : k) {
    f.normal = std::max(f.normal, 0.0);
    f.shear = std::max(f.shear, 0.0);
  }
  return k;
}

std::vector<StrategyOption> SquareStrategy::options() const {
  return {
      {"fibre_offset", fibre_offset_deg_,
       "angle of the fibre from the lattice x axis [deg]: 0 (lattice along the fibre), 45 "
       "(fibre along a diagonal), or -1 to choose: 45 where that puts the lattice along x, else 0; "
       "the other where the first cannot represent the ply"},
      edge_treatment_option(edge_treatment_)};
}

void SquareStrategy::set_option(const std::string& name, double value) {
  if (name == "edge_equilibrium") {
    edge_treatment_ = parse_edge_treatment("square", value);
    return;
  }
  if (name != "fibre_offset") {
    Strategy::set_option(name, value);
    return;
  }
  require(value == 0 || value == 45 || value == -1,
          fmt::format("square: fibre_offset must be 0, 45 or -1 (automatic) deg, got {}", value));
  fibre_offset_deg_ = value;
}

std::string SquareStrategy::description() const {
  return "square layer (paper Sec. 3.4): 8 neighbours, lattice turned to 0 or 45 deg from the "
         "fibre, corrected eq. (33) then relaxed calibration";
}

Calibration SquareStrategy::calibrate(const Material& material, double ply_angle,
                                      double thickness) const {
  check_ply(material, ply_angle, thickness);
  const Eigen::Matrix3d target = rotate_reduced_stiffness(reduced_stiffness(material), ply_angle);
  const std::string ply =
      fmt::format("material '{}' at {:.4g} deg", material.name, ply_angle / kDegree);
  std::vector<double> offsets = {fibre_offset_deg_};
  if (fibre_offset_deg_ < 0) {
    // A lattice along the specimen axes meets a rectangular coupon's edges along lattice lines
    // (the boundary completion is then exact): prefer it when the ply angle allows, as the paper
    // did for its 45 deg ply; otherwise the lattice follows the fibre.
    const double quarter = std::numbers::pi / 2;
    const double residue = std::remainder(ply_angle - 45 * kDegree, quarter);
    const bool diagonal_aligned = std::abs(residue) < 1e-9;
    offsets = diagonal_aligned ? std::vector<double>{45.0, 0.0} : std::vector<double>{0.0, 45.0};
  }
  const FamilyStiffnessRule rule = parallel_bond_rule(0.5);  // stiffness is independent of l
  std::string reasons;
  for (double offset : offsets) {
    const double lattice_angle = ply_angle - offset * kDegree;
    const Eigen::Matrix3d target_lattice = rotate_reduced_stiffness(target, -lattice_angle);
    const std::optional<std::array<FamilyStiffness, 4>> start =
        square_springs_non_negative(target_lattice, thickness);
    if (!start) {
      reasons +=
          fmt::format("{}with the fibre at {:g} deg from the lattice x axis {}",
                      reasons.empty() ? "" : "; ", offset, violated_conditions(target_lattice));
      continue;
    }
    // square_springs_non_negative returns eq. (33) itself whenever that is non-negative.
    const bool is_eq33 = all_non_negative(square_springs_eq33(target_lattice, thickness));
    const UnitCell cell = SquareLayer(1.0, 0.0).unit_cell(thickness);
    // The springs above are exact for the affine lattice sum; where unequal shear springs let
    // the spins relax, Gauss-Newton re-solves them. Should that fail, the offset is refused with
    // the rest (never "did not converge").
    RelaxedCalibration relaxed;
    std::string failed;
    try {
      relaxed = calibrate_relaxed_layer(cell, target_lattice, with_rule(*start, rule), rule);
      for (int f = 0; f < SquareLayer::kFamilyCount && failed.empty(); ++f) {
        const FamilyStiffness& k = relaxed.families[f];
        if (!(k.normal >= 0 && k.shear >= 0)) {
          failed = fmt::format("bond family {} would need k_n = {:.4g} N/m, k_s = {:.4g} N/m",
                               family_name(f), k.normal, k.shear);
        }
      }
      if (failed.empty() && !(relaxed.relative_error < 1e-9)) {
        failed = fmt::format(
            "with spinning particles the least squares stops at relative error "
            "{:.3g}",
            relaxed.relative_error);
      }
    } catch (const Error& e) {
      failed = e.what();
    }
    if (!failed.empty()) {
      reasons += fmt::format("{}with the fibre at {:g} deg from the lattice x axis {}",
                             reasons.empty() ? "" : "; ", offset, failed);
      continue;
    }
    Calibration cal;
    cal.method = fmt::format(
        "square: {}, fibre at {:g} deg from the lattice, relaxed on the unit cell",
        is_eq33 ? "corrected eq. (33)"
                : "nearest exact springs to eq. (33) (which has a negative spring here), axial and "
                  "diagonal k_s apart",
        offset);
    cal.lattice_angle = lattice_angle;
    cal.target = target;
    for (int f = 0; f < SquareLayer::kFamilyCount; ++f) {
      const bool fibre = std::abs(SquareLayer::family_offset(f) - offset * kDegree) < 1e-12;
      cal.families.push_back({fmt::format("{}{}", family_name(f), fibre ? " (fibre)" : ""),
                              lattice_angle + SquareLayer::family_offset(f), relaxed.families[f]});
    }
    fill_stiffness(cal, thickness);
    return cal;
  }

  // Nothing representable: name why, and what the lattice can reach instead (fibre frame).
  const Eigen::Matrix3d q = reduced_stiffness(material);
  Eigen::Matrix3d nearest = Eigen::Matrix3d::Zero();
  for (double offset : offsets) {
    const Eigen::Matrix3d c = nearest_achievable(q, -offset * kDegree, thickness);
    if (offset == offsets.front() || relative_difference(c, q) < relative_difference(nearest, q)) {
      nearest = c;
    }
  }
  Unreachable refusal;
  refusal.strategy = "square";
  refusal.material = material.name;
  refusal.ply_angle = ply_angle;
  refusal.reason = fmt::format("non-negative springs cannot give it: {}", reasons);
  refusal.frame = "fibre frame";
  refusal.target = q;
  refusal.nearest = nearest;
  refuse_unreachable(std::move(refusal), material, thickness);
}

Model SquareStrategy::assemble(const CouponSpec& coupon, const Calibration& calibration) const {
  return build_square_coupon(coupon, calibration, "square", edge_treatment_);
}

BoundaryCompletion SquareStrategy::boundary_completion() const {
  return {SquareLayer::kFamilyCount, 2};
}

std::optional<UnitCell> SquareStrategy::unit_cell(const Calibration& calibration,
                                                  double thickness) const {
  // The cell fill_stiffness() computes the calibration's relaxed stiffness on; assemble() numbers
  // the coupon's families as SquareLayer at the same lattice angle.
  return SquareLayer(1.0, calibration.lattice_angle).unit_cell(thickness);
}

std::string SquarePaperStrategy::description() const {
  return "square layer with eq. (33) exactly as printed (C16, C26 dropped; lattice along x, no "
         "relaxed correction): reproduces the paper's formula for comparison, not the target";
}

Calibration SquarePaperStrategy::calibrate(const Material& material, double ply_angle,
                                           double thickness) const {
  check_ply(material, ply_angle, thickness);
  Calibration cal;
  cal.method = "square-paper: eq. (33) as printed on a lattice along x (the paper's formula)";
  cal.lattice_angle = 0;  // the paper's Fig. 14b: the lattice stays, the fibre turns
  cal.target = rotate_reduced_stiffness(reduced_stiffness(material), ply_angle);
  const std::array<FamilyStiffness, 4> k = square_springs_eq33_as_printed(cal.target, thickness);
  if (!all_non_negative(k)) {
    throw Error(fmt::format(
        "square-paper cannot build material '{}' at {:.4g} deg: eq. (33) as printed gives {}",
        material.name, ply_angle / kDegree, negative_springs(k)));
  }
  const FamilyStiffnessRule rule = parallel_bond_rule(0.5);
  for (int f = 0; f < SquareLayer::kFamilyCount; ++f) {
    cal.families.push_back(
        {family_name(f), SquareLayer::family_offset(f), rule(k[f].normal, k[f].shear)});
  }
  fill_stiffness(cal, thickness);
  return cal;
}

Model SquarePaperStrategy::assemble(const CouponSpec& coupon,
                                    const Calibration& calibration) const {
  return build_square_coupon(coupon, calibration, "square-paper", EdgeTreatment::kCellCompletion);
}

BoundaryCompletion SquarePaperStrategy::boundary_completion() const {
  return {SquareLayer::kFamilyCount, 2};
}

std::optional<UnitCell> SquarePaperStrategy::unit_cell(const Calibration& calibration,
                                                       double thickness) const {
  return SquareLayer(1.0, calibration.lattice_angle).unit_cell(thickness);
}

void register_square(Registry& registry) {
  registry.add("square", SquareStrategy().description(),
               [] { return std::make_unique<SquareStrategy>(); });
  registry.add("square-paper", SquarePaperStrategy().description(),
               [] { return std::make_unique<SquarePaperStrategy>(); });
}

}  // namespace plydem
