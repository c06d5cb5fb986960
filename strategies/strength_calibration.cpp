#include "strategies/strength_calibration.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <numbers>
#include <optional>
#include <random>
#include <typeinfo>

#include "core/bond_failure.hpp"
#include "core/elasticity.hpp"
#include "core/error.hpp"
#include "core/homogenizer.hpp"
#include "core/parallel_bond.hpp"
#include "core/units.hpp"
#include "strategies/registry.hpp"

namespace plydem {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
/// A target counts as met when the model's first failure lies within this of it (relative).
constexpr double kReachedTolerance = 1e-9;
/// Families within this angle of the fibre get G_fibre, the others G_matrix.
constexpr double kFibreFamilyAngle = 15.0 * kDegree;

using Resultants = Eigen::Matrix<double, 8, 3>;

// The three calibrated targets, and the four loads that set strengths (S12 with either sign).
constexpr int kTargetCount = 3;
constexpr int kXT = 0, kYT = 1, kS12 = 2;
const char* const kTargetNames[kTargetCount] = {"XT", "YT", "S12"};
struct Load {
  int target;
  PlyStress unit;  // the ply stress per unit of the target's value
  const char* name;
};
constexpr int kLoadCount = 4;
const Load kLoads[kLoadCount] = {{kXT, {1, 0, 0}, "sigma1 = +XT"},
                                 {kYT, {0, 1, 0}, "sigma2 = +YT"},
                                 {kS12, {0, 0, 1}, "tau12 = +S12"},
                                 {kS12, {0, 0, -1}, "tau12 = -S12"}};
using Targets = std::array<double, kTargetCount>;

PlyStress scaled(const PlyStress& s, double factor) {
  return {s.sigma1 * factor, s.sigma2 * factor, s.tau12 * factor};
}

double mpa(double pascal) {
  return pascal * kMPaPerPa;
}

// The section stresses of a bond whose resultants per unit ply stress are `r`, under `stress`.
BondStresses stresses_of(const Resultants& r, double radius, const PlyStress& stress) {
  const Eigen::Matrix<double, 8, 1> v =
      r * Eigen::Vector3d(stress.sigma1, stress.sigma2, stress.tau12);
  return section_stresses(v(0), v.segment<3>(1).norm(), v.segment<3>(4).norm(), std::abs(v(7)),
                          radius);
}

// The bond's elastic energy under `stress`: 1/2 F.F/k summed over the four springs.
double energy_of(const Resultants& r, const FamilyStiffness& k, const PlyStress& stress) {
  const Eigen::Matrix<double, 8, 1> v =
      r * Eigen::Vector3d(stress.sigma1, stress.sigma2, stress.tau12);
  auto part = [](double squared, double stiffness) {
    return stiffness > 0 ? 0.5 * squared / stiffness : 0.0;
  };
  return part(v(0) * v(0), k.normal) + part(v.segment<3>(1).squaredNorm(), k.shear) +
         part(v.segment<3>(4).squaredNorm(), k.bending) + part(v(7) * v(7), k.twisting);
}

// The relaxed bulk of a ply, read from the unit cell its strategy calibrated on: per cell bond,
// its resultants per unit ply stress at the report's particle size.
struct RelaxedBulk {
  std::vector<int> family;
  std::vector<double> radius;  // section radius R: the smaller particle radius
  std::vector<Resultants> unit;
  std::vector<FamilyStiffness> stiffness;
  std::vector<Eigen::Vector3d> normal;
  std::vector<double> length;
  double volume = 0;
  int family_count = 0;
};

RelaxedBulk relaxed_bulk(const Strategy& strategy, const Calibration& calibration,
                         const Material& material, double ply_angle, double thickness,
                         double diameter, const std::string& ply) {
  const std::optional<UnitCell> found = strategy.unit_cell(calibration, thickness);
  if (!found) {
    throw Error(fmt::format(
        "the strength calibration of {} reads the bond forces of the relaxed bulk from the "
        "periodic cell the strategy calibrated on, and this strategy has none (a random packing "
        "has no uniform bond state); use a strategy with a unit cell (hex2d, square, hcp)",
        ply));
  }
  UnitCell cell = *found;
  const Eigen::Matrix3d qbar = rotate_reduced_stiffness(reduced_stiffness(material), ply_angle);
  require(relative_difference(calibration.target, qbar) < 1e-9,
          fmt::format("the strength calibration of {}: the calibration given was made for "
                      "another ply (its target stiffness is not this ply's Q-bar)",
                      ply));
  const int families = static_cast<int>(calibration.families.size());
  require(cell.family_count == families,
          fmt::format("the strength calibration of {}: the strategy's unit cell has {} bond "
                      "families, its calibration {}",
                      ply, cell.family_count, families));
  require(
      !cell.radius.empty() && cell.radius.size() == cell.basis.size() && !cell.bonds.empty(),
      fmt::format("the strength calibration of {}: the unit cell has no particles or bonds", ply));
  // To the report's size: lengths by s, and the layer's volume (area x thickness) by s^2. A
  // parallel bond's k_b = k_n R^2 / 4 and k_t = k_s R^2 / 2 belong to its radius, so they scale
  // by s^2; k_n and k_s do not depend on the size. The relaxed stiffness is unchanged.
  const double cell_diameter = 2.0 * *std::max_element(cell.radius.begin(), cell.radius.end());
  require(cell_diameter > 0, "the unit cell's particles have no radius");
  const double s = diameter / cell_diameter;
  for (Eigen::Vector3d& x : cell.basis) x *= s;
  cell.lattice_vectors.leftCols<2>() *= s;
  for (double& r : cell.radius) r *= s;
  cell.volume *= s * s;
  std::vector<FamilyStiffness> stiffness;
  for (const FamilyCalibration& f : calibration.families) {
    FamilyStiffness k = f.stiffness;
    k.bending *= s * s;
    k.twisting *= s * s;
    stiffness.push_back(k);
  }
  // The cell must be the one the calibration was solved on.
  const Eigen::Matrix3d relaxed = in_plane_block(relaxed_stiffness(cell, stiffness));
  const double mismatch = relative_difference(relaxed, calibration.relaxed);
  require(mismatch < 1e-8,
          fmt::format("the strength calibration of {}: the strategy's unit cell has a relaxed "
                      "stiffness {:.3g} (relative) away from its calibration's: the calibration "
                      "was not made by this strategy (or with other options)",
                      ply, mismatch));
  require(is_positive_definite(calibration.relaxed),
          fmt::format("the strength calibration of {}: the relaxed stiffness is not positive "
                      "definite",
                      ply));
  const Eigen::Matrix3d compliance = calibration.relaxed.inverse();

  RelaxedBulk bulk;
  bulk.volume = cell.volume;
  bulk.family_count = families;
  const int bonds = static_cast<int>(cell.bonds.size());
  std::vector<BondParameters> parameters;
  for (int b = 0; b < bonds; ++b) {
    const UnitCell::Bond& bond = cell.bonds[b];
    parameters.push_back(cell_bond(cell, b, stiffness[bond.family]));
    bulk.family.push_back(bond.family);
    bulk.radius.push_back(std::min(cell.radius[bond.first], cell.radius[bond.second]));
    bulk.stiffness.push_back(stiffness[bond.family]);
    bulk.normal.push_back(parameters.back().normal);
    bulk.length.push_back(cell.branch(b).norm());
    bulk.unit.push_back(Resultants::Zero());
  }
  for (int k = 0; k < 3; ++k) {
    // Unit ply stress k, in the specimen frame, then the strain of the relaxed model.
    const PlyStress ply_stress{k == 0 ? 1.0 : 0.0, k == 1 ? 1.0 : 0.0, k == 2 ? 1.0 : 0.0};
    const PlyStress specimen =
        to_ply_axes(ply_stress.sigma1, ply_stress.sigma2, ply_stress.tau12, -ply_angle);
    const Eigen::Vector3d strain =
        compliance * Eigen::Vector3d(specimen.sigma1, specimen.sigma2, specimen.tau12);
    Vector6d voigt = Vector6d::Zero();
    voigt(0) = strain(0);
    voigt(1) = strain(1);
    voigt(5) = strain(2);
    const CellMotion motion = relaxed_motion(cell, stiffness, voigt);
    for (int b = 0; b < bonds; ++b) {
      const UnitCell::Bond& bond = cell.bonds[b];
      const BondParameters& p = parameters[b];
      const Eigen::Vector3d& theta_i = motion.rotation[bond.first];
      const Eigen::Vector3d& theta_j = motion.rotation[bond.second];
      const Eigen::Vector3d du = contact_relative_displacement(
          p, motion.displacement(cell, bond.first, Eigen::Vector3i::Zero()), theta_i,
          motion.displacement(cell, bond.second, bond.image), theta_j);
      const Eigen::Vector3d dtheta = theta_j - theta_i;
      const Eigen::Vector3d& n = p.normal;
      const double du_n = n.dot(du), dtheta_n = n.dot(dtheta);
      Eigen::Matrix<double, 8, 1> column;
      column(0) = p.normal_stiffness * du_n;
      column.segment<3>(1) = p.shear_stiffness * (du - du_n * n);
      column.segment<3>(4) = p.bending_stiffness * (dtheta - dtheta_n * n);
      column(7) = p.twisting_stiffness * dtheta_n;
      bulk.unit[b].col(k) = column;
    }
  }
  return bulk;
}

// Strengths solved for targets T and the model's first failure under each load.
struct Evaluation {
  std::vector<FamilyStrength> families;
  // Per family: the load and cell bond that set its tensile strength and its cohesion (-1: none).
  std::vector<int> tensile_load, tensile_bond, cohesion_load, cohesion_bond;
  std::array<double, kLoadCount> factor{};  // first failure / load (>= 1 up to rounding)
  std::array<int, kLoadCount> first_bond{};
  std::array<BondState, kLoadCount> first_mode{};

