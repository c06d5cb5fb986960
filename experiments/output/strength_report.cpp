#include "experiments/output/strength_report.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "contacts/site_failure.hpp"
#include "core/units.hpp"
#include "experiments/output/vtk_output.hpp"

namespace plydem {
namespace fs = std::filesystem;

namespace {

std::string specimen_text(const StrengthResult& r) {
  if (r.layup.empty()) return fmt::format("ply angle {:g} deg", r.ply_angle / kDegree);
  return fmt::format("laminate {}", format_layup(r.layup));
}

std::string scatter_text(const StrengthResult& r) {
  if (!(r.weibull_modulus > 0)) return "no strength scatter";
  return fmt::format("Weibull strength scatter m = {:g}, seed {}", r.weibull_modulus, r.seed);
}

std::string mpa(double pascals) {
  if (!std::isfinite(pascals)) return "never";
  return fmt::format("{:.2f} MPa", pascals * kMPaPerPa);
}

nlohmann::json finite_or_null(double value) {
  return std::isfinite(value) ? nlohmann::json(value) : nlohmann::json(nullptr);
}

// At the material point: what the cracks dissipated against G times their area, and the sites that
// could not soften.
std::string crack_energy_lines(const StrengthResult& r) {
  std::string out = fmt::format("{:<34} {:>11.4g} m^2\n", "crack area (open sites)", r.crack_area);
  out += fmt::format("{:<34} {:>11.4g} J", "energy dissipated by the cracks", r.crack_energy);
  if (r.softening_sites > 0) {
    out += fmt::format(
        "  ({} sites still softening at the stop, their energy so far included, their area not: "
        "--stop-fraction 0 runs until every crack is open)",
        r.softening_sites);
  } else if (r.crack_fracture_energy > 0) {
    out += fmt::format("  ({:.4f} x G x crack area, {:.4g} J)",
                       r.crack_energy / r.crack_fracture_energy, r.crack_fracture_energy);
  }
  out += "\n";
  if (r.brittle_sites > 0) {
    const Material& m = r.material;
    const LaminaStrength& s = m.strength;
    out += fmt::format(
        "{:<34} {:>14}  (too large to soften without snap-back: a site longer than 2 E G / "
        "sigma^2 across its crack; E2 G_matrix / YT^2 = {:.3g} mm, E1 G_fibre / XT^2 = {:.3g} mm: "
        "use smaller particles)\n",
        "sites that opened brittle", r.brittle_sites,
        m.E2 * s.G_matrix / (s.YT * s.YT) * kMmPerMetre,
        m.E1 * s.G_fibre / (s.XT * s.XT) * kMmPerMetre);
  }
  return out;
}

// In-plane shear that followed the material's shear_curve: its points beside the simulated curve.
std::string shear_curve_lines(const StrengthResult& r) {
  std::string out = fmt::format(
      "\nshear curve followed by plastic shear strain at the material point (Ramberg-Osgood fit, "
      "eta {:.3g}; plastic work {:.4g} J)\n",
      r.shear_law_eta, r.plastic_work);
  if (r.shear_curve.empty()) return out + "(compared with the curve at 0 and 90 deg only)\n";
  out += fmt::format("{:>10} {:>14} {:>14} {:>14} {:>12}\n", "gamma12 %", "measured MPa", "law MPa",
                     "simulated MPa", "sim/measured");
  for (const ShearCurveCheck& c : r.shear_curve) {
    out += fmt::format("{:>10.2f} {:>14.2f} {:>14.2f} ", c.strain * 100, c.measured * kMPaPerPa,
                       c.law * kMPaPerPa);
    out += std::isfinite(c.simulated)
               ? fmt::format("{:>14.2f} {:>12.4f}\n", c.simulated * kMPaPerPa,
                             c.simulated / c.measured)
               : fmt::format("{:>14} {:>12}\n", "(cracked)", "-");
  }
  return out;
}

}  // namespace

const char* criterion_label(FailureCriterion criterion) {
  switch (criterion) {
    case FailureCriterion::kMaxStress:
      return "max-stress";
    case FailureCriterion::kTsaiHill:
      return "Tsai-Hill";
    case FailureCriterion::kTsaiWu:
      return "Tsai-Wu";
    case FailureCriterion::kHashin:
      return "Hashin";
    case FailureCriterion::kPuck:
      return "Puck";
  }
  return "?";
}

double criteria_compared_stress(const StrengthResult& r) {
  return r.layup.empty() ? r.strength : r.first_failure_stress;
}

const char* criteria_compared_name(const StrengthResult& r) {
  return r.layup.empty() ? "strength" : "first failure";
}

std::string format_strength_table(const StrengthResult& r, const StrengthSettings& s) {
  std::string out =
      fmt::format("plydem strength test: strategy {}, material {}, {}, {}, method {}, grips {}\n",
                  r.strategy, r.material.name, specimen_text(r), strength_load_name(r.load),
                  strength_method_name(r.method), strength_grips_name(s.grips));
  out += fmt::format(
      "coupon {:g} mm x {:g} mm x {:g} mm{}, particle diameter {:g} mm; {} particles, {} bonds; "
      "{}; {}\n\n",
      s.coupon.length * kMmPerMetre, s.coupon.width * kMmPerMetre, s.coupon.thickness * kMmPerMetre,
      r.layup.empty() ? "" : " per ply", s.coupon.particle_diameter * kMmPerMetre, r.particles,
      r.bonds, s.strength_options.softening ? "linear-softening bonds" : "brittle bonds",
      scatter_text(r));
  if (r.delta_T != 0)
    out += fmt::format(
        "cured: {} by {:g} K from stress-free (thermal.delta_T), the grips holding the coupon "
        "where its free cure left it; strains from the cured state\n",
        r.delta_T < 0 ? "cooled" : "heated", std::abs(r.delta_T));
  if (r.load == StrengthLoad::kCompression)
    out += "stresses and strains along the load: positive in compression\n";
  if (r.load == StrengthLoad::kShear)
    out += "in-plane shear in a frame: stresses tau_xy, strains gamma_xy\n";
  static const char* const kStrength[] = {"strength (peak stress)",
                                          "compressive strength (peak stress)",
                                          "shear strength (peak stress)"};
  out += fmt::format("{:<34} {:>14}\n", kStrength[static_cast<int>(r.load)], mpa(r.strength));
  out += fmt::format("{:<34} {:>13.4f}%\n", "strain at peak", r.strain_at_peak * 100);
  out += fmt::format("{:<34} {:>14}\n", "first-failure stress", mpa(r.first_failure_stress));
  if (!std::isnan(r.model_first_failure)) {  // NaN: failure at the material point
    out += fmt::format("{:<34} {:>14}  (calibrated bulk: no edges, no scatter)\n",
                       "model's own first failure", mpa(r.model_first_failure));
  }
  if (!r.peak_mode.empty()) {
    out += fmt::format("{:<34} {:>14}  (criterion {}, {} cracked sites)\n", "mode at the peak",
                       r.peak_mode, failure_model_name(r.failure_criterion), r.cracked_sites);
    out += fmt::format("{:<34} {:>9.1f} deg  (from the ply's thickness direction)\n",
                       "fracture plane at the peak", r.peak_fracture_angle / kDegree);
    out += crack_energy_lines(r);
  }
  if (r.plastic_shear) out += shear_curve_lines(r);
  if (r.edge_strengthened_bonds > 0) {
    out += fmt::format(
        "{:<34} {:>14}  (edge and grip bonds raised to fail with the bulk, by up to {:.3f}x)\n",
        "bonds with bulk-consistent strength", r.edge_strengthened_bonds, r.edge_strength_factor);
  }
  const LaminaStrength& ls = r.material.strength;
  auto given = [](double v) {
    return v > 0 ? fmt::format("{:g}", v * kMPaPerPa) : std::string("-");
  };
  out += fmt::format("\nlamina strengths [MPa]: XT {}, XC {}, YT {}, YC {}, S12 {}\n\n",
                     given(ls.XT), given(ls.XC), given(ls.YT), given(ls.YC), given(ls.S12));
  out += fmt::format("{:<15} {:>14}   DEM {} rel. to it\n",
                     r.layup.empty() ? "criterion" : "criterion (FPF)", "strength",
                     criteria_compared_name(r));
  for (const CriterionStrength& t : r.theory) {
    if (t.strength) {
      out +=
          fmt::format("{:<15} {:>14} {:>+12.2f}%\n", criterion_label(t.criterion), mpa(*t.strength),
                      100.0 * (criteria_compared_stress(r) / *t.strength - 1.0));
    } else {
      out += fmt::format("{:<15} {:>14}  ({})\n", criterion_label(t.criterion), "-", t.missing);
    }
  }
  out += fmt::format("\n{:<28} {:>8} {:>8}\n", "broken bonds (family)", "tension", "shear");
  for (const BrokenBonds& b : r.broken) {
    out += fmt::format("{:<28} {:>8} {:>8}\n", b.family, b.tension, b.shear);
  }
  out += fmt::format("{:<28} {:>8} {:>8}\n", "all", r.broken_tension, r.broken_shear);
  if (r.damaged > 0) out += fmt::format("softened, not broken: {}\n", r.damaged);
  if (r.method == StrengthMethod::kExplicit) {
    out += fmt::format(
        "\n{} points of the curve (explicit: checks at which a site cracked, and samples after "
        "the first; stopped: {}), energy released {:.4g} J\n",
        r.events, r.stop, r.dissipated_energy);
  } else {
    out += fmt::format(
        "\n{} events (stopped: {}), {} factorizations, {} solves, energy released {:.4g} J\n",
        r.events, r.stop, r.factorizations, r.solves, r.dissipated_energy);
    if (std::isfinite(r.final_stiffness_ratio))
      out += fmt::format("stiffness after the last event: {:.4g} of the intact coupon's\n",
                         r.final_stiffness_ratio);
  }
  out += fmt::format("building {:.2f} s, wall time {:.2f} s\n", r.build_seconds, r.wall_seconds);
  return out;
}

// The failure model's figures: the criterion, the peak's mode and plane, the cracks' energy
// against G times their area, and in shear the followed shear curve.
void add_failure_model_json(const StrengthResult& r, nlohmann::json& j) {
  j["failure_criterion"] = failure_model_name(r.failure_criterion);
  if (r.peak_mode.empty()) {
    j["peak_mode"] = nullptr;
  } else {
    j["peak_mode"] = r.peak_mode;
  }
  j["peak_fracture_angle_deg"] = finite_or_null(r.peak_fracture_angle / kDegree);
  j["cracked_sites"] = r.cracked_sites;
  j["crack_area"] = r.crack_area;
  j["crack_dissipated_energy"] = r.crack_energy;
  j["crack_fracture_energy"] = r.crack_fracture_energy;
  j["brittle_sites"] = r.brittle_sites;
  j["softening_sites"] = r.softening_sites;
  if (r.plastic_shear) {
    nlohmann::json curve = nlohmann::json::array();
    for (const ShearCurveCheck& c : r.shear_curve)
      curve.push_back({{"gamma12", c.strain},
                       {"measured_tau12", c.measured},
                       {"law_tau12", c.law},
                       {"simulated_tau12", finite_or_null(c.simulated)}});
    j["shear_curve"] = curve;
    j["shear_law_eta"] = r.shear_law_eta;
    j["plastic_work"] = r.plastic_work;
  }
}

nlohmann::json strength_json(const StrengthResult& r, const StrengthSettings& s) {
  nlohmann::json j;
  j["strength"] = r.strength;
  j["strain_at_peak"] = r.strain_at_peak;
  j["first_failure_stress"] = r.first_failure_stress;
  j["first_failure_strain"] = r.first_failure_strain;
  nlohmann::json curve = nlohmann::json::array();
  for (std::size_t i = 0; i < r.strain.size(); ++i) curve.push_back({r.strain[i], r.stress[i]});
  j["curve"] = curve;
  nlohmann::json nominal = nlohmann::json::array();
  for (std::size_t i = 0; i < r.nominal_strain.size(); ++i)
    nominal.push_back({r.nominal_strain[i], r.stress[i]});
  j["curve_nominal"] = nominal;
  nlohmann::json families = nlohmann::json::object();
  for (const BrokenBonds& b : r.broken) {
    families[b.family] = {{"tension", b.tension}, {"shear", b.shear}, {"interface", b.interface}};
  }
  j["broken_bonds"] = {{"tension", r.broken_tension},
                       {"shear", r.broken_shear},
                       {"total", r.broken_tension + r.broken_shear},
                       {"softened", r.damaged},
                       {"by_family", families}};
  nlohmann::json theory = nlohmann::json::object();
  nlohmann::json missing = nlohmann::json::object();
  for (const CriterionStrength& t : r.theory) {
    theory[criterion_name(t.criterion)] = t.strength ? nlohmann::json(*t.strength) : nullptr;
    if (!t.strength) missing[criterion_name(t.criterion)] = t.missing;
  }
  j["theory"] = theory;
  if (!missing.empty()) j["theory_missing"] = missing;
  j["theory_kind"] = r.layup.empty() ? "off-axis strength of the ply"
                                     : "first-ply failure, classical lamination theory";
  j["events"] = r.events;
  j["wall_seconds"] = r.wall_seconds;

  j["model_first_failure"] = finite_or_null(r.model_first_failure);
  j["edge_strengthened_bonds"] = r.edge_strengthened_bonds;
  j["edge_strength_factor"] = r.edge_strength_factor;
  const LaminaStrength& ls = r.material.strength;
  j["lamina_strengths"] = {
      {"XT", ls.XT}, {"XC", ls.XC}, {"YT", ls.YT}, {"YC", ls.YC}, {"S12", ls.S12}};
  j["strategy"] = r.strategy;
  j["material"] = r.material.name;
  j["angle_deg"] = r.ply_angle / kDegree;
  if (!r.layup.empty()) {
    j["layup"] = format_layup(r.layup);
    const InterfaceStrength& is = s.interface_strength;
    j["interface_strength"] = {{"normal", is.normal},
                               {"shear", is.shear},
                               {"GIc", is.GIc},
                               {"GIIc", is.GIIc},
                               {"bk_exponent", is.bk_exponent}};
  }
  j["method"] = strength_method_name(r.method);
  j["load"] = strength_load_name(r.load);
  j["grips"] = strength_grips_name(s.grips);
  if (s.grips == StrengthGrips::kUniform) {
    j["uniform_grips"] = {
        {"strain_per_unit_exx", {r.uniform_strain(0), r.uniform_strain(1), r.uniform_strain(2)}},
        {"spin_per_unit_exx", r.uniform_spin}};
  }
  j["softening"] = s.strength_options.softening;
  j["friction_coefficient"] = s.strength_options.friction_coefficient;
  j["weibull_modulus"] = r.weibull_modulus;
  if (r.weibull_modulus > 0) j["seed"] = r.seed;
  j["delta_T"] = r.delta_T;  // [K], the cure the test started from (0: none)
  j["stop"] = r.stop;
  j["final_stiffness_ratio"] = finite_or_null(r.final_stiffness_ratio);
  add_failure_model_json(r, j);
  j["factorizations"] = r.factorizations;
  j["solves"] = r.solves;
  j["dissipated_energy"] = r.dissipated_energy;
  j["particles"] = r.particles;
  j["bonds"] = r.bonds;
  j["cross_section"] = r.cross_section;
  j["build_seconds"] = r.build_seconds;
  nlohmann::json plies = nlohmann::json::array();
  for (const StrengthCalibration& c : r.ply_strengths) {
    nlohmann::json fams = nlohmann::json::array();
    for (const FamilyStrength& f : c.families) {
      fams.push_back({{"family", f.label},
                      {"tensile_strength", finite_or_null(f.tensile)},
                      {"cohesion", finite_or_null(f.cohesion)},
                      {"friction_coefficient", f.friction},
                      {"radius", f.radius},
                      {"ductility", f.ductility},
                      {"tensile_set_by", f.tensile_set_by},
                      {"cohesion_set_by", f.cohesion_set_by}});
    }
    nlohmann::json targets = nlohmann::json::array();
    for (const StrengthTarget& t : c.targets) {
      targets.push_back({{"name", t.name},
                         {"target", t.target},
                         {"model", finite_or_null(t.model)},
                         {"calibrated", t.calibrated},
                         {"family", t.family},
                         {"mode", t.mode}});
    }
    plies.push_back(
        {{"ply_angle_deg", c.ply_angle / kDegree}, {"families", fams}, {"targets", targets}});
  }
  j["strength_calibration"] = plies;
  j["units"] = "SI (Pa, m, s, J)";
  return j;
}

Figure plot_strength_curve(const StrengthResult& r, const fs::path& out_dir,
                           const std::string& stem, const std::string& title) {
  std::vector<Curve> curves;
  Curve dem{"DEM", {}, {}, true};
  double max_strain = 0;
  for (std::size_t i = 0; i < r.strain.size(); ++i) {
    dem.x.push_back(r.strain[i] * 100);
    dem.y.push_back(r.stress[i] * kMPaPerPa);
    max_strain = std::max(max_strain, r.strain[i] * 100);
  }
  curves.push_back(dem);
  curves.push_back({fmt::format("DEM peak {:.1f} MPa", r.strength * kMPaPerPa),
                    {r.strain_at_peak * 100},
                    {r.strength * kMPaPerPa},
                    true});
  const double right = max_strain > 0 ? 1.05 * max_strain : 1.0;
  for (const CriterionStrength& t : r.theory) {
    if (!t.strength) continue;
    curves.push_back(
        {fmt::format("{} {:.1f} MPa", criterion_label(t.criterion), *t.strength * kMPaPerPa),
         {0.0, right},
         {*t.strength * kMPaPerPa, *t.strength * kMPaPerPa},
         false});
  }
  const bool shear = r.load == StrengthLoad::kShear;
  return plot_curves(curves, out_dir, stem, title,
                     shear ? "gauge shear strain gamma_xy [%]" : "gauge strain eps_x [%]",
                     shear ? "shear stress tau_xy [MPa]" : "stress sigma_x [MPa]");
}

namespace {

// A cracked site's crack plane (failure at the material point), the unit normal its mode gives
// (contacts/site_failure.hpp crack_normal) in the coupon's axes.
Eigen::Vector3d site_crack_normal(const StrengthResult& r, const Model& model,
                                  const EventPoint& point) {
  const int ply = model.particles.ply(point.site);
  const double ply_angle = r.layup.empty() ? r.ply_angle : r.layup[static_cast<std::size_t>(ply)];
  PlyFailure failure;
  failure.mode = point.site_mode;
  failure.fracture_angle = point.site_fracture_angle;
  return crack_normal(failure, ply_angle);
}

// The cracked sites' planes for the crack pattern: each a particle diameter long, through the
// middle of the site's bonds on its normal's side (where its crack opens, half a diameter from
// the site), along the plane's trace in x-y.
std::vector<CrackTrace> crack_traces(const StrengthResult& r) {
  std::vector<CrackTrace> traces;
  if (!r.model) return traces;
  const Particles& p = r.model->particles;
  for (const EventPoint& point : r.path) {
    if (point.site < 0 || point.site >= p.size() || point.site_tooth != 0) continue;
    const Eigen::Vector3d n = site_crack_normal(r, *r.model, point);
    Eigen::Vector2d in_plane(n.x(), n.y());
    if (!(in_plane.norm() > 1e-9)) continue;  // a plane in the ply's plane has no trace
    in_plane.normalize();
    CrackTrace t;
    const double diameter = 2 * p.radius(point.site);
    t.centre =
        Eigen::Vector2d(p.reference_position(point.site, 0), p.reference_position(point.site, 1)) +
        0.5 * diameter * in_plane;
    t.along = Eigen::Vector2d(-in_plane.y(), in_plane.x());
    t.length = diameter;
    t.ply = p.ply(point.site);
    t.fibre = point.site_mode == PlyFailureMode::kFibreTension ||
              point.site_mode == PlyFailureMode::kFibreCompression;
    traces.push_back(t);
  }
  return traces;
}

}  // namespace

Figure plot_crack_pattern(const StrengthResult& r, const fs::path& out_dir, const std::string& stem,
                          const std::string& title) {
  const Model& model = *r.model;
  const Particles& p = model.particles;
  const Bonds& b = model.bonds;
  double x_begin = 0, x_end = 0;
  double broken_min = INFINITY, broken_max = -INFINITY;
  for (int k = 0; k < b.size(); ++k) {
    if (!b.is_broken(k) && !(b.damage(k) > 0)) continue;
    for (int i : {b.first(k), b.second(k)}) {
      broken_min = std::min(broken_min, p.reference_position(i, 0));
      broken_max = std::max(broken_max, p.reference_position(i, 0));
    }
  }
  if (broken_max >= broken_min) {
    const double width =
        p.reference_position.col(1).maxCoeff() - p.reference_position.col(1).minCoeff();
    x_begin = std::max(broken_min - width, p.reference_position.col(0).minCoeff());
    x_end = std::min(broken_max + width, p.reference_position.col(0).maxCoeff());
  }
  std::vector<std::string> labels;
  for (std::size_t k = 0; k < r.layup.size(); ++k)
    labels.push_back(fmt::format("ply {}: {:g} deg", k, r.layup[k] / kDegree));
  return plot_bond_states(model, out_dir, stem, title, x_begin, x_end, labels, crack_traces(r));
}

namespace {

// At the material point: each particle's site crack after the events before `event` (the
// snapshot's state is that event's critical state, before it changes anything), as point data:
// crack_mode (-1: none; else PlyFailureMode: 0 fibre tension, 1 fibre compression, 2 matrix
// tension, 3 matrix compression), crack_normal (the plane's unit normal, zero where none),
// crack_teeth (events of its crack: 1 for a brittle one) and crack_energy (what its bonds
// dissipated [J]).
VtkOptions site_crack_fields(const StrengthResult& r, const Model& model, long event) {
  VtkOptions options;
  if (r.failure_criterion == PlyFailureModel::kBond) return options;
  const int n = model.particles.size();
  Eigen::ArrayXd mode = Eigen::ArrayXd::Constant(n, -1), teeth = Eigen::ArrayXd::Zero(n);
  Eigen::ArrayXd energy = Eigen::ArrayXd::Zero(n);
  Vector3Array normal = Vector3Array::Zero(n, 3);
  for (const EventPoint& point : r.path) {
    if (point.event >= event) break;
    const int i = point.site;
    if (i < 0 || i >= n) continue;
    mode(i) = static_cast<double>(point.site_mode);
    normal.row(i) = site_crack_normal(r, model, point).transpose().array();
    teeth(i) += 1;
    energy(i) += point.crack_energy;
  }
  options.particle_scalars = {
      {"crack_mode", mode}, {"crack_teeth", teeth}, {"crack_energy", energy}};
  options.particle_vectors = {{"crack_normal", normal}};
  return options;
}

}  // namespace

std::vector<fs::path> write_strength_vtu(const StrengthResult& r, const fs::path& out_dir,
                                         const std::string& stem) {
  fs::create_directories(out_dir / "vtu");
  VtkSeries series((out_dir / "vtu" / fmt::format("{}.pvd", stem)).string());
  if (r.snapshots.empty()) {
    series.add_model(static_cast<double>(r.events), *r.model,
                     site_crack_fields(r, *r.model, r.events + 1));
  } else {
    for (const StrengthSnapshot& snapshot : r.snapshots)
      series.add_model(static_cast<double>(snapshot.event), *snapshot.model,
                       site_crack_fields(r, *snapshot.model, snapshot.event));
  }
  std::vector<fs::path> files{fs::path("vtu") / fmt::format("{}.pvd", stem)};
  for (const std::string& file : series.files()) files.push_back(fs::path("vtu") / file);
  return files;
}

}  // namespace plydem
