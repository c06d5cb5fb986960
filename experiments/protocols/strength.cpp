#include "experiments/protocols/strength.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <limits>
#include <map>
#include <numbers>
#include <optional>
#include <random>
#include <span>
#include <string_view>

#include "contacts/bond_kernel.hpp"
#include "core/error.hpp"
#include "core/homogenizer.hpp"
#include "core/measurements.hpp"
#include "core/shear_curve.hpp"
#include "core/stopwatch.hpp"
#include "core/units.hpp"
#include "solvers/plastic_shear.hpp"
#include "strategies/boundary_cells.hpp"
#include "strategies/cure_stress.hpp"
#include "strategies/registry.hpp"

namespace plydem {
namespace {

using Clock = Stopwatch::Clock;

// The right grip's travel at load factor 1: a nominal strain of 1e-3 (the tension test's target
// strain), so that load factors are of order one. Any value gives the same path: the model is
// linear between events.
constexpr double kUnitNominalStrain = 1e-3;

// +1 in tension, -1 in compression: the sign of the grips' travel and of the stress along x.
double load_sign(StrengthLoad load) {
  return load == StrengthLoad::kCompression ? -1.0 : 1.0;
}

// The mean membrane stress (sigma_x, sigma_y, tau_xy) of a unit load: sigma_x = 1 Pa in tension,
// -1 Pa in compression, tau_xy = 1 Pa in shear.
Eigen::Vector3d unit_mean_stress(StrengthLoad load) {
  return load == StrengthLoad::kShear ? Eigen::Vector3d(0, 0, 1)
                                      : Eigen::Vector3d(load_sign(load), 0, 0);
}

// The stress of the coupon's plies under the unit load's mean stress (unit_mean_stress; classical
// lamination theory, A matrix), in each ply's axes.
std::vector<PlyStress> unit_ply_stresses(const std::vector<Ply>& plies,
                                         StrengthLoad load = StrengthLoad::kTension) {
  require(!plies.empty(), "a laminate needs at least one ply");
  const Eigen::Matrix3d A = laminate_extensional_stiffness(plies);
  double h = 0;
  for (const Ply& ply : plies) h += ply.thickness;
  const Eigen::Vector3d strain = A.ldlt().solve(h * unit_mean_stress(load));
  std::vector<PlyStress> stresses;
  for (const Ply& ply : plies) {
    const Eigen::Vector3d s =
        rotate_reduced_stiffness(reduced_stiffness(ply.material), ply.angle) * strain;
    stresses.push_back(to_ply_axes(s(0), s(1), s(2), ply.angle));
  }
  return stresses;
}

std::string family_label(const StrengthCalibration& ply, int family) {
  if (family >= 0 && family < static_cast<int>(ply.families.size()) &&
      !ply.families[static_cast<std::size_t>(family)].label.empty()) {
    return ply.families[static_cast<std::size_t>(family)].label;
  }
  return fmt::format("{}", family + 1);
}

// A bond fails "before its family" below this relative margin.
constexpr double kEdgeTolerance = 1e-6;

// The factor by which each bond's strengths must grow so that, in the coupon solved at the unit
// load `unit`, it fails no earlier than the first bond of its ply's relaxed bulk under the same
// uniform stress (`ply_stress` per ply, at the unit load); 1 for every other bond. See
// StrengthSettings::consistent_edges.
// Bonds whose two particles both lie within `keep_radius` of `keep_centre` (x, y) keep their
// strengths: the notch's own concentration is not an edge artefact.
std::vector<double> edge_strength_factors(const Model& model, const DofConstraints& unit,
                                          const StaticSettings& settings,
                                          const std::vector<StrengthCalibration>& plies,
                                          const std::vector<PlyStress>& ply_stress,
                                          const Eigen::Vector2d& keep_centre, double keep_radius) {
  Model solved = model;
  StaticSystem(solved, unit, settings).solve(solved, unit.value);
  std::vector<double> bulk_first;
  for (std::size_t k = 0; k < plies.size(); ++k)
    bulk_first.push_back(plies[k].first_failure_factor(ply_stress[k]));
  const Particles& p = solved.particles;
  const Bonds& bonds = solved.bonds;
  std::vector<double> factors(static_cast<std::size_t>(bonds.size()), 1.0);
  for (int b = 0; b < bonds.size(); ++b) {
    if (bonds.is_interface(b) || bonds.is_broken(b)) continue;
    const BondStrength strength = bond_strength(bonds, b);
    if (!std::isfinite(strength.tensile) && !std::isfinite(strength.cohesion)) continue;
    const int i = bonds.first(b), j = bonds.second(b);
    if (keep_radius > 0) {
      auto near = [&](int k) {
        return (Eigen::Vector2d(p.reference_position(k, 0), p.reference_position(k, 1)) -
                keep_centre)
                   .norm() < keep_radius;
      };
      if (near(i) || near(j)) continue;
    }
    const BondStresses stresses = intact_stresses(
        bond_stresses(bond_parameters(bonds, b), strength.radius, p.displacement.row(i).transpose(),
                      p.rotation.row(i).transpose(), p.displacement.row(j).transpose(),
                      p.rotation.row(j).transpose()),
        bonds.damage(b));
    const double own = critical_load(stresses, strength).factor;
    const auto ply = static_cast<std::size_t>(p.ply(i));
    const auto family = static_cast<std::size_t>(bonds.family(b));  // checked, not used
    require(ply < bulk_first.size() && family < plies[ply].families.size(),
            fmt::format("bond {} belongs to ply {} family {}, which the strength calibration "
                        "does not have",
                        b, ply, family));
    const double target = bulk_first[ply];
    // Round-off leaves the bulk's own bonds within ~1e-12 of their family: they keep theirs.
    if (std::isfinite(target) && own < target * (1.0 - kEdgeTolerance))
      factors[static_cast<std::size_t>(b)] = target / own;
  }
  return factors;
}

// Multiplies bond b's strengths by factors[b], keeping a softening bond's dissipated energy (its
// peak energy grows as the square of its strength, so kappa_u falls by it).
void raise_strengths(Bonds& bonds, const std::vector<double>& factors) {
  for (int b = 0; b < bonds.size(); ++b) {
    const double f = factors[static_cast<std::size_t>(b)];
    if (f == 1.0) continue;
    bonds.tensile_strength(b) *= f;
    bonds.cohesion(b) *= f;
    bonds.ductility(b) = std::max(1.0, bonds.ductility(b) / (f * f));
  }
}

// The hole of `s` stays clear of grips `grip` [m] long.
void require_hole_clear_of_grips(const StrengthSettings& s, double grip) {
  require(
      s.hole_diameter < s.coupon.length - 2.0 * grip,
      fmt::format("a {:g} mm hole reaches into the grips ({:g} mm each) of a {:g} mm long coupon",
                  s.hole_diameter * 1e3, grip * 1e3, s.coupon.length * 1e3));
}

}  // namespace

const char* strength_grips_name(StrengthGrips grips) {
  switch (grips) {
    case StrengthGrips::kUniform:
      return "uniform";
    case StrengthGrips::kFree:
      return "free";
    case StrengthGrips::kClamped:
      return "clamped";
  }
  return "?";
}

StrengthGrips parse_strength_grips(const std::string& name) {
  if (name == "uniform") return StrengthGrips::kUniform;
  if (name == "free") return StrengthGrips::kFree;
  if (name == "clamped") return StrengthGrips::kClamped;
  throw Error(fmt::format("unknown grips '{}' (uniform, free or clamped)", name));
}

const char* strength_load_name(StrengthLoad load) {
  switch (load) {
    case StrengthLoad::kTension:
      return "tension";
    case StrengthLoad::kCompression:
      return "compression";
    case StrengthLoad::kShear:
      return "shear";
  }
  return "?";
}

StrengthLoad parse_strength_load(const std::string& name) {
  if (name == "tension") return StrengthLoad::kTension;
  if (name == "compression") return StrengthLoad::kCompression;
  if (name == "shear") return StrengthLoad::kShear;
  throw Error(fmt::format("unknown load '{}' (tension, compression or shear)", name));
}

const char* strength_method_name(StrengthMethod method) {
  return method == StrengthMethod::kEvents ? "events" : "explicit";
}

StrengthMethod parse_strength_method(const std::string& name) {
  if (name == "events") return StrengthMethod::kEvents;
  if (name == "explicit") return StrengthMethod::kExplicit;
  throw Error(fmt::format("unknown strength method '{}' (events or explicit)", name));
}

double StrengthSettings::effective_weibull_modulus() const {
  return weibull_modulus ? *weibull_modulus : coupon.material.strength.weibull_modulus;
}

PlyFailureModel StrengthSettings::effective_failure_criterion() const {
  return failure_criterion ? *failure_criterion : coupon.material.failure_criterion;
}

void StrengthSettings::require_strengths_for(const std::string& purpose) const {
  // The strength test decides failure at the material point itself (material_point_failure), so
  // require_strengths checks the strengths only.
  Material checked = coupon.material;
  checked.failure_criterion = PlyFailureModel::kBond;
  require_strengths(checked, purpose, strength_options.softening);
  if (load != StrengthLoad::kCompression) return;
  const LaminaStrength& ls = coupon.material.strength;
  std::string missing;
  if (!(ls.XC > 0)) missing += "XC";
  if (!(ls.YC > 0)) missing += missing.empty() ? "YC" : " and YC";
  require(missing.empty(),
          fmt::format("{} in compression needs the compressive strengths XC and YC; material '{}' "
                      "does not give {}",
                      purpose, coupon.material.name, missing));
}

namespace {

// The coupled criterion's needs: failure at the material point, brittle, by the events method,
// with a matrix fracture energy.
void require_coupled_criterion_inputs(const StrengthSettings& s) {
  require(s.effective_failure_criterion() != PlyFailureModel::kBond,
          "the coupled criterion (--coupled-criterion) decides matrix cracks at the material "
          "point, and the plies fail bond by bond (give --failure-criterion puck, hashin, "
          "max-stress or tsai-wu)");
  require(!s.strength_options.softening,
          "the coupled criterion (--coupled-criterion) opens brittle cracks, and --softening "
          "makes them soften (leave out one of the two)");
  require(s.coupon.material.strength.G_matrix > 0,
          fmt::format("the coupled criterion (--coupled-criterion) opens a matrix crack when it "
                      "releases G_matrix per unit area: material '{}' gives no G_matrix (J/m^2)",
                      s.coupon.material.name));
  require(s.method == StrengthMethod::kEvents,
          "the coupled criterion (--coupled-criterion) is decided by the events method only "
          "(use --method events)");
}

}  // namespace

void StrengthSettings::validate() const {
  coupon.validate();
  require(std::isfinite(hole_diameter) && hole_diameter >= 0,
          fmt::format("the hole diameter must be >= 0 (0 = no hole), got {:g} mm",
                      hole_diameter * 1e3));
  if (hole_diameter > 0) {
    require(
        hole_diameter < 0.9 * coupon.width,
        fmt::format("a {:g} mm hole in a {:g} mm wide coupon leaves ligaments narrower than 5% of "
                    "the width each: the hole must be narrower than 0.9 W ({:g} mm)",
                    hole_diameter * 1e3, coupon.width * 1e3, 0.9 * coupon.width * 1e3));
    require(
        hole_diameter >= coupon.particle_diameter,
        fmt::format("a {:g} mm hole is narrower than one particle ({:g} mm): the particles cannot "
                    "resolve it",
                    hole_diameter * 1e3, coupon.particle_diameter * 1e3));
    // The shortest grips a run gives (at the material point run() checks its own again).
    require_hole_clear_of_grips(*this,
                                grip_length > 0 ? grip_length : 2.0 * coupon.particle_diameter);
  }
  for (double angle : layup)
    require(std::isfinite(angle), "a ply angle of the layup is not finite");
  if (!layup.empty()) interface.validate();
  interface_strength.validate();
  require(
      !(interface_strength.given() || interface_strength.GIc > 0 || interface_strength.GIIc > 0) ||
          !layup.empty(),
      "interface strengths and fracture energies need a laminate (--layup): one ply has no "
      "interface");
  if (weibull_modulus) {
    require(std::isfinite(*weibull_modulus) && *weibull_modulus >= 0,
            fmt::format("the Weibull modulus must be finite and >= 0 (0 = no scatter), got {}",
                        *weibull_modulus));
  }
  const int ply_count = layup.empty() ? 1 : static_cast<int>(layup.size());
  for (int k : scatter_plies) {
    require(k >= 0 && k < ply_count,
            fmt::format("the scattered ply {} does not exist: the coupon has {} plies (0 to {})", k,
                        ply_count, ply_count - 1));
  }
  require(grip_length >= 0 && std::isfinite(grip_length), "grip length must be >= 0");
  require(std::isfinite(gauge_fraction) && gauge_fraction > 0 && gauge_fraction < 1,
          fmt::format("gauge fraction must lie in (0, 1), got {}", gauge_fraction));
  require(std::isfinite(edge_band_diameters) && edge_band_diameters >= 0,
          "the gauge's edge band must be >= 0 diameters");
  strength_options.validate();
  require(std::isfinite(delta_T) && std::abs(delta_T) <= 500,
          fmt::format("thermal.delta_T must be a temperature change of at most 500 K, got {} K",
                      delta_T));
  require(delta_T == 0 || coupon.material.thermal_expansion_given,
          fmt::format("thermal.delta_T = {} K needs the material's thermal expansion: material "
                      "'{}' gives no alpha1, alpha2",
                      delta_T, coupon.material.name));
  if (coupled_criterion) require_coupled_criterion_inputs(*this);
  require(delta_T == 0 || method == StrengthMethod::kEvents,
          "thermal.delta_T (cure stresses) is taken by the events method only: the explicit "
          "kernels refuse the bonds' free offsets (use --method events)");
  require(
      load != StrengthLoad::kCompression || effective_failure_criterion() != PlyFailureModel::kBond,
      "compression (--load compression) needs failure at the material point "
      "(--failure-criterion puck, hashin, max-stress or tsai-wu): bonds calibrated by the "
      "parallel-bond law have no compressive strength, so a coupon of them would not fail at "
      "XC or YC");
  if (load == StrengthLoad::kShear) {
    require(effective_failure_criterion() != PlyFailureModel::kBond,
            "shear (--load shear) needs failure at the material point (--failure-criterion puck, "
            "hashin, max-stress or tsai-wu): the shear frame is made for sites judged by a lamina "
            "criterion");
    require(grips == StrengthGrips::kUniform,
            fmt::format("shear (--load shear) holds the coupon in a frame at the uniform state "
                        "(--grips uniform); --grips {} holds only its ends along x",
                        strength_grips_name(grips)));
    require(!(hole_diameter > 0),
            "shear (--load shear) of a coupon with a hole is not modelled (the frame's y bands "
            "would have to clear the hole): leave out --hole-diameter-mm");
  }
  require(!events.on_progress && !events.on_event,
          "the strength test sets the events solver's callbacks itself (use "
          "StrengthTest::on_progress)");
  events.validate();
  require(events.checkpoint_every == 0 && !events.on_checkpoint,
          "the strength test sets the events solver's checkpoints itself (use "
          "StrengthSettings::checkpoint)");
  ExplicitFailureSettings failure;
  failure.integrator = explicit_settings;
  failure.cycles_to_failure = explicit_loading.cycles_to_failure;
  failure.check_cycles = explicit_loading.check_cycles;
  failure.max_cycles = explicit_loading.max_cycles;
  failure.stop_fraction = events.stop_fraction;
  failure.validate();
  checkpoint.validate();
  if (method != StrengthMethod::kExplicit) return;
  require(effective_failure_criterion() != PlyFailureModel::kBond,
          "the strength test's explicit method decides failure at the material point "
          "(--failure-criterion puck, hashin, max-stress or tsai-wu); bond by bond (the "
          "parallel-bond law) its dynamics and the events method part after the first break, "
          "where the lattice's diagonals bridge the cracks (square, E-glass, 3 x 1 mm, 90 deg: "
          "0.88 of the events method's peak without scatter, 1.84 with Weibull modulus 10; at 0 "
          "and 30 deg they agree within 0.1%): use --method events for failure_criterion = "
          "\"bond\"");
  require(!checkpoint.writes() && checkpoint.restart.empty(),
          "checkpoints and restarts of the strength test (--checkpoint-every, --checkpoint, "
          "--restart) are written for the events method only (use --method events)");
  require(!(strength_options.softening && effective_failure_criterion() != PlyFailureModel::kBond),
          "softening cracks at the material point are opened by the events method only (its "
          "saw-tooth dissipates G exactly); the explicit method opens them brittle (leave out "
          "--softening, or use --method events)");
}

CheckpointHeader strength_checkpoint_header(const StrengthSettings& s) {
  CheckpointHeader h;
  h.kind = fmt::format("strength/{}", strength_method_name(s.method));
  add_coupon_settings(h, s.strategy, s.strategy_options, s.coupon, s.layup, s.interface,
                      s.grip_length, s.gauge_fraction);
  h.add("interface_strength.normal", exact(s.interface_strength.normal));
  h.add("interface_strength.shear", exact(s.interface_strength.shear));
  h.add("interface_strength.GIc", exact(s.interface_strength.GIc));
  h.add("interface_strength.GIIc", exact(s.interface_strength.GIIc));
  h.add("interface_strength.bk_exponent", exact(s.interface_strength.bk_exponent));
  h.add("weibull_modulus", exact(s.effective_weibull_modulus()));
  if (!s.scatter_plies.empty()) {
    std::string plies;
    for (int k : s.scatter_plies) plies += fmt::format("{}{}", plies.empty() ? "" : ",", k);
    h.add("scatter_plies", plies);
  }
  if (s.scatter_per_crack_site) h.add("scatter_per", "crack site");
  if (s.delta_T != 0) h.add("delta_T", exact(s.delta_T));
  if (s.coupled_criterion) h.add("coupled_criterion", "true");
  h.add("seed", fmt::format("{}", s.seed));
  h.add("friction", exact(s.strength_options.friction_coefficient));
  h.add("softening", s.strength_options.softening ? "true" : "false");
  h.add("failure_criterion", failure_model_name(s.effective_failure_criterion()));
  h.add("strength_particle_diameter", exact(s.strength_options.particle_diameter));
  h.add("edge_band_diameters", exact(s.edge_band_diameters));
  h.add("hole_diameter", exact(s.hole_diameter));
  h.add("grips", strength_grips_name(s.grips));
  if (s.load != StrengthLoad::kTension) h.add("load", strength_load_name(s.load));
  h.add("linear_solver", fmt::format("{}", static_cast<int>(s.linear_solver)));
  h.add("edge_strengths", s.consistent_edges ? "bulk" : "weighted");
  const EventSettings& e = s.events;
  h.add("max_events", fmt::format("{}", e.max_events));
  h.add("stop_fraction", exact(e.stop_fraction));
  h.add("tooth_stiffness_ratio", exact(e.tooth_stiffness_ratio));
  h.add("last_tooth_stiffness", exact(e.last_tooth_stiffness));
  h.add("max_update_rank", fmt::format("{}", e.max_update_rank));
  h.add("refactor_every_event", e.refactor_every_event ? "true" : "false");
  h.add("static.method", fmt::format("{}", static_cast<int>(e.static_settings.method)));
  h.add("static.pivot_tolerance", exact(e.static_settings.pivot_tolerance));
  h.add("snapshots (--out)", s.record_snapshots ? "recorded" : "not recorded");
  h.add("settings_hash", fmt::format("{:016x}", h.settings_hash()));
  return h;
}

double first_ply_failure_stress(FailureCriterion criterion, const std::vector<Ply>& plies,
                                const LaminaStrength& strength, StrengthLoad load) {
  if (plies.size() == 1 && load != StrengthLoad::kShear) {
    return load == StrengthLoad::kTension
               ? off_axis_strength(criterion, strength, plies.front().angle)
               : off_axis_compressive_strength(criterion, strength, plies.front().angle);
  }
  double factor = std::numeric_limits<double>::infinity();
  for (const PlyStress& s : unit_ply_stresses(plies, load))
    factor = std::min(factor, failure_load_factor(criterion, s, strength));
  return factor;
}

StrengthTest::StrengthTest(StrengthSettings settings) : settings_(std::move(settings)) {
  settings_.validate();
}

void StrengthTest::on_progress(std::function<void(const EventProgress&)> callback) {
  progress_ = std::move(callback);
}

ResourceEstimate StrengthTest::estimate(const Strategy& strategy) const {
  // The built coupon and the events solver's working copy (and the VTU series' snapshots).
  return estimate_resources(
      strategy, settings_.coupon, settings_.layup, settings_.interface,
      settings_.method == StrengthMethod::kExplicit ? SolverUse::kExplicit : SolverUse::kEvents,
      settings_.record_snapshots ? 10 : 2, settings_.events.max_update_rank);
}

StrengthResult StrengthTest::run() const {
  const std::unique_ptr<Strategy> strategy = default_registry().create(settings_.strategy);
  for (const auto& [name, value] : settings_.strategy_options) strategy->set_option(name, value);
  SpecimenBuilder builder(*strategy);
  return run(builder);
}

namespace {

// The plies as CLT sees them, bottom to top (a laminate's angles into result.layup).
std::vector<Ply> coupon_plies(const StrengthSettings& s, StrengthResult& result) {
  std::vector<Ply> plies;
  if (s.layup.empty()) {
    plies.push_back({s.coupon.material, s.coupon.ply_angle, s.coupon.thickness});
  } else {
    plies = laminate_plies({s.coupon, s.layup, s.interface});
    for (const Ply& ply : plies) result.layup.push_back(ply.angle);
  }
  return plies;
}

// Strengths of each distinct ply, before the coupon is built (a strategy or target the
// calibration refuses fails here); the builder keeps the stiffness calibrations for the build.
std::vector<StrengthCalibration> calibrate_ply_strengths(SpecimenBuilder& builder,
                                                         const StrengthSettings& s,
                                                         const std::vector<Ply>& plies) {
  std::vector<StrengthCalibration> strengths;
  std::map<std::string, StrengthCalibration> calibrated;
  for (const Ply& ply : plies) {
    CouponSpec spec = s.coupon;
    spec.ply_angle = ply.angle;
    const std::string key = builder.strategy().calibration_key(spec);
    auto it = calibrated.find(key);
    if (it == calibrated.end()) {
      // Family strengths stated for the coupon's particles (the report's numbers are the bonds').
      StrengthOptions options = s.strength_options;
      if (options.particle_diameter == 0) options.particle_diameter = s.coupon.particle_diameter;
      it = calibrated
               .emplace(key, calibrate_strengths(builder.strategy(), builder.calibration(spec),
                                                 s.coupon.material, ply.angle, s.coupon.thickness,
                                                 options))
               .first;
    }
    strengths.push_back(it->second);
  }
  return strengths;
}

// The coupon, as the tension test builds it. A hole is cut into the coupon built without edge
// completion, and its edges then completed (result.hole, result.hole_centre).
Specimen build_strength_coupon(SpecimenBuilder& builder, const StrengthSettings& s,
                               StrengthResult& result) {
  std::optional<BoundaryCompletion> completion;
  CouponSpec coupon = s.coupon;
  if (s.hole_diameter > 0) {
    if (coupon.complete_boundary_cells)
      completion = hole_boundary_completion(builder.strategy(), s.strategy);
    coupon.complete_boundary_cells = false;
  }
  Specimen specimen = build_coupon(builder, coupon, s.layup, s.interface, s.coupon.ply_angle);
  if (s.hole_diameter > 0) {
    const Particles& q = specimen.model.particles;
    const Eigen::Vector3d low = q.reference_position.colwise().minCoeff().transpose();
    const Eigen::Vector3d high = q.reference_position.colwise().maxCoeff().transpose();
    result.hole_centre = 0.5 * (low + high).head<2>();
    result.hole = remove_hole(specimen.model, result.hole_centre.x(), result.hole_centre.y(),
                              s.hole_diameter);
    if (completion) complete_ply_boundary_cells(specimen.model, *completion);
  }
  return specimen;
}

// Each classical criterion's strength of the plies (a criterion needing a strength the material
// does not give: the reason instead).
std::vector<CriterionStrength> classical_strengths(const std::vector<Ply>& plies,
                                                   const LaminaStrength& strength,
                                                   StrengthLoad load) {
  std::vector<CriterionStrength> theory;
  for (FailureCriterion criterion : all_criteria()) {
    CriterionStrength t{criterion, std::nullopt, ""};
    try {
      t.strength = first_ply_failure_stress(criterion, plies, strength, load);
    } catch (const Error& e) {
      t.missing = e.what();  // a strength the criterion needs is not given
    }
    theory.push_back(t);
  }
  return theory;
}

// The calibrated bulk's own first failure under the coupon's load.
double bulk_first_failure(const std::vector<Ply>& plies,
                          const std::vector<StrengthCalibration>& ply_strengths) {
  double factor = std::numeric_limits<double>::infinity();
  const std::vector<PlyStress> stresses = unit_ply_stresses(plies);
  for (std::size_t k = 0; k < plies.size(); ++k)
    factor = std::min(factor, ply_strengths[k].first_failure_factor(stresses[k]));
  return factor;
}

// The gripped coupon at the unit load: its gauge section, the grips' prescribed values and the
// degrees of freedom whose reactions sum to the load.
struct UnitLoading {
  CouponGrips grips;
  GaugeSection gauge;
  DofConstraints unit;
  DofFlags reaction_dofs;
};

// The particles uniform grips hold: those of the grips, and in shear also those within the
// grips' depth of the y edges (the frame: StrengthSettings::load).
std::vector<bool> held_by_grips(const Particles& p, StrengthLoad load) {
  std::vector<bool> held(static_cast<std::size_t>(p.size()));
  for (int i = 0; i < p.size(); ++i)
    held[static_cast<std::size_t>(i)] = p.group(i) != static_cast<int>(BoundaryGroup::kFree);
  if (load != StrengthLoad::kShear) return held;
  // The grips' depth along x, as assign_grips left it.
  const double depth = grip_faces(p).left - p.reference_position.col(0).minCoeff();
  const double y_min = p.reference_position.col(1).minCoeff();
  const double y_max = p.reference_position.col(1).maxCoeff();
  for (int i = 0; i < p.size(); ++i) {
    const double y = p.reference_position(i, 1);
    if (y <= y_min + depth || y >= y_max - depth) held[static_cast<std::size_t>(i)] = true;
  }
  return held;
}

// A shear frame's bonds between two held particles go: they would carry the frame's own uniform
// shear for ever and add it to the right grip's reaction, which then never falls when the gauge
// cracks through; the free particles' equilibrium, which every solve finds, does not see them. A
// picture-frame test's arms, likewise, are hinged at the corners and carry nothing between them.
void drop_frame_bonds(Model& model, const std::vector<bool>& held) {
  std::vector<int> kept;
  const Bonds& bonds = model.bonds;
  for (int b = 0; b < bonds.size(); ++b)
    if (!held[static_cast<std::size_t>(bonds.first(b))] ||
        !held[static_cast<std::size_t>(bonds.second(b))])
      kept.push_back(b);
  model.bonds = bonds.select(kept);
}

// Uniform grips: the relaxed bulk's uniform state under sigma_x (in shear: tau_xy), the plies'
// relaxed stiffness summed as CLT sums Q-bar, its strain per unit eps_xx, and each ply's spin under
// that strain (into result.uniform_strain and result.uniform_spin).
DofConstraints uniform_unit_load(const Strategy& strategy, double thickness,
                                 const std::vector<Calibration>& calibrations, const Particles& p,
                                 double travel, StrengthLoad load, StrengthResult& result) {
  Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
  for (const Calibration& c : calibrations) A += c.relaxed;
  // Per unit eps_xx under sigma_x, per unit gamma_xy under tau_xy.
  const int along = load == StrengthLoad::kShear ? 2 : 0;
  Eigen::Vector3d e = A.ldlt().solve(Eigen::Vector3d::Unit(along));
  require(e(along) > 0, "the coupon's relaxed stiffness gives no positive strain under the load");
  e /= e(along);
  result.uniform_strain = e;
  for (const Calibration& c : calibrations) {
    const std::optional<UnitCell> cell = strategy.unit_cell(c, thickness);
    double spin = 0;
    if (cell && cell->basis.size() == 1) {
      std::vector<FamilyStiffness> families;
      for (const FamilyCalibration& f : c.families) families.push_back(f.stiffness);
      Vector6d voigt;
      voigt << e(0), e(1), 0, 0, 0, e(2);
      spin = relaxed_motion(*cell, families, voigt).rotation[0].z();
    }
    result.uniform_spin.push_back(spin);
  }
  std::vector<double> spin = result.uniform_spin;
  for (double& w : spin) w *= travel;
  return uniform_grip_constraints(p, travel * e, spin, held_by_grips(p, load));
}

// The grips' length when StrengthSettings::grip_length is 0: two diameters bond by bond (the
// tension test's); at the material point, the edge strips' depth plus the coupon's longest in-ply
// bond, so that the strips' corners, where the edge balance writes no equilibrium
// (strategies/boundary_cells.hpp), lie in the grips and not in the gauge beside them. With two
// diameters the first site to crack off axis is there: E-glass, square, 3 x 1 mm, 0.1 mm
// particles, Puck: 0.88 of the criterion at 30 deg, 0.90 at 60 and 75 deg; 0.97-0.98 so.
double default_grip_length(const StrengthSettings& s, const Model& model) {
  const double two_diameters = 2.0 * s.coupon.particle_diameter;
  // A shear frame leaves no free edge: no edge strips to hold.
  if (s.effective_failure_criterion() == PlyFailureModel::kBond || s.load == StrengthLoad::kShear)
    return two_diameters;
  double reach = 0;
  for (int b = 0; b < model.bonds.size(); ++b)
    if (!model.bonds.is_interface(b)) reach = std::max(reach, model.bonds.length(b));
  return std::max(two_diameters, kEdgeStripDiameters * s.coupon.particle_diameter + reach);
}

// Grips, gauge section, the unit loading.
UnitLoading grip_coupon(const Strategy& strategy, const StrengthSettings& s,
                        const std::vector<Calibration>& calibrations, Model& model,
                        StrengthResult& result) {
  Particles& p = model.particles;
  UnitLoading l;
  const double grip = s.grip_length > 0 ? s.grip_length : default_grip_length(s, model);
  if (s.hole_diameter > 0) require_hole_clear_of_grips(s, grip);
  l.grips = assign_grips(p, grip);  // refuses grips that leave no free length
  // In shear the gauge keeps clear of the frame's y bands by a diameter.
  const double band = s.load == StrengthLoad::kShear
                          ? std::max(s.edge_band_diameters, grip / s.coupon.particle_diameter + 1)
                          : s.edge_band_diameters;
  l.gauge = gauge_section(p, l.grips, s.gauge_fraction, band, s.coupon.particle_diameter);
  // The grips' nominal strain at load factor 1, signed.
  const double travel = load_sign(s.load) * kUnitNominalStrain;
  if (s.grips == StrengthGrips::kUniform) {
    l.unit =
        uniform_unit_load(strategy, s.coupon.thickness, calibrations, p, travel, s.load, result);
  } else {
    l.unit = grip_constraints(
        p, 0.0, travel * l.grips.span,
        s.grips == StrengthGrips::kClamped ? GripCondition::kClamped : GripCondition::kFree);
  }
  if (s.load == StrengthLoad::kShear) drop_frame_bonds(model, held_by_grips(p, s.load));
  // The load: the right grip's x reactions, in shear its y reactions (tau_xy times the section).
  const Dof load_dof = s.load == StrengthLoad::kShear ? Dof::kUy : Dof::kUx;
  l.reaction_dofs = DofFlags::Constant(p.size(), kDofsPerParticle, false);
  for (int i = 0; i < p.size(); ++i) {
    if (p.group(i) == static_cast<int>(BoundaryGroup::kRightGrip))
      l.reaction_dofs(i, static_cast<int>(load_dof)) = true;
  }
  result.particles = p.size();
  result.bonds = model.bonds.size();
  result.cross_section = l.gauge.cross_section;
  result.span = l.grips.span;
  return l;
}

// StrengthSettings::consistent_edges: the bonds that would fail before the relaxed bulk raised to
// fail with it, after the scatter (if any) is drawn on the strengths as assigned.
void make_edges_consistent(const StrengthSettings& s, const std::vector<Ply>& plies,
                           const std::vector<Calibration>& calibrations,
                           const std::vector<bool>& scattered_plies, const DofConstraints& unit,
                           const StaticSettings& grip_settings, Model& model,
                           StrengthResult& result) {
  std::vector<PlyStress> ply_stress;
  for (std::size_t k = 0; k < plies.size(); ++k) {
    const Eigen::Vector3d sigma =
        calibrations[k].relaxed * (kUnitNominalStrain * result.uniform_strain);
    ply_stress.push_back(to_ply_axes(sigma(0), sigma(1), sigma(2), plies[k].angle));
  }
  const std::vector<double> factors =
      edge_strength_factors(model, unit, grip_settings, result.ply_strengths, ply_stress,
                            result.hole_centre, s.hole_diameter > 0 ? 1.5 * s.hole_diameter : 0.0);
  if (result.weibull_modulus > 0) {
    Specimen scattered{std::move(model), calibrations, 0.0};
    assign_bond_strengths(scattered, result.ply_strengths, s.interface_strength,
                          result.weibull_modulus, s.seed, scattered_plies,
                          s.scatter_per_crack_site);
    model = std::move(scattered.model);
  }
  raise_strengths(model.bonds, factors);
  for (double f : factors) {
    if (f == 1.0) continue;
    ++result.edge_strengthened_bonds;
    result.edge_strength_factor = std::max(result.edge_strength_factor, f);
  }
}

// The stress-strain curve as the events solver reports its critical states, the snapshots on
// the way and the peak's state; all of it goes into checkpoints.
struct StrengthCurve {
  StrengthCurve(StrengthResult& run_result, const GaugeSection& section, bool snapshots,
                StrengthLoad load)
      : result(run_result),
        gauge(section),
        record_snapshots(snapshots),
        sign(load_sign(load)),
        shear(load == StrengthLoad::kShear) {}