  bool load_reached(int l) const { return std::abs(factor[l] - 1.0) <= kReachedTolerance; }
  bool reached(int target) const {
    for (int l = 0; l < kLoadCount; ++l)
      if (kLoads[l].target == target && !load_reached(l)) return false;
    return true;
  }
  bool all_reached() const {
    for (int t = 0; t < kTargetCount; ++t)
      if (!reached(t)) return false;
    return true;
  }
  // The model's first-failure stress for target t [Pa]; for S12 the sign further from it.
  double model(int target, const Targets& targets) const {
    double factor_max = 0;
    for (int l = 0; l < kLoadCount; ++l)
      if (kLoads[l].target == target) factor_max = std::max(factor_max, factor[l]);
    return factor_max * targets[target];
  }
};

BondStrength strength_of(const FamilyStrength& f) {
  BondStrength s;
  s.radius = f.radius;
  s.tensile = f.tensile;
  s.cohesion = f.cohesion;
  s.friction = f.friction;
  s.ductility = f.ductility;
  return s;
}

// The shear demand c must meet: tau + (F_n / A) tan(phi).
double shear_demand(const BondStresses& s, double friction) {
  return s.shear + s.axial * friction;
}

Evaluation evaluate(const RelaxedBulk& bulk, const Targets& targets, double friction) {
  Evaluation e;
  const int families = bulk.family_count;
  e.families.resize(families);
  e.tensile_load.assign(families, -1);
  e.tensile_bond.assign(families, -1);
  e.cohesion_load.assign(families, -1);
  e.cohesion_bond.assign(families, -1);
  std::vector<double> tension(families, 0.0), shear(families, 0.0);
  const int bonds = static_cast<int>(bulk.family.size());
  for (int l = 0; l < kLoadCount; ++l) {
    const PlyStress load = scaled(kLoads[l].unit, targets[kLoads[l].target]);
    for (int b = 0; b < bonds; ++b) {
      const int f = bulk.family[b];
      const BondStresses s = stresses_of(bulk.unit[b], bulk.radius[b], load);
      if (s.normal > tension[f]) {
        tension[f] = s.normal;
        e.tensile_load[f] = l;
        e.tensile_bond[f] = b;
      }
      const double demand = shear_demand(s, friction);
      if (demand > shear[f]) {
        shear[f] = demand;
        e.cohesion_load[f] = l;
        e.cohesion_bond[f] = b;
      }
    }
  }
  for (int f = 0; f < families; ++f) {
    FamilyStrength& fs = e.families[f];
    fs.friction = friction;
    // A mode no target load reaches keeps +inf: its stress is a positively homogeneous convex
    // function of the ply stress (a linear part plus norms), <= 0 at +XT, +YT and +-S12, hence
    // <= 0 on their cone, which holds every uniform state of a ply in uniaxial tension at any
    // angle (sigma1 = cos^2, sigma2 = sin^2, tau12 = -sin cos times sigma_x >= 0).
    if (e.tensile_load[f] >= 0) {
      fs.tensile = tension[f];
      fs.tensile_set_by = kTargetNames[kLoads[e.tensile_load[f]].target];
    }
    if (e.cohesion_load[f] >= 0) {
      fs.cohesion = shear[f];
      fs.cohesion_set_by = kTargetNames[kLoads[e.cohesion_load[f]].target];
    }
  }
  for (int b = 0; b < bonds; ++b) e.families[bulk.family[b]].radius = bulk.radius[b];
  for (int l = 0; l < kLoadCount; ++l) {
    const PlyStress load = scaled(kLoads[l].unit, targets[kLoads[l].target]);
    e.factor[l] = kInf;
    e.first_bond[l] = -1;
    e.first_mode[l] = BondState::kIntact;
    for (int b = 0; b < bonds; ++b) {
      const CriticalLoad c = critical_load(stresses_of(bulk.unit[b], bulk.radius[b], load),
                                           strength_of(e.families[bulk.family[b]]));
      if (c.factor < e.factor[l]) {
        e.factor[l] = c.factor;
        e.first_bond[l] = b;
        e.first_mode[l] = c.mode;
      }
    }
  }
  return e;
}

// First failure of the relaxed bulk under `stress`: the factor, the cell bond and the mode.
struct FirstFailure {
  double factor = kInf;
  int bond = -1;
  BondState mode = BondState::kIntact;
};
FirstFailure first_failure(const RelaxedBulk& bulk, const std::vector<FamilyStrength>& families,
                           const PlyStress& stress) {
  FirstFailure first;
  for (int b = 0; b < static_cast<int>(bulk.family.size()); ++b) {
    const CriticalLoad c = critical_load(stresses_of(bulk.unit[b], bulk.radius[b], stress),
                                         strength_of(families[bulk.family[b]]));
    if (c.factor < first.factor) first = {c.factor, b, c.mode};
  }
  return first;
}

// The targets that keep target `kept` and lower the others as little as needed for all three to
// be met (greedy: each round meets one missed load at the family and mode that asks the smallest
// relative reduction of the others). nullopt if none is found.
std::optional<Targets> keeping(const RelaxedBulk& bulk, Targets targets, int kept,
                               double friction) {
  for (int round = 0; round < 2 * kLoadCount; ++round) {
    const Evaluation e = evaluate(bulk, targets, friction);
    if (e.all_reached()) return targets;
    int missed = -1;
    for (int l = 0; l < kLoadCount && missed < 0; ++l)
      if (kLoads[l].target == kept && !e.load_reached(l)) missed = l;
    for (int l = 0; l < kLoadCount && missed < 0; ++l)
      if (!e.load_reached(l)) missed = l;
    // A target other than `kept` can miss once lowering the others made it: it is met the same
    // way, never raising anything and never lowering `kept`.
    const int t = kLoads[missed].target;
    double best_cost = kInf;
    Targets best = targets;
    for (int f = 0; f < bulk.family_count; ++f) {
      for (int mode = 0; mode < 2; ++mode) {
        // A family's strength in a mode is its largest demand over its cell bonds and the loads.
        auto demand = [&](int l) {
          double largest = 0;
          for (int b = 0; b < static_cast<int>(bulk.family.size()); ++b) {
            if (bulk.family[b] != f) continue;
            const BondStresses s = stresses_of(bulk.unit[b], bulk.radius[b],
                                               scaled(kLoads[l].unit, targets[kLoads[l].target]));
            largest = std::max(largest, mode == 0 ? s.normal : shear_demand(s, friction));
          }
          return largest;
        };
        const double own = demand(missed);
        if (!(own > 0)) continue;
        Targets candidate = targets;
        double cost = 0;
        for (int other = 0; other < kTargetCount; ++other) {
          if (other == t) continue;
          double largest = 0;
          for (int l = 0; l < kLoadCount; ++l)
            if (kLoads[l].target == other) largest = std::max(largest, demand(l));
          if (largest > own) {
            if (other == kept) cost = kInf;  // never lower the target being kept
            candidate[other] *= own / largest;
            cost = std::max(cost, 1.0 - own / largest);
          }
        }
        if (cost < best_cost) {
          best_cost = cost;
          best = candidate;
        }
      }
    }
    if (!(best_cost < kInf)) return std::nullopt;
    targets = best;
  }
  return std::nullopt;
}

std::string strategy_name(const Strategy& strategy) {
  const Registry& registry = default_registry();
  for (const std::string& name : registry.names()) {
    const std::unique_ptr<Strategy> candidate = registry.create(name);
    const Strategy& built = *candidate;
    if (typeid(built) == typeid(strategy)) return name;
  }
  return "this strategy";
}

StrengthCalibration calibrate(const Strategy& strategy, const Calibration& calibration,
                              const Material& material, double ply_angle, double thickness,
                              const StrengthOptions& options, bool name_alternatives);

// The registered strategies that meet XT, YT and S12 for this ply (calibrate, then calibrate the
// strengths without looking for alternatives in turn).
std::vector<std::string> strategies_reaching(const Material& material, double ply_angle,
                                             double thickness, const StrengthOptions& options) {
  std::vector<std::string> reaching;
  const Registry& registry = default_registry();
  for (const std::string& name : registry.names()) {
    try {
      const std::unique_ptr<Strategy> candidate = registry.create(name);
      if (!candidate->unit_cell(Calibration{}, thickness)) continue;  // no cell: cannot
      const Calibration c = candidate->calibrate(material, ply_angle, thickness);
      calibrate(*candidate, c, material, ply_angle, thickness, options, false);
      reaching.push_back(name);
    } catch (const Error&) {
      // This strategy cannot build the ply or cannot meet its strengths.
    }
  }
  return reaching;
}

std::string describe_targets(const Targets& t) {
  return fmt::format("XT = {:.4g}, YT = {:.4g}, S12 = {:.4g} MPa", mpa(t[kXT]), mpa(t[kYT]),
                     mpa(t[kS12]));
}

std::string unreachable_message(const std::string& name, const std::string& ply,
                                const RelaxedBulk& bulk, const Evaluation& e,
                                const Targets& targets, const Calibration& calibration,
                                const Material& material, double ply_angle, double thickness,
                                const StrengthOptions& options, bool name_alternatives) {
  std::string missed;
  for (int t = 0; t < kTargetCount; ++t) {
    if (e.reached(t)) continue;
    int l = -1;  // the load that misses most
    for (int k = 0; k < kLoadCount; ++k)
      if (kLoads[k].target == t && (l < 0 || e.factor[k] > e.factor[l])) l = k;
    const int f = e.first_bond[l] >= 0 ? bulk.family[e.first_bond[l]] : -1;
    std::string where = "no bond breaks";
    if (f >= 0) {
      const FamilyStrength& fs = e.families[f];
      const bool tension = e.first_mode[l] == BondState::kBrokenTension;
      where = fmt::format("family '{}' breaks first, in {}, whose strength {} sets",
                          calibration.families[f].label, mode_name(e.first_mode[l]),
                          tension ? fs.tensile_set_by : fs.cohesion_set_by);
    }
    missed += fmt::format(
        "{}{} = {:.4g} MPa is not met: under {} the model first breaks at {:.4g} MPa ({})",
        missed.empty() ? "" : "; ", kTargetNames[t], mpa(targets[t]), kLoads[l].name,
        mpa(e.factor[l] * targets[t]), where);
  }
  Targets own;
  for (int t = 0; t < kTargetCount; ++t) own[t] = e.model(t, targets);
  std::string alternatives = fmt::format(
      "the nearest strengths its bonds can have: {} (the model's own first failures "
      "with the least strengths above)",
      describe_targets(own));
  for (int t = 0; t < kTargetCount; ++t) {
    if (e.reached(t)) continue;
    const std::optional<Targets> kept = keeping(bulk, targets, t, options.friction_coefficient);
    if (!kept) continue;
    std::string lowered;
    for (int other = 0; other < kTargetCount; ++other) {
      if (other == t || (*kept)[other] == targets[other]) continue;
      lowered += fmt::format("{}{} = {:.4g} MPa", lowered.empty() ? "" : " and ",
                             kTargetNames[other], mpa((*kept)[other]));
    }
    if (!lowered.empty()) {
      alternatives +=
          fmt::format(", or {} = {:.4g} MPa with {}", kTargetNames[t], mpa(targets[t]), lowered);
    }
  }
  std::string others;
  if (name_alternatives) {
    const std::vector<std::string> reaching =
        strategies_reaching(material, ply_angle, thickness, options);
    if (reaching.empty()) {
      others = "; no registered strategy meets XT, YT and S12 for this ply";
    } else {
      std::string list;
      for (const std::string& s : reaching) list += (list.empty() ? "" : ", ") + s;
      others = fmt::format("; strategies that meet XT, YT and S12 for this ply: {}", list);
    }
  }
  return fmt::format(
      "{} cannot give {} its strengths as simulated: {}. The least bond strengths that let no "
      "bond fail before a target leave it stronger there, and any other choice only makes it "
      "stronger still: {}{}",
      name, ply, missed, alternatives, others);
}

StrengthCalibration calibrate(const Strategy& strategy, const Calibration& calibration,
                              const Material& material, double ply_angle, double thickness,
                              const StrengthOptions& options, bool name_alternatives) {
  options.validate();
  require_strengths(material, "the strength calibration", options.softening);
  require(std::isfinite(ply_angle), "the strength calibration: the ply angle is not finite");
  require(std::isfinite(thickness) && thickness > 0,
          fmt::format("the strength calibration: the ply thickness must be positive, got {} m",
                      thickness));
  const std::string ply =
      fmt::format("material '{}' at {:.4g} deg", material.name, ply_angle / kDegree);
  const double diameter =
      options.particle_diameter > 0 ? options.particle_diameter : CouponSpec{}.particle_diameter;
  const RelaxedBulk bulk =
      relaxed_bulk(strategy, calibration, material, ply_angle, thickness, diameter, ply);
  const LaminaStrength& x = material.strength;
  const Targets targets = {x.XT, x.YT, x.S12};
  const Evaluation e = evaluate(bulk, targets, options.friction_coefficient);
  if (!e.all_reached()) {
    throw Error(unreachable_message(strategy_name(strategy), ply, bulk, e, targets, calibration,
                                    material, ply_angle, thickness, options, name_alternatives));
  }

  StrengthCalibration result;
  result.ply_angle = ply_angle;
  result.families = e.families;
  for (int f = 0; f < bulk.family_count; ++f)
    result.families[f].label = calibration.families[f].label;
  for (int b = 0; b < static_cast<int>(bulk.family.size()); ++b) {
    result.responses.push_back({bulk.family[b], bulk.unit[b]});
  }

  if (options.softening) {
    // A_crack = V / sum over the cell's bonds of L_b |n_b . n| (each cell bond is one bond per
    // cell volume V), averaged over the family's cell bonds.
    const Eigen::Vector3d fibre(std::cos(ply_angle), std::sin(ply_angle), 0.0);
    const int bonds = static_cast<int>(bulk.family.size());
    for (int f = 0; f < bulk.family_count; ++f) {
      FamilyStrength& fs = result.families[f];
      double area = 0;
      int count = 0;
      bool along_fibre = false;
      for (int b = 0; b < bonds; ++b) {
        if (bulk.family[b] != f) continue;
        double crossing = 0;
        for (int g = 0; g < bonds; ++g)
          crossing += bulk.length[g] * std::abs(bulk.normal[g].dot(bulk.normal[b]));
        area += bulk.volume / crossing;
        ++count;
        along_fibre = std::acos(std::min(1.0, std::abs(bulk.normal[b].dot(fibre)))) <=
                      kFibreFamilyAngle + 1e-12;
      }
      if (count == 0) continue;
      fs.crack_area = area / count;
      fs.fracture_energy = along_fibre ? x.G_fibre : x.G_matrix;
      // The bond's energy at the family's calibrated first failure: at the load that set its
      // tensile strength (its cohesion's if no load pulls it).
      const bool by_tension = e.tensile_load[f] >= 0;
      const int l = by_tension ? e.tensile_load[f] : e.cohesion_load[f];
      const int b = by_tension ? e.tensile_bond[f] : e.cohesion_bond[f];
      if (l < 0) continue;
      fs.peak_energy = energy_of(bulk.unit[b], bulk.stiffness[b],
                                 scaled(kLoads[l].unit, targets[kLoads[l].target]));
      fs.ductility = bond_ductility(fs.fracture_energy, fs.crack_area, fs.peak_energy);
    }
  }

  for (int t = 0; t < kTargetCount; ++t) {
    StrengthTarget target;
    target.name = kTargetNames[t];
    target.target = targets[t];
    target.model = e.model(t, targets);
    target.calibrated = true;
    int l = -1;
    for (int k = 0; k < kLoadCount; ++k)
      if (kLoads[k].target == t && (l < 0 || e.factor[k] > e.factor[l])) l = k;
    target.family = result.families[bulk.family[e.first_bond[l]]].label;
    target.mode = mode_name(e.first_mode[l]);
    result.targets.push_back(target);
  }
  // Compression: reported, not solved for.
  const std::pair<const char*, PlyStress> compression[2] = {{"XC", {-1, 0, 0}}, {"YC", {0, -1, 0}}};
  for (const auto& [name, stress] : compression) {
    StrengthTarget target;
    target.name = name;
    target.target = std::string(name) == "XC" ? x.XC : x.YC;
    const FirstFailure first = first_failure(bulk, result.families, stress);
    target.model = first.factor;  // per 1 Pa of compression
    target.calibrated = false;
    if (first.bond >= 0) {
      target.family = result.families[bulk.family[first.bond]].label;
      target.mode = mode_name(first.mode);
    }
    result.targets.push_back(target);
  }
  return result;
}

}  // namespace

