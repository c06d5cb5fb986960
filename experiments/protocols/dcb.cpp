#include "experiments/protocols/dcb.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numbers>

#include "core/error.hpp"
#include "core/stopwatch.hpp"
#include "core/units.hpp"
#include "strategies/registry.hpp"
#include "strategies/specimen.hpp"

namespace plydem {

namespace {

/// The opening at load factor 1 [m] (the solve is linear: any value gives the same path).
constexpr double kUnitOpening = 1e-3;

void require_size(double value, const char* what) {
  require(std::isfinite(value) && value > 0,
          fmt::format("dcb: the {} must be positive and finite, got {}", what, value));
}

// One row of particles facing the interface, sorted by x.
std::vector<int> facing_row(const Particles& p, int first, int last, bool top, double diameter) {
  double edge =
      top ? -std::numeric_limits<double>::infinity() : std::numeric_limits<double>::infinity();
  for (int i = first; i < last; ++i) {
    const double y = p.reference_position(i, 1);
    edge = top ? std::max(edge, y) : std::min(edge, y);
  }
  std::vector<int> row;
  for (int i = first; i < last; ++i) {
    if (std::abs(p.reference_position(i, 1) - edge) <= 0.25 * diameter) row.push_back(i);
  }
  std::sort(row.begin(), row.end(),
            [&](int a, int b) { return p.reference_position(a, 0) < p.reference_position(b, 0); });
  return row;
}

}  // namespace

double DcbSettings::arm_thickness() const {
  return 0.5 * static_cast<double>(layup.size()) * ply_thickness;
}

void DcbSettings::validate() const {
  require(!layup.empty(), "dcb: the layup has no ply");
  require(layup.size() % 2 == 0,
          fmt::format("dcb: the layup has {} plies; the delamination lies on the mid-plane, "
                      "which needs an even number of plies",
                      layup.size()));
  for (std::size_t k = 0; k < layup.size(); ++k) {
    const double turns = layup[k] / std::numbers::pi;
    require(std::isfinite(layup[k]) && std::abs(turns - std::round(turns)) < 1e-9,
            fmt::format("dcb: ply {} is at {:g} deg; the side-view DCB represents unidirectional "
                        "laminates (every ply at 0 deg, fibres along the beam), whose x-thickness "
                        "plane is the ply's 1-3 plane",
                        k + 1, layup[k] / kDegree));
  }
  plydem::validate(material);
  require_size(ply_thickness, "ply thickness");
  require_size(length, "length");
  require_size(width, "width");
  require_size(crack, "starter crack length");
  require_size(particle_diameter, "particle diameter");
  require_size(max_crack, "largest crack length (max_crack)");
  require(crack < max_crack,
          fmt::format("dcb: the starter crack ({:g} mm) must be shorter than the crack length at "
                      "which the run stops ({:g} mm)",
                      crack / kMetresPerMm, max_crack / kMetresPerMm));
  require(max_crack < length,
          fmt::format("dcb: the crack length at which the run stops ({:g} mm) must be shorter "
                      "than the beam ({:g} mm)",
                      max_crack / kMetresPerMm, length / kMetresPerMm));
  const double rows = arm_thickness() / particle_diameter;
  require(std::abs(rows - std::round(rows)) < 1e-6 && std::round(rows) >= 2,
          fmt::format("dcb: each arm is {:g} mm thick ({} plies of {:g} mm), which is {:.4g} "
                      "particle diameters of {:g} mm; it must be a whole number of them, at least "
                      "2",
                      arm_thickness() / kMetresPerMm, layup.size() / 2,
                      ply_thickness / kMetresPerMm, rows, particle_diameter / kMetresPerMm));
  require(length / particle_diameter <= 1e6,
          fmt::format("dcb: {:.3g} particle columns along the beam is more than this test builds "
                      "(1e6)",
                      length / particle_diameter));
  interface.validate();
  require(interface_strength.normal > 0,
          "dcb: the interface's normal strength (interface.strength_normal, Pa) is required");
  require(interface_strength.GIc > 0,
          "dcb: the interface's mode I fracture energy (interface.GIc, J/m^2) is required: "
          "the DCB measures it");
  resolved_interface_strength().validate();
  events.validate();
}

InterfaceStrength DcbSettings::resolved_interface_strength() const {
  InterfaceStrength s = interface_strength;
  if (s.shear == 0) s.shear = material.strength.S12 > 0 ? material.strength.S12 : s.normal;
  return s;
}

DcbBeamTheory dcb_beam_theory(const Material& m, double b, double h, double a, double GIc) {
  DcbBeamTheory t;
  t.crack = a;
  const double G13 = m.G12;
  const double gamma = 1.18 * std::sqrt(m.E1 * m.E2) / G13;
  const double ratio = gamma / (1.0 + gamma);
  t.chi = std::sqrt(m.E1 / (11.0 * G13)) * (3.0 - 2.0 * ratio * ratio);
  const double bending = m.E1 * b * h * h * h;
  auto compliance = [&](double crack) { return 8.0 * crack * crack * crack / bending; };
  auto load = [&](double crack) { return b * h / crack * std::sqrt(GIc * m.E1 * h / 12.0); };
  t.compliance = compliance(a);
  t.propagation_load = load(a);
  t.corrected_compliance = compliance(a + t.chi * h);
  t.corrected_propagation_load = load(a + t.chi * h);
  return t;
}

namespace {

// The two arms of the side view in one model: plies of the side view, the lower at y in [0, h]
// (its particles first), the upper above it.
struct DcbArms {
  Model model;
  int lower_particles = 0;
  std::string arm_description;  // the strategy's description of one arm
};

DcbArms build_arms(const Strategy& strategy, const DcbSettings& s) {
  const double h = s.arm_thickness();
  CouponSpec arm;
  arm.material = s.material;
  arm.ply_angle = 0;
  arm.length = s.length;
  arm.width = h;
  arm.thickness = s.width;
  arm.particle_diameter = s.particle_diameter;
  SpecimenBuilder builder(strategy);
  Specimen lower = builder.build(arm);
  Model upper = lower.model;
  upper.particles.reference_position.col(1) += h;
  // Both arms are ply 0 (one ply in the side view: plan-view plots draw it as it is).
  DcbArms arms;
  arms.lower_particles = lower.model.particles.size();
  arms.arm_description = lower.model.description;
  Model& model = arms.model;
  model.particles.append(lower.model.particles);
  model.particles.append(upper.particles);
  model.bonds.append(lower.model.bonds);
  model.bonds.append(upper.bonds, arms.lower_particles);
  model.thickness = s.width;
  return arms;
}

// The arms' facing rows, column by column, and where the interface lies.
struct InterfaceColumns {
  std::vector<int> below, above;  // the facing rows' particles, sorted by x
  double gap = 0;                 // between the facing rows' centres [m]
  double x_load = 0, x_end = 0;   // the load line and the far end [m]
  double spacing = 0;             // of the columns [m]
  double share = 0;               // each column's share of the interface [m^2]
};

InterfaceColumns interface_columns(const Particles& p, int lower_particles, const DcbSettings& s) {
  const double d = s.particle_diameter;
  InterfaceColumns c;
  c.below = facing_row(p, 0, lower_particles, true, d);
  c.above = facing_row(p, lower_particles, p.size(), false, d);
  const std::vector<int>& below = c.below;
  const std::vector<int>& above = c.above;
  require(below.size() == above.size() && below.size() >= 2,
          fmt::format("dcb: the arms' facing rows hold {} and {} particles; the side-view DCB "
                      "joins them column by column (use the square strategy)",
                      below.size(), above.size()));
  for (std::size_t k = 0; k < below.size(); ++k) {
    require(
        std::abs(p.reference_position(below[k], 0) - p.reference_position(above[k], 0)) <= 0.05 * d,
        fmt::format(
            "dcb: the {} strategy's rows facing the mid-plane are not above each other "
            "(column {} is {:g} mm apart); the side-view DCB joins them column by "
            "column (use the square strategy)",
            s.strategy, k + 1,
            std::abs(p.reference_position(below[k], 0) - p.reference_position(above[k], 0)) /
                kMetresPerMm));
  }
  c.gap = p.reference_position(above.front(), 1) - p.reference_position(below.front(), 1);
  require(c.gap > 0.5 * d, fmt::format("dcb: the arms' facing rows are {:g} mm apart, closer than "
                                       "half a particle diameter",
                                       c.gap / kMetresPerMm));
  c.x_load = p.reference_position.col(0).minCoeff();
  c.x_end = p.reference_position.col(0).maxCoeff();
  c.spacing = s.length / static_cast<double>(below.size());
  c.share = s.width * c.spacing;
  return c;
}

// An interface bond of the crack front and where its share of the interface starts.
struct Front {
  double x;  // start of the bond's share of interface
  int bond;
};

// Interface bonds ahead of the starter crack (a column's share of the interface starts half a
// spacing before it), appended to the model's bonds; every bond's strength radius. The front, in
// x.
std::vector<Front> join_arms(Model& model, const InterfaceColumns& columns,
                             const InterfaceStiffness& k, const InterfaceStrength& strength,
                             const DcbSettings& s) {
  const Particles& p = model.particles;
  const double spacing = columns.spacing;
  Bonds between;
  std::vector<std::pair<int, int>> pairs;
  for (std::size_t c = 0; c < columns.below.size(); ++c) {
    const double x = p.reference_position(columns.below[c], 0);
    if (x - 0.5 * spacing < columns.x_load + s.crack - 1e-9 * s.length) continue;
    pairs.emplace_back(columns.below[c], columns.above[c]);
  }
  require(pairs.size() >= 2,
          fmt::format("dcb: the starter crack ({:g} mm) leaves fewer than two bonded columns",
                      s.crack / kMetresPerMm));
  between.resize(static_cast<int>(pairs.size()));
  for (int c = 0; c < between.size(); ++c) {
    between.first(c) = pairs[c].first;
    between.second(c) = pairs[c].second;
    between.normal_stiffness(c) = k.normal * columns.share;
    between.shear_stiffness(c) = k.shear * columns.share;
    between.family(c) = 0;
    between.kind(c) = static_cast<int>(BondKind::kInterface);
    set_bond_geometry(p, between, c);
  }
  const int first_interface = model.bonds.size();
  model.bonds.append(between);
  Bonds& bonds = model.bonds;
  for (int b = 0; b < bonds.size(); ++b) {
    bonds.strength_radius(b) = std::min(p.radius(bonds.first(b)), p.radius(bonds.second(b)));
  }
  std::vector<Front> front;
  for (int b = first_interface; b < bonds.size(); ++b) {
    set_interface_bond_strength(bonds, b, columns.share, strength);
    front.push_back({p.reference_position(bonds.first(b), 0) - 0.5 * spacing, b});
  }
  return front;
}

// The plane problem, the loading blocks (the end columns moved apart along y at the unit
// opening) and the reaction (the upper end column's y).
struct OpeningLoad {
  DofConstraints unit;
  DofFlags reaction;
};

OpeningLoad opening_load(const Particles& p, int lower_particles, const InterfaceColumns& columns) {
  const int n = p.size();
  OpeningLoad load{DofConstraints(n), DofFlags::Constant(n, kDofsPerParticle, false)};
  for (int i = 0; i < n; ++i) {
    load.unit.fix(i, Dof::kUz);
    load.unit.fix(i, Dof::kThetaX);
    load.unit.fix(i, Dof::kThetaY);
    if (p.reference_position(i, 0) > columns.x_load + 0.25 * columns.spacing) continue;
    const bool top = i >= lower_particles;
    load.unit.fix(i, Dof::kUy, (top ? 0.5 : -0.5) * kUnitOpening);
    if (top) load.reaction(i, static_cast<int>(Dof::kUy)) = true;
  }
  return load;
}

// The load-opening curve as the events solver reports its critical states, with the crack length
// at each, the cohesive zone at the peak and the snapshots.
struct DcbCurve {
  DcbCurve(DcbResult& result, const std::vector<Front>& crack_front,
           const InterfaceColumns& interface, bool snapshots)
      : r(result), front(crack_front), columns(interface), record_snapshots(snapshots) {}