  StrengthResult& result;
  const GaugeSection& gauge;
  GaugeStrain preload;  // the gauge's strain before the load (a cured coupon's), subtracted
  bool record_snapshots = false;
  double sign = 1;     // stresses and strains along the load: -1 in compression
  bool shear = false;  // tau_xy against gamma_xy
  double peak_stress = -std::numeric_limits<double>::infinity();
  std::shared_ptr<const Model> peak_state;
  long peak_event = 0;

  // In shear: the gauge particles' mean virial tau_xy (volume-weighted), the stress the gauge
  // carries. The frame's right grip takes its y reaction over an edge whose height a row of bonds
  // to the frame blurs (half a row at either side, on square), and the virial is exact in the
  // uniform state at every gauge site.
  // `free_offsets`: the bonds' free offsets of a plastic shear run (particle_stresses).
  double gauge_shear_stress(const Model& state,
                            std::span<const Eigen::Vector3d> free_offsets) const {
    const std::vector<Eigen::Matrix3d> stress =
        particle_stresses(state.particles, state.bonds, free_offsets);
    double weighted = 0, volume = 0;
    for (int i : gauge.particles) {
      const double v = state.particles.volume(i);
      weighted += v * stress[static_cast<std::size_t>(i)](0, 1);
      volume += v;
    }
    return weighted / volume;
  }