void InterfaceStrength::validate() const {
  const std::pair<const char*, double> entries[] = {
      {"normal strength", normal}, {"shear strength", shear}, {"GIc", GIc}, {"GIIc", GIIc}};
  for (const auto& [name, value] : entries) {
    require(std::isfinite(value) && value >= 0,
            fmt::format("the interface {} must be finite and >= 0 (0 = not given), got {}", name,
                        value));
  }
  require((normal > 0) == (shear > 0),
          fmt::format("the interface needs both a normal and a shear strength, or neither (it "
                      "does not break); got normal {} Pa and shear {} Pa",
                      normal, shear));
  require(given() || (GIc == 0 && GIIc == 0),
          "the interface fracture energies GIc, GIIc need interface strengths (normal and shear)");
  require(GIIc == 0 || GIc > 0,
          fmt::format("the interface GIIc ({} J/m^2) needs GIc (interface.GIc): the mixed-mode "
                      "law scales the fracture energy from GIc",
                      GIIc));
  require(std::isfinite(bk_exponent) && bk_exponent > 0,
          fmt::format("the interface's Benzeggagh-Kenane exponent (interface.bk_exponent) must be "
                      "finite and > 0, got {}",
                      bk_exponent));
}

void StrengthOptions::validate() const {
  require(std::isfinite(friction_coefficient) && friction_coefficient >= 0,
          fmt::format("the bonds' friction coefficient tan(phi) must be finite and >= 0, got {}",
                      friction_coefficient));
  require(std::isfinite(particle_diameter) && particle_diameter >= 0,
          fmt::format("the strength calibration's particle diameter must be finite and >= 0 (0 = "
                      "the coupon default), got {} m",
                      particle_diameter));
}