  DcbResult& r;
  const std::vector<Front>& front;
  const InterfaceColumns& columns;
  bool record_snapshots = false;
  std::size_t tip = 0;  // the first interface bond (in x) not broken
  double peak = -std::numeric_limits<double>::infinity();
  std::shared_ptr<const Model> peak_state;
  long peak_event = 0;
  double peak_load = -std::numeric_limits<double>::infinity();

  // The crack tip: the first interface bond (in x) not broken.
  double crack_length(const Bonds& state) {
    while (tip < front.size() && state.is_broken(front[tip].bond)) ++tip;
    return (tip < front.size() ? front[tip].x : columns.x_end) - columns.x_load;
  }

  // The unloaded origin.
  void start() {
    r.opening.push_back(0);
    r.load.push_back(0);
    r.crack.push_back(r.initial_crack);
  }

  void on_event(const Model& state, const EventPoint& point) {
    r.opening.push_back(point.load_factor * kUnitOpening);
    r.load.push_back(point.reaction);
    r.crack.push_back(crack_length(state.bonds));
    if (point.reaction > peak_load) {
      peak_load = point.reaction;
      int softened = 0;
      for (const Front& f : front) {
        const double damage = state.bonds.damage(f.bond);
        if (damage > 0 && damage < 1) ++softened;
      }
      r.cohesive_zone_at_peak = softened * columns.spacing;
    }
    if (!record_snapshots) return;
    const long e = point.event;
    if (e == 1 || (e & (e - 1)) == 0) {
      r.snapshots.push_back({e, e == 1 ? "first softening" : fmt::format("event {}", e),
                             std::make_shared<const Model>(state)});
    }
    if (point.reaction > peak) {
      peak = point.reaction;
      peak_event = e;
      peak_state = !r.snapshots.empty() && r.snapshots.back().event == e
                       ? r.snapshots.back().model
                       : std::make_shared<const Model>(state);
    }
  }