  // The unloaded origin.
  void start() {
    result.strain.push_back(0.0);
    result.stress.push_back(0.0);
    result.nominal_strain.push_back(0.0);
  }

  void on_event(const Model& state, const EventPoint& point,
                std::span<const Eigen::Vector3d> free_offsets = {}) {
    const GaugeStrain fit = fit_gauge_strain(state.particles, gauge.particles);
    result.strain.push_back(sign *
                            (shear ? fit.gamma_xy - preload.gamma_xy : fit.exx - preload.exx));
    result.stress.push_back(shear ? gauge_shear_stress(state, free_offsets)
                                  : sign * point.reaction / gauge.cross_section);
    result.nominal_strain.push_back(point.load_factor * kUnitNominalStrain);
    if (!record_snapshots) return;
    const long e = point.event;
    if (e == 1 || (e & (e - 1)) == 0) {
      result.snapshots.push_back({e, e == 1 ? "first failure" : fmt::format("event {}", e),
                                  std::make_shared<const Model>(state)});
    }
    if (result.stress.back() > peak_stress) {
      peak_stress = result.stress.back();
      peak_event = e;
      peak_state = !result.snapshots.empty() && result.snapshots.back().event == e
                       ? result.snapshots.back().model
                       : std::make_shared<const Model>(state);
    }
  }