double StrengthCalibration::first_failure_factor(const PlyStress& stress) const {
  const std::vector<double> factors = family_failure_factors(stress);
  return factors.empty() ? kInf : *std::min_element(factors.begin(), factors.end());
}

std::vector<double> StrengthCalibration::family_failure_factors(const PlyStress& stress) const {
  require(
      std::isfinite(stress.sigma1) && std::isfinite(stress.sigma2) && std::isfinite(stress.tau12),
      "first failure factor: the ply stress is not finite");
  std::vector<double> factors(families.size(), kInf);
  for (const UnitResponse& r : responses) {
    require(r.family >= 0 && r.family < static_cast<int>(families.size()),
            fmt::format("family failure factors: a response refers to bond family {} of {}",
                        r.family, families.size()));
    const FamilyStrength& f = families[r.family];
    factors[r.family] =
        std::min(factors[r.family],
                 critical_load(stresses_of(r.resultants, f.radius, stress), strength_of(f)).factor);
  }
  return factors;
}

StrengthCalibration calibrate_strengths(const Strategy& strategy, const Calibration& calibration,
                                        const Material& material, double ply_angle,
                                        double thickness, const StrengthOptions& options) {
  return calibrate(strategy, calibration, material, ply_angle, thickness, options, true);
}

void set_interface_bond_strength(Bonds& bonds, int b, double area,
                                 const InterfaceStrength& interface) {
  require(b >= 0 && b < bonds.size() && bonds.is_interface(b),
          fmt::format("set_interface_bond_strength: bond {} is not an interface bond", b));
  require(std::isfinite(area) && area > 0,
          fmt::format("interface bond {}: its interface area must be positive, got {}", b, area));
  const double radius = bonds.strength_radius(b);
  require(radius > 0, fmt::format("interface bond {} has no section radius", b));
  const double section = std::numbers::pi * radius * radius;
  bonds.tensile_strength(b) = interface.normal > 0 ? interface.normal * area / section : kInf;
  bonds.cohesion(b) = interface.shear > 0 ? interface.shear * area / section : kInf;
  bonds.friction_coefficient(b) = 0;
  bonds.mixed_mode_exponent(b) = interface.bk_exponent;
  // kappa_I = GIc area / E_I, E_I = (normal area)^2 / (2 k_n) the energy at onset in pure mode I;
  // E_II = (shear area)^2 / (2 k_s) in pure mode II. Brittle (kappa_I = g = r = 1) without GIc.
  bonds.ductility(b) = 1;
  bonds.fracture_energy_ratio(b) = 1;
  bonds.peak_energy_ratio(b) = 1;
  const double k_n = bonds.normal_stiffness(b), k_s = bonds.shear_stiffness(b);
  if (interface.GIc > 0 && interface.normal > 0 && k_n > 0) {
    const double normal_force = interface.normal * area;
    const double mode_I_energy = 0.5 * normal_force * normal_force / k_n;
    bonds.ductility(b) = bond_ductility(interface.GIc, area, mode_I_energy);
    bonds.fracture_energy_ratio(b) = interface.mode_II_energy() / interface.GIc;
    if (interface.shear > 0 && k_s > 0) {
      const double shear_force = interface.shear * area;
      bonds.peak_energy_ratio(b) = 0.5 * shear_force * shear_force / k_s / mode_I_energy;
    }
  }
}