  // The peak (labelled, or added when it was not an event 2^k) and the final state, in event
  // order.
  void finish_snapshots(const std::shared_ptr<const Model>& final_state) {
    if (peak_state && peak_event > 1 && (peak_event & (peak_event - 1)) != 0) {
      r.snapshots.push_back({peak_event, "peak", peak_state});
    } else {
      for (DcbSnapshot& snapshot : r.snapshots)
        if (snapshot.event == peak_event) snapshot.label += " (peak)";
    }
    r.snapshots.push_back({r.events + 1, "final", final_state});
    std::stable_sort(r.snapshots.begin(), r.snapshots.end(),
                     [](const DcbSnapshot& a, const DcbSnapshot& b) { return a.event < b.event; });
  }
};

// The events solver opening the beam until the crack reaches s.max_crack (or the solver stops),
// each critical state into `curve`.
EventsResult open_beam(const DcbSettings& s,
                       const std::function<void(const EventProgress&)>& progress,
                       const OpeningLoad& load, Model& model, DcbCurve& curve) {
  EventSettings events = s.events;
  events.static_settings.pin_rigid_modes = true;
  events.static_settings.linear_solver = s.linear_solver;
  if (progress) events.on_progress = progress;
  curve.start();
  events.on_event = [&](const Model& state, const EventPoint& point) {
    curve.on_event(state, point);
  };
  events.stop_after = [&](const Model& state, const EventPoint&) -> std::string {
    if (curve.crack_length(state.bonds) >= s.max_crack)
      return fmt::format("crack reached {:g} mm", s.max_crack / kMetresPerMm);
    return "";
  };
  return run_events(model, load.unit, load.reaction, events);
}

// The run's figures: the initial compliance, the peak, the crack grown and the energy released
// per unit area of it.
void take_events_result(const EventsResult& run, const DcbSettings& s, const Model& model,
                        DcbCurve& curve, DcbResult& r) {
  require(!run.path.empty(),
          fmt::format("dcb: no interface bond was loaded to its strength ({})", run.stop));
  require(r.load[1] > 0, "dcb: the opening gives no positive load on the upper arm");
  r.breaks = run.breaks;
  r.events = static_cast<long>(run.path.size());
  r.stop = run.stop;
  r.factorizations = run.factorizations;
  r.solves = run.solves;
  r.dissipated_energy = run.dissipated_energy;
  r.initial_compliance = r.opening[1] / r.load[1];
  const std::size_t at = static_cast<std::size_t>(run.peak) + 1;
  r.propagation_load = r.load[at];
  r.opening_at_peak = r.opening[at];
  r.crack_at_peak = r.crack[at];
  r.final_crack = curve.crack_length(model.bonds);
  const double grown = r.final_crack - r.initial_crack;
  r.released_per_area = grown > 0 ? r.dissipated_energy / (s.width * grown) : 0.0;
}

}  // namespace

DcbResult run_dcb(const DcbSettings& s, const std::function<void(const EventProgress&)>& progress) {
  const auto start = std::chrono::steady_clock::now();
  s.validate();
  require(!s.events.on_event && !s.events.on_progress && !s.events.stop_after,
          "dcb: the events settings' callbacks are the test's own (pass progress to run_dcb)");
  const std::unique_ptr<Strategy> strategy = default_registry().create(s.strategy);
  for (const auto& [name, value] : s.strategy_options) strategy->set_option(name, value);

  DcbResult r;
  r.strategy = s.strategy;
  r.material = s.material;
  r.layup = s.layup;
  r.width = s.width;
  r.length = s.length;
  r.arm_thickness = s.arm_thickness();
  r.particle_diameter = s.particle_diameter;
  const double d = s.particle_diameter;
  const double h = r.arm_thickness;

  DcbArms arms = build_arms(*strategy, s);
  Model& model = arms.model;
  const Particles& p = model.particles;
  const int n = p.size();
  const InterfaceColumns columns = interface_columns(p, arms.lower_particles, s);
  InterfaceStiffness k = s.interface;
  if (k.normal == 0) k.normal = s.material.E2 / columns.gap;
  if (k.shear == 0) k.shear = s.material.G12 / columns.gap;
  r.interface = k;
  const InterfaceStrength strength = s.resolved_interface_strength();
  r.interface_strength = strength;
  const std::vector<Front> front = join_arms(model, columns, k, strength, s);
  const int interface_bonds = static_cast<int>(front.size());
  r.interface_ductility = model.bonds.ductility(front.front().bond);
  model.description =
      fmt::format("side-view DCB of {}: two arms of {} ({} rows of {:g} mm), {} interface bonds",
                  format_layup(s.layup), arms.arm_description, static_cast<int>(std::round(h / d)),
                  d / kMetresPerMm, interface_bonds);
  model.check_consistency();
  r.particles = n;
  r.bonds = model.bonds.size();
  r.interface_bonds = interface_bonds;
  r.initial_crack = front.front().x - columns.x_load;
  r.theory = dcb_beam_theory(s.material, s.width, h, r.initial_crack, strength.GIc);
  spdlog::debug("dcb: {} particles, {} bonds, load line x = {:g} mm, far end {:g} mm, a0 = {:g} mm",
                n, model.bonds.size(), columns.x_load / kMetresPerMm, columns.x_end / kMetresPerMm,
                r.initial_crack / kMetresPerMm);

  const OpeningLoad load = opening_load(p, arms.lower_particles, columns);
  DcbCurve curve(r, front, columns, s.record_snapshots);
  const EventsResult run = open_beam(s, progress, load, model, curve);
  take_events_result(run, s, model, curve, r);
  auto final_state = std::make_shared<const Model>(std::move(model));
  if (s.record_snapshots) curve.finish_snapshots(final_state);
  r.model = std::move(final_state);
  r.wall_seconds = seconds_since(start);
  return r;
}

DcbReduction reduce_dcb_curve(const DcbResult& r) {
  DcbReduction out;
  // Propagation: the critical states after the peak whose crack has grown.
  std::vector<std::size_t> points;
  for (std::size_t i = 1; i < r.load.size(); ++i) {
    if (i > 1 && r.crack[i] > r.crack_at_peak && r.load[i] > 0) points.push_back(i);
  }
  out.points = static_cast<int>(points.size());
  if (points.size() < 3) return out;
  // C^(1/3) = m (a + Delta): least squares over the propagation points.
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (std::size_t i : points) {
    const double x = r.crack[i], y = std::cbrt(r.opening[i] / r.load[i]);
    sx += x;
    sy += y;
    sxx += x * x;
    sxy += x * y;
  }
  const double n = static_cast<double>(points.size());
  const double slope = (n * sxy - sx * sy) / (n * sxx - sx * sx);
  const double intercept = (sy - slope * sx) / n;
  if (!(slope > 0)) return out;
  out.delta = intercept / slope;
  out.flexural_modulus =
      8.0 / (r.width * r.arm_thickness * r.arm_thickness * r.arm_thickness * slope * slope * slope);
  double sum = 0;
  for (std::size_t i : points) {
    sum += 3.0 * r.load[i] * r.opening[i] / (2.0 * r.width * (r.crack[i] + std::abs(out.delta)));
  }
  out.GIc = sum / n;
  return out;
}

}  // namespace plydem