  void write(CheckpointWriter& w) const {
    w.section("strength");
    w.doubles(result.strain);
    w.doubles(result.stress);
    w.doubles(result.nominal_strain);
    w.f64(peak_stress);
    w.i64(peak_event);
    w.boolean(peak_state != nullptr);
    if (peak_state) write_model(w, *peak_state);
    w.u64(result.snapshots.size());
    for (const StrengthSnapshot& snapshot : result.snapshots) {
      w.i64(snapshot.event);
      w.str(snapshot.label);
      write_model(w, *snapshot.model);
    }
  }

  void read(CheckpointReader& in) {
    in.section("strength");
    result.strain = in.doubles();
    result.stress = in.doubles();
    result.nominal_strain = in.doubles();
    peak_stress = in.f64();
    peak_event = in.i64();
    if (in.boolean()) {
      auto m = std::make_shared<Model>();
      read_model(in, *m);
      peak_state = std::move(m);
    }
    const std::uint64_t snapshots = in.u64();
    for (std::uint64_t k = 0; k < snapshots; ++k) {
      StrengthSnapshot snapshot;
      snapshot.event = in.i64();
      snapshot.label = in.str();
      auto m = std::make_shared<Model>();
      read_model(in, *m);
      snapshot.model = std::move(m);
      // The peak's snapshot is the peak state itself (as the run shares it).
      if (peak_state && snapshot.event == peak_event) snapshot.model = peak_state;
      result.snapshots.push_back(std::move(snapshot));
    }
  }