namespace {

// SplitMix64's finaliser: a well-mixed 64-bit hash, for draws that do not depend on any order.
std::uint64_t mix64(std::uint64_t z) {
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

}  // namespace

double crack_band_factor(double weibull_modulus, std::uint64_t seed, int ply, long band) {
  require(std::isfinite(weibull_modulus) && weibull_modulus > 0,
          fmt::format("a crack band's strength factor needs a Weibull modulus > 0, got {}",
                      weibull_modulus));
  const std::uint64_t h =
      mix64(seed ^ mix64(static_cast<std::uint64_t>(ply) * 0x9e3779b97f4a7c15ULL +
                         static_cast<std::uint64_t>(band)));
  const double u = (static_cast<double>(h >> 11) + 0.5) * 0x1.0p-53;
  return std::pow(-std::log(u), 1.0 / weibull_modulus) / std::tgamma(1.0 + 1.0 / weibull_modulus);
}

namespace {

void check_strength_inputs(const Specimen& specimen, const std::vector<StrengthCalibration>& plies,
                           const InterfaceStrength& interface, double weibull_modulus) {
  interface.validate();
  require(std::isfinite(weibull_modulus) && weibull_modulus >= 0,
          fmt::format("the Weibull modulus must be finite and >= 0 (0 = no scatter), got {}",
                      weibull_modulus));
  const int ply_count = static_cast<int>(specimen.ply_calibrations.size());
  require(static_cast<int>(plies.size()) == ply_count,
          fmt::format("assign_bond_strengths: {} strength calibrations for a specimen of {} plies",
                      plies.size(), ply_count));
  for (int k = 0; k < ply_count; ++k) {
    require(
        plies[k].families.size() == specimen.ply_calibrations[k].families.size(),
        fmt::format("assign_bond_strengths: ply {} has {} bond families, its strength "
                    "calibration {}",
                    k + 1, specimen.ply_calibrations[k].families.size(), plies[k].families.size()));
  }
}

// Per crack site: one Weibull draw per band parallel to a ply's fibres (bands counted from the
// ply's lowest particle across its fibres), hashed from the seed, the ply and the band, so that
// a bond's factor depends on where it lies, not on any order.
class CrackSiteScatter {
 public:
  CrackSiteScatter(const Particles& p, const std::vector<StrengthCalibration>& plies,
                   double weibull_modulus, std::uint64_t seed, bool active)
      : p_(p),
        plies_(plies),
        weibull_modulus_(weibull_modulus),
        seed_(seed),
        across_origin_(plies.size(), std::numeric_limits<double>::infinity()) {
    const int ply_count = static_cast<int>(plies.size());
    if (active)
      for (int i = 0; i < p.size(); ++i) {
        const int k = p.ply(i);
        if (k >= 0 && k < ply_count)
          across_origin_[k] =
              std::min(across_origin_[k], across(k, p.reference_position.row(i).transpose()));
      }
  }
  // The factor of bond b (of ply k) in `bonds`.
  double operator()(const Bonds& bonds, int k, int b) const {
    const Eigen::Vector3d mid = 0.5 * (p_.reference_position.row(bonds.first(b)).transpose() +
                                       p_.reference_position.row(bonds.second(b)).transpose());
    const double diameter = p_.radius(bonds.first(b)) + p_.radius(bonds.second(b));
    const long band = std::lround(2.0 * (across(k, mid) - across_origin_[k]) / diameter);
    return crack_band_factor(weibull_modulus_, seed_, k, band);
  }