  // The peak (labelled, or added when it was not an event 2^k) and the final state, in event
  // order.
  void finish_snapshots(const std::shared_ptr<const Model>& final_state) {
    if (peak_state && peak_event > 1 && (peak_event & (peak_event - 1)) != 0) {
      result.snapshots.push_back({peak_event, "peak", peak_state});
    } else {
      for (StrengthSnapshot& snapshot : result.snapshots)
        if (snapshot.event == peak_event) snapshot.label += " (peak)";
    }
    result.snapshots.push_back({result.events + 1, "final", final_state});
    std::stable_sort(
        result.snapshots.begin(), result.snapshots.end(),
        [](const StrengthSnapshot& a, const StrengthSnapshot& b) { return a.event < b.event; });
  }
};

// What a checkpoint of this run must match: the settings and the model as it starts (strengths
// assigned) with its unit load.
CheckpointHeader strength_run_header(const StrengthSettings& s, const Model& model,
                                     const DofConstraints& unit) {
  CheckpointHeader header = strength_checkpoint_header(s);
  add_model_fingerprint(header, model);
  CheckpointWriter unit_bytes;
  for (Eigen::Index i = 0; i < unit.fixed.size(); ++i) unit_bytes.boolean(unit.fixed.data()[i]);
  unit_bytes.doubles({unit.value.data(), static_cast<std::size_t>(unit.value.size())});
  header.add("unit_load", fmt::format("{:016x}", fnv1a64(unit_bytes.bytes())));
  return header;
}

// A restart: the curve so far into `curve`, the model's state into `model`, and the events
// solver's state to continue from.
EventsState restore_strength_run(const std::filesystem::path& restart,
                                 const CheckpointHeader& header, Model& model,
                                 StrengthCurve& curve) {
  CheckpointFile f = read_checkpoint(restart);
  const std::string file = restart.string();
  check_same_run(f.header, header, file);
  CheckpointReader& in = f.payload;
  curve.read(in);
  Model saved;
  read_model(in, saved);
  static constexpr std::string_view kRunFields[] = {"displacement",
                                                    "rotation",
                                                    "force",
                                                    "torque",
                                                    "normal_stiffness",
                                                    "shear_stiffness",
                                                    "bending_stiffness",
                                                    "twisting_stiffness",
                                                    "damage",
                                                    "state"};
  check_same_model(model, saved, kRunFields, file);
  EventsState resume = read_events_state(in);
  in.finish();
  if (curve.result.strain.size() != resume.result.path.size() + 1)
    in.corrupt("the curve and the events differ in length");
  model.particles = std::move(saved.particles);
  model.bonds = std::move(saved.bonds);
  spdlog::info("restarting from {} after event {} ({} bonds broken)", file, resume.events,
               resume.broken);
  return resume;
}

// Failure at the material point (StrengthSettings::failure_criterion other than bond): refuses
// what it does not do yet, naming it.
// In-plane shear at the material point of a material with a shear_curve: the plastic shear run.
bool follows_shear_curve(const StrengthSettings& s) {
  return s.load == StrengthLoad::kShear &&
         s.effective_failure_criterion() != PlyFailureModel::kBond &&
         !s.coupon.material.shear_curve.empty();
}

void refuse_what_material_points_lack(const StrengthSettings& s) {
  const PlyFailureModel model = s.effective_failure_criterion();
  if (model == PlyFailureModel::kBond) return;
  const std::string name = failure_model_name(model);
  auto refuse_unless = [&](bool ok, const std::string& what) {
    require(ok, fmt::format("failure_criterion = \"{}\" (failure at the material point) {}; use "
                            "failure_criterion = \"bond\" for it",
                            name, what));
  };
  refuse_unless(!s.interface_strength.given(),
                "breaks no interface yet (leave the interface strengths out)");
  if (!follows_shear_curve(s)) return;
  const std::string curve = fmt::format(
      "material '{}' has a shear_curve, which in-plane shear (--load shear) follows "
      "by plastic shear strain at the material point up to its first crack "
      "(solvers/plastic_shear.hpp)",
      s.coupon.material.name);
  require(s.method == StrengthMethod::kEvents,
          curve +
              ", with the events method only: --method explicit does not follow it yet "
              "(leave shear_curve out of the material file for a linear explicit run)");
  require(!s.checkpoint.writes() && s.checkpoint.restart.empty(),
          curve +
              ": a run of load steps without checkpoints (--checkpoint-every, --restart do "
              "not apply)");
  require(!s.strength_options.softening,
          curve + ", where the crack opens brittle: --softening does not apply");
}

// Strength scatter at the material point: each site's strengths times a Weibull factor of
// modulus m and mean 1, (-ln U)^(1/m) / Gamma(1 + 1/m). Per site: U from draw k of
// std::mt19937_64(seed) for particle k (every particle draws, so that a site's factor depends on
// its index and the seed only), U = (draw / 2^11 + 1/2) / 2^53. Per crack band (`per_band`): the
// sites of one row along their ply's fibres share crack_band_factor of their band (their distance
// across the fibre from the ply's lowest particle, in half diameters, rounded: the bands of
// assign_bond_strengths' per-crack-site scatter), so that a transverse crack runs through its row
// as a cross-ply's 90 deg cracks do. Sites of plies outside `scattered_plies` (when given) keep 1.
std::vector<double> site_strength_factors(const Particles& p, const std::vector<Ply>& plies,
                                          double weibull_modulus, std::uint64_t seed,
                                          const std::vector<bool>& scattered_plies, bool per_band) {
  const std::size_t n = static_cast<std::size_t>(p.size());
  std::vector<double> factors(n, 1.0);
  auto across = [&](int i) {
    const double a = plies[static_cast<std::size_t>(p.ply(i))].angle;
    return -std::sin(a) * p.reference_position(i, 0) + std::cos(a) * p.reference_position(i, 1);
  };
  std::vector<double> origin(plies.size(), std::numeric_limits<double>::infinity());
  for (int i = 0; i < p.size(); ++i) {
    const auto k = static_cast<std::size_t>(p.ply(i));
    require(k < plies.size(), fmt::format("particle {} is in ply {} of {}", i, k, plies.size()));
    origin[k] = std::min(origin[k], across(i));
  }
  std::mt19937_64 random(seed);
  const double mean = std::tgamma(1.0 + 1.0 / weibull_modulus);
  for (int i = 0; i < p.size(); ++i) {
    const double u = (static_cast<double>(random() >> 11) + 0.5) * 0x1.0p-53;
    const auto k = static_cast<std::size_t>(p.ply(i));
    if (!scattered_plies.empty() && !(k < scattered_plies.size() && scattered_plies[k])) continue;
    const long band = std::lround(2.0 * (across(i) - origin[k]) / (2.0 * p.radius(i)));
    factors[static_cast<std::size_t>(i)] =
        per_band ? crack_band_factor(weibull_modulus, seed, static_cast<int>(k), band)
                 : std::pow(-std::log(u), 1.0 / weibull_modulus) / mean;
  }
  return factors;
}

// The criterion, the material and each ply's angle for the events solver; nullopt for failure
// bond by bond.
std::optional<MaterialPointFailure> material_point_failure(const StrengthSettings& s,
                                                           const std::vector<Ply>& plies) {
  const PlyFailureModel model = s.effective_failure_criterion();
  if (model == PlyFailureModel::kBond) return std::nullopt;
  MaterialPointFailure f;
  switch (model) {
    case PlyFailureModel::kHashin:
      f.criterion = FailureCriterion::kHashin;
      break;
    case PlyFailureModel::kPuck:
      f.criterion = FailureCriterion::kPuck;
      break;
    case PlyFailureModel::kMaxStress:
      f.criterion = FailureCriterion::kMaxStress;
      break;
    case PlyFailureModel::kTsaiWu:
      f.criterion = FailureCriterion::kTsaiWu;
      break;
    case PlyFailureModel::kBond:
      break;
  }
  f.material = s.coupon.material;
  f.softening = s.strength_options.softening;
  f.coupled = s.coupled_criterion;
  for (const Ply& ply : plies) f.ply_angles.push_back(ply.angle);
  return f;
}

// Softening cracks at the material point dissipate G per unit area where each crack runs along a
// row of the square lattice (the lattice along the fibre: matrix cracks along its rows, fibre
// cracks across them); a crack along a diagonal is bridged by bonds that no site on it owns and
// widens into a band (tests/test_strength_command.cpp measures both). Refuses the rest by name.
void require_cracks_along_lattice(const StrengthSettings& s, const std::vector<Ply>& plies,
                                  const std::vector<Calibration>& calibrations) {
  const std::string what = fmt::format(
      "softening cracks at the material point (--softening with failure_criterion = \"{}\")",
      failure_model_name(s.effective_failure_criterion()));
  require(s.strategy == "square",
          fmt::format("{} are made for the square lattice along the fibres, where every crack runs "
                      "along a row of sites; strategy '{}' has none such (use --strategy square)",
                      what, s.strategy));
  for (std::size_t k = 0; k < plies.size() && k < calibrations.size(); ++k) {
    const double off = std::remainder(plies[k].angle - calibrations[k].lattice_angle, 90 * kDegree);
    require(std::abs(off) < 1e-9,
            fmt::format("{} need the square lattice along the fibres: ply {} at {:g} deg has its "
                        "lattice at {:g} deg, where softening cracks along the lattice's diagonals "
                        "do not localize (a 90 deg E-glass coupon's sites softened across the "
                        "whole gauge and dissipated 2.2 G w t; use --strategy-option "
                        "fibre_offset=0)",
                        what, k + 1, plies[k].angle / kDegree,
                        calibrations[k].lattice_angle / kDegree));
  }
}

// With failure at the material point the in-ply bonds open only with their sites: no strength of
// their own.
void open_only_with_sites(Model& model) {
  Bonds& bonds = model.bonds;
  const double inf = std::numeric_limits<double>::infinity();
  for (int b = 0; b < bonds.size(); ++b) {
    if (bonds.is_interface(b)) continue;
    bonds.tensile_strength(b) = inf;
    bonds.cohesion(b) = inf;
  }
}

// The events solver from the unit load to failure, each critical state into `curve`, with the
// checkpoints and restart of s.checkpoint.
EventsResult run_to_failure(const StrengthSettings& s,
                            const std::function<void(const EventProgress&)>& progress,
                            const StaticSettings& grip_settings, const UnitLoading& loading,
                            Model& model, StrengthCurve& curve,
                            std::optional<MaterialPointFailure> material_point, DofArray preload) {
  EventSettings events = s.events;
  events.material_point = std::move(material_point);
  events.preload = std::move(preload);
  events.static_settings.pin_rigid_modes = grip_settings.pin_rigid_modes;
  events.static_settings.linear_solver = grip_settings.linear_solver;
  events.on_progress = progress;
  curve.start();
  events.on_event = [&](const Model& state, const EventPoint& point) {
    curve.on_event(state, point);
  };

  const CheckpointOptions& ck = s.checkpoint;
  CheckpointHeader header;
  if (ck.writes() || !ck.restart.empty()) header = strength_run_header(s, model, loading.unit);
  std::optional<EventsState> resume;
  if (!ck.restart.empty()) resume = restore_strength_run(ck.restart, header, model, curve);
  if (ck.writes()) {
    events.checkpoint_every = ck.every;
    events.on_checkpoint = [&](const Model& state, const EventsState& run_state) {
      CheckpointWriter w;
      curve.write(w);
      write_model(w, state);
      write_events_state(w, run_state);
      write_checkpoint(ck.file, header, w);
    };
  }
  return run_events(model, loading.unit, loading.reaction_dofs, events,
                    resume ? &*resume : nullptr);
}

// The explicit method's estimate of the coupon's first failure, which sets its loading rate: the
// load factor at which the bulk's stress along the load (sigma_x, in shear tau_xy; the plies'
// relaxed stiffness, summed as CLT sums it, at the unit load's nominal strain) reaches the smallest
// of the classical criteria's strengths.
double failure_load_factor(const std::vector<Calibration>& calibrations,
                           const StrengthResult& result) {
  Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
  for (const Calibration& c : calibrations)
    A += c.relaxed / static_cast<double>(calibrations.size());
  const int along = result.load == StrengthLoad::kShear ? 2 : 0;  // sigma_x, or tau_xy
  const double modulus = 1.0 / A.inverse()(along, along);
  double strength = std::numeric_limits<double>::infinity();
  for (const CriterionStrength& c : result.theory)
    if (c.strength) strength = std::min(strength, std::abs(*c.strength));
  require(std::isfinite(strength) && modulus > 0,
          "the explicit method sets its loading rate by the classical criteria's strength of the "
          "coupon, and none of them has one (the material lacks the strengths they need)");
  return strength / (modulus * kUnitNominalStrain);
}

// The explicit method (solvers/explicit_failure.hpp) from rest to failure, each point into
// `curve`.
EventsResult run_explicit(const StrengthSettings& s,
                          const std::function<void(const EventProgress&)>& progress,
                          const UnitLoading& loading, double failure_load_factor, Model& model,
                          StrengthCurve& curve,
                          std::optional<MaterialPointFailure> material_point) {
  ExplicitFailureSettings f;
  f.integrator = s.explicit_settings;
  // At the material point an open crack carries nothing, as in the events method: no contacts
  // between its faces (in one layer of particles an inclined compression crack cannot slide, and
  // its faces would carry the load on for ever: 23 x YC at 90 deg).
  if (material_point) f.integrator.contacts = false;
  f.failure_load_factor = failure_load_factor;
  f.cycles_to_failure = s.explicit_loading.cycles_to_failure;
  f.check_cycles = s.explicit_loading.check_cycles;
  f.max_cycles = s.explicit_loading.max_cycles;
  f.stop_fraction = s.events.stop_fraction;
  f.material_point = std::move(material_point);
  f.on_progress = progress;
  f.progress_seconds = s.events.progress_seconds;
  curve.start();
  f.on_point = [&](const Model& state, const EventPoint& point) { curve.on_event(state, point); };
  return run_explicit_failure(model, loading.unit, loading.reaction_dofs, f);
}

// In-plane shear that follows the material's shear_curve (solvers/plastic_shear.hpp), each point
// into `curve`.
EventsResult run_plastic(const StrengthSettings& s,
                         const std::function<void(const EventProgress&)>& progress,
                         const StaticSettings& grip_settings, const UnitLoading& loading,
                         Model& model, StrengthCurve& curve, MaterialPointFailure material_point,
                         StrengthResult& result) {
  PlasticShearSettings p;
  p.material_point = std::move(material_point);
  p.static_settings.pin_rigid_modes = grip_settings.pin_rigid_modes;
  p.static_settings.linear_solver = grip_settings.linear_solver;
  p.on_progress = progress;
  p.progress_seconds = s.events.progress_seconds;
  curve.start();
  p.on_point = [&](const Model& state, const EventPoint& point,
                   std::span<const Eigen::Vector3d> offsets) {
    curve.on_event(state, point, offsets);
  };
  PlasticShearResult run = run_plastic_shear(model, loading.unit, loading.reaction_dofs, p);
  result.plastic_shear = true;
  result.plastic_work = run.plastic_work;
  return std::move(run.events);
}

// The material's shear_curve beside the simulated curve (a ply at 0 or 90 deg: gamma_xy is
// gamma12 there, up to its sign).
void compare_shear_curve(StrengthResult& result) {
  const RambergOsgoodShear law(result.material);
  result.shear_law_eta = law.eta();
  const double turned = std::remainder(result.ply_angle, std::numbers::pi / 2);
  if (!result.layup.empty() || std::abs(turned) > 1e-9) return;
  const std::size_t last = static_cast<std::size_t>(result.peak) + 1;  // the curve's peak
  for (const ShearCurvePoint& q : result.material.shear_curve) {
    ShearCurveCheck c;
    c.strain = q.strain;
    c.measured = q.stress;
    c.law = law.stress_at(q.strain);
    for (std::size_t k = 1; k <= last && k < result.strain.size(); ++k) {
      const double g0 = std::abs(result.strain[k - 1]), g1 = std::abs(result.strain[k]);
      if (g1 < q.strain || g1 == g0) continue;
      const double t = (q.strain - g0) / (g1 - g0);
      c.simulated = (1 - t) * std::abs(result.stress[k - 1]) + t * std::abs(result.stress[k]);
      break;
    }
    result.shear_curve.push_back(c);
  }
}

// The run's figures: the path, the peak and the first failure.
void take_events_result(const EventsResult& run, StrengthResult& result) {
  require(!run.path.empty(),
          fmt::format("no bond of the coupon broke under the grips' pull ({}): nothing to "
                      "measure",
                      run.stop));
  require(result.strain.size() == run.path.size() + 1,
          "the events solver did not report every critical state");
  result.path = run.path;
  result.breaks = run.breaks;
  result.peak = run.peak >= 0 ? run.peak : 0;
  // In shear the stress is the gauge's own (StrengthCurve), not the reaction the run's peak
  // follows.
  if (result.load == StrengthLoad::kShear) {
    const auto top = std::max_element(result.stress.begin() + 1, result.stress.end());
    result.peak = static_cast<int>(top - result.stress.begin()) - 1;
  }
  result.events = static_cast<long>(run.path.size());
  result.stop = run.stop;
  result.factorizations = run.factorizations;
  result.solves = run.solves;
  result.dissipated_energy = run.dissipated_energy;
  const EventPoint& at_peak = run.path[static_cast<std::size_t>(result.peak)];
  if (at_peak.site >= 0) {
    result.peak_mode = failure_mode_name(at_peak.site_mode);
    result.peak_fracture_angle = at_peak.site_fracture_angle;
  }
  for (const EventPoint& point : run.path)
    result.cracked_sites += point.site >= 0 && point.site_tooth == 0 ? 1 : 0;
  result.crack_energy = run.crack_energy;
  result.crack_area = run.crack_area;
  result.crack_fracture_energy = run.crack_fracture_energy;
  result.brittle_sites = run.brittle_sites;
  result.softening_sites = run.softening_sites;
  result.final_stiffness_ratio = run.final_stiffness_ratio;
  const std::size_t peak = static_cast<std::size_t>(result.peak) + 1;
  result.strength = result.stress[peak];
  result.strain_at_peak = result.strain[peak];
  // The first failure: the first point that is not a load step (a plastic shear run's).
  std::size_t first = 0;
  while (first + 1 < run.path.size() && run.path[first].load_step) ++first;
  result.first_failure_stress = result.stress[first + 1];
  result.first_failure_strain = result.strain[first + 1];
}

// Broken bonds by family and mode; every family of the coupon is listed.
void count_broken_bonds(const Model& model, StrengthResult& result) {
  const Particles& p = model.particles;
  const Bonds& bonds = model.bonds;
  std::map<std::pair<bool, std::string>, BrokenBonds> counts;
  for (int b = 0; b < bonds.size(); ++b) {
    const bool interface = bonds.is_interface(b);
    const std::string label =
        interface ? fmt::format("interface {}/{}", bonds.family(b), bonds.family(b) + 1)
        : result.ply_strengths.empty()  // failure at the material point
            ? fmt::format("{}", bonds.family(b) + 1)
            : family_label(result.ply_strengths[static_cast<std::size_t>(p.ply(bonds.first(b)))],
                           bonds.family(b));
    BrokenBonds& c = counts[{interface, label}];
    c.family = label;
    c.interface = interface;
    if (bonds.state(b) == static_cast<int>(BondState::kBrokenTension)) {
      ++c.tension;
      ++result.broken_tension;
    } else if (bonds.state(b) == static_cast<int>(BondState::kBrokenShear)) {
      ++c.shear;
      ++result.broken_shear;
    } else if (bonds.damage(b) > 0) {
      ++result.damaged;
    }
  }
  for (auto& [key, c] : counts) result.broken.push_back(c);
}

}  // namespace

StrengthResult StrengthTest::run(SpecimenBuilder& builder) const {
  const auto start = Clock::now();
  const StrengthSettings& s = settings_;
  const Material& material = s.coupon.material;
  // Fail before any work on what the run cannot do.
  refuse_what_material_points_lack(s);
  s.require_strengths_for("plydem strength");

  require(s.strength_options.softening ||
              !(s.interface_strength.GIc > 0 || s.interface_strength.GIIc > 0),
          "the interface fracture energies GIc, GIIc are used by softening bonds only "
          "(--softening); brittle interfaces would ignore them");
  check_resources(estimate(builder.strategy()), s.force, "--force");

  StrengthResult result;
  result.strategy = s.strategy;
  result.material = material;
  result.ply_angle = s.coupon.ply_angle;
  result.method = s.method;
  result.load = s.load;
  result.weibull_modulus = s.effective_weibull_modulus();
  result.seed = s.seed;

  const std::vector<Ply> plies = coupon_plies(s, result);
  std::optional<MaterialPointFailure> material_point = material_point_failure(s, plies);
  result.failure_criterion = s.effective_failure_criterion();
  // The bonds' strengths are calibrated for failure bond by bond only.
  if (!material_point) result.ply_strengths = calibrate_ply_strengths(builder, s, plies);

  // The coupon, and the strength of every bond.
  Specimen specimen = build_strength_coupon(builder, s, result);
  result.build_seconds = specimen.build_seconds;
  result.calibration = specimen.ply_calibrations.front();
  require(plies.size() == specimen.ply_calibrations.size(),
          fmt::format("the coupon was built with {} ply calibrations for {} plies",
                      specimen.ply_calibrations.size(), plies.size()));
  // Without scatter first: the edge consistency below compares the strengths as calibrated.
  const bool consistent_edges =
      s.consistent_edges && s.grips == StrengthGrips::kUniform && !material_point;
  std::vector<bool> scattered_plies(s.scatter_plies.empty() ? 0 : plies.size(), false);
  for (int k : s.scatter_plies) scattered_plies[static_cast<std::size_t>(k)] = true;
  if (material_point) {
    if (material_point->softening)
      require_cracks_along_lattice(s, plies, specimen.ply_calibrations);
    open_only_with_sites(specimen.model);
    if (result.weibull_modulus > 0)
      material_point->strength_factors =
          site_strength_factors(specimen.model.particles, plies, result.weibull_modulus, s.seed,
                                scattered_plies, s.scatter_per_crack_site);
  } else {
    assign_bond_strengths(specimen, result.ply_strengths, s.interface_strength,
                          consistent_edges ? 0.0 : result.weibull_modulus, s.seed, scattered_plies,
                          s.scatter_per_crack_site);
  }

  // Theory, and the calibrated bulk's own first failure under the same load.
  result.theory = classical_strengths(plies, material.strength, s.load);
  result.model_first_failure = material_point ? std::numeric_limits<double>::quiet_NaN()
                                              : bulk_first_failure(plies, result.ply_strengths);

  const std::vector<Calibration> specimen_calibrations = specimen.ply_calibrations;
  auto model = std::make_shared<Model>(std::move(specimen.model));
  const UnitLoading loading =
      grip_coupon(builder.strategy(), s, specimen_calibrations, *model, result);
  const StaticSettings grip_settings = grip_solve_settings(s.linear_solver, s.force);
  if (consistent_edges) {
    make_edges_consistent(s, plies, specimen_calibrations, scattered_plies, loading.unit,
                          grip_settings, *model, result);
  }

  StrengthCurve curve(result, loading.gauge, s.record_snapshots, s.load);
  // The cure: the grips hold the cured coupon where its free cure left it, and the strains are
  // measured from there.
  DofArray preload;
  if (s.delta_T != 0) {
    require(!follows_shear_curve(s),
            "thermal.delta_T (cure stresses) is not taken by the plastic shear run (a material "
            "with a shear_curve in shear at the material point): leave it out");
    preload = cured_preload(*model, plies, s.delta_T, loading.unit.fixed);
    curve.preload = fit_gauge_strain(model->particles, loading.gauge.particles);
  }
  result.delta_T = s.delta_T;
  const bool at_material_points = material_point.has_value();
  const EventsResult run =
      follows_shear_curve(s) ? run_plastic(s, progress_, grip_settings, loading, *model, curve,
                                           std::move(*material_point), result)
      : s.method == StrengthMethod::kExplicit
          ? run_explicit(s, progress_, loading, failure_load_factor(specimen_calibrations, result),
                         *model, curve, std::move(material_point))
          : run_to_failure(s, progress_, grip_settings, loading, *model, curve,
                           std::move(material_point), std::move(preload));
  require(!at_material_points || run.stop != "no bond loaded",
          fmt::format("failure at the material point left the coupon carrying load with no site "
                      "that can crack, after {} events: its peak would not be a strength (use "
                      "failure_criterion = \"bond\", or another strategy or particle size)",
                      run.path.size()));
  take_events_result(run, result);
  if (result.plastic_shear) compare_shear_curve(result);
  count_broken_bonds(*model, result);
  if (s.record_snapshots) curve.finish_snapshots(model);
  result.model = std::move(model);
  result.wall_seconds = seconds_since(start);
  return result;
}

}  // namespace plydem