 private:
  double across(int k, const Eigen::Vector3d& x) const {
    const double a = plies_[k].ply_angle;
    return -std::sin(a) * x.x() + std::cos(a) * x.y();
  }
  const Particles& p_;
  const std::vector<StrengthCalibration>& plies_;
  double weibull_modulus_;
  std::uint64_t seed_;
  std::vector<double> across_origin_;
};

// An in-ply bond's strengths from its family's, scaled by its stiffness weight, its section
// radius and its scatter factor.
void set_ply_bond_strength(Bonds& bonds, int b, double radius, const FamilyStrength& fs,
                           const FamilyStiffness& bulk, double scatter) {
  // The bond's stiffness weight (boundary cells scale all four stiffnesses by it).
  double weight = 0;
  if (bulk.normal > 0) {
    weight = bonds.normal_stiffness(b) / bulk.normal;
  } else if (bulk.shear > 0) {
    weight = bonds.shear_stiffness(b) / bulk.shear;
  }
  if (!(weight > 0)) return;  // the bond carries nothing
  // Section stresses at a given strain scale as 1/R (forces as R, the section as R^2).
  const double size = fs.radius > 0 ? fs.radius / radius : 1.0;
  const double factor = weight * size * scatter;
  bonds.tensile_strength(b) = fs.tensile * factor;
  bonds.cohesion(b) = fs.cohesion * factor;
  bonds.friction_coefficient(b) = fs.friction;
  if (fs.fracture_energy > 0 && fs.peak_energy > 0) {
    // kappa_u = G A_crack / E_peak: A_crack scales as weight R, E_peak as weight R^2 scatter^2.
    bonds.ductility(b) =
        bond_ductility(fs.fracture_energy, fs.crack_area * weight / size,
                       fs.peak_energy * weight / (size * size) * scatter * scatter);
  }
}

}  // namespace

void assign_bond_strengths(Specimen& specimen, const std::vector<StrengthCalibration>& plies,
                           const InterfaceStrength& interface, double weibull_modulus,
                           std::uint64_t seed, const std::vector<bool>& scattered_plies,
                           bool per_crack_site) {
  check_strength_inputs(specimen, plies, interface, weibull_modulus);
  Model& model = specimen.model;
  const Particles& p = model.particles;
  Bonds& bonds = model.bonds;
  const int ply_count = static_cast<int>(specimen.ply_calibrations.size());
  // Interface bonds: each particle's interface area (its volume over the ply thickness) split
  // over its interface bonds, half from each end, as strategies/laminate.cpp gives them their
  // stiffness; a bond breaks when its traction F / area reaches the interface strength.
  std::vector<int> interface_count(p.size(), 0);
  for (int b = 0; b < bonds.size(); ++b) {
    if (!bonds.is_interface(b)) continue;
    ++interface_count[bonds.first(b)];
    ++interface_count[bonds.second(b)];
  }
  const double ply_thickness = model.thickness / std::max(ply_count, 1);

  // Weibull scatter: draw k of std::mt19937_64(seed) goes to bond row k (every row draws, so a
  // bond's factor depends only on its row and the seed), U = (draw / 2^11 + 1/2) / 2^53 in (0, 1).
  std::mt19937_64 random(seed);
  const double weibull_mean = weibull_modulus > 0 ? std::tgamma(1.0 + 1.0 / weibull_modulus) : 1.0;
  const CrackSiteScatter site_scatter(p, plies, weibull_modulus, seed,
                                      per_crack_site && weibull_modulus > 0);
  for (int b = 0; b < bonds.size(); ++b) {
    double scatter = 1.0;
    if (weibull_modulus > 0) {
      const double u = (static_cast<double>(random() >> 11) + 0.5) * 0x1.0p-53;
      scatter = std::pow(-std::log(u), 1.0 / weibull_modulus) / weibull_mean;
    }
    require(
        bonds.damage(b) == 0 && !bonds.is_broken(b),
        fmt::format("assign_bond_strengths needs an intact specimen, but bond {} is damaged", b));
    const int i = bonds.first(b), j = bonds.second(b);
    const double radius = std::min(p.radius(i), p.radius(j));
    bonds.strength_radius(b) = radius;
    bonds.tensile_strength(b) = kInf;
    bonds.cohesion(b) = kInf;
    bonds.friction_coefficient(b) = 0;
    bonds.ductility(b) = 1;
    if (bonds.is_interface(b)) {
      if (!interface.given()) continue;
      const double area = 0.5 * (p.volume(i) / ply_thickness / interface_count[i] +
                                 p.volume(j) / ply_thickness / interface_count[j]);
      set_interface_bond_strength(bonds, b, area, interface);
      continue;
    }
    const int k = p.ply(i);
    require(k >= 0 && k < ply_count,
            fmt::format("assign_bond_strengths: bond {} belongs to ply {}, but the specimen has {} "
                        "plies",
                        b, k + 1, ply_count));
    if (!scattered_plies.empty() &&
        !(k < static_cast<int>(scattered_plies.size()) && scattered_plies[k])) {
      scatter = 1.0;
    } else if (per_crack_site && weibull_modulus > 0) {
      scatter = site_scatter(bonds, k, b);
    }
    const int f = bonds.family(b);
    require(f >= 0 && f < static_cast<int>(plies[k].families.size()),
            fmt::format("assign_bond_strengths: bond {} has family {}, but ply {} has {} families",
                        b, f, k + 1, plies[k].families.size()));
    set_ply_bond_strength(bonds, b, radius, plies[k].families[f],
                          specimen.ply_calibrations[k].families[f].stiffness, scatter);
  }
}

}  // namespace plydem
