// The notched-plate experiment kind (`plydem run experiments/hole_failure.toml`, kind
// `hole_failure`): the paper's Fig. 16 plate (a [0/90/0] E-glass/MY750 laminate with a central
// hole) pulled to failure by the strength test (experiments/protocols/strength.hpp,
// StrengthSettings::hole_diameter), and the same plate without the hole for the unnotched
// strength. Reported: both plates' grip force against grip travel, notched strength (gross and
// net section) beside the unnotched one, the first failure and where it sits, beside Lekhnitskii's
// orthotropic stress concentration with Heywood's finite-width factor
// (core/stress_concentration.hpp), damage maps per ply at chosen fractions of the peak load, the
// cracks per ply and each plate's strength-test section (figures, VTU series). Config keys
// (README, "Notched strength: the hole plate to failure"):
//
//   experiment = "hole_failure"
//   material = "eglass-my750"   strategy = "square"   strategy_options = []
//   layup = "[0/90/0]"          weibull_modulus = 0   seed = 1
//   [coupon] length_mm = 60, width_mm = 36, thickness_mm = 0.5 (per ply), diameter_mm = 1.2,
//            grip_mm = 0 (two diameters), hole_diameter_mm = 3
//   [quick]  the same sizes
//   [interface] normal, shear (N/m^3), strength_normal, strength_shear (Pa)
//   [events] max_events, stop_fraction, max_update_rank
//   [maps] load_fractions (of the notched plate's peak grip force, each in (0, 1])
//   [output] vtu_series
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/error.hpp"
#include "core/material.hpp"
#include "core/stress_concentration.hpp"
#include "experiments/output/figures.hpp"
#include "experiments/output/vtk_output.hpp"
#include "experiments/protocols/strength.hpp"
#include "experiments/runner/coupon_config.hpp"
#include "experiments/runner/experiment.hpp"
#include "experiments/runner/report_text.hpp"
#include "experiments/runner/strength_experiment.hpp"
#include "solvers/cracks.hpp"
#include "strategies/laminate.hpp"
#include "strategies/registry.hpp"

namespace plydem {
namespace fs = std::filesystem;

namespace {

constexpr double kMm = 1e-3;
constexpr double kMPa = 1e-6;

// A break lies "at the hole's edge" when its contact point is within this many particle diameters
// of the hole's circle: the first column of particles left by the cut sits up to one diameter
// inside it, and its bonds' contact points half a diameter further.
constexpr double kEdgeDiameters = 1.5;

// The grip force [N] at curve point k of a strength result (its stress is the reaction over the
// gauge cross-section).
double grip_force(const StrengthResult& r, std::size_t k) {
  return r.stress[k] * r.cross_section;
}

// The grip travel [m] at curve point k: the nominal strain times the grip-to-grip span.
double grip_travel(const StrengthResult& r, std::size_t k) {
  return r.nominal_strain[k] * r.span;
}

// A copy of the run's final model with the bonds that broke at or after critical state `event`
// intact again: the damage present at that state (the path is linear between events, so the
// broken set is all that differs).
Model damage_at(const StrengthResult& r, long event) {
  Model m = *r.model;
  for (const BondBreak& b : r.breaks) {
    if (b.at >= static_cast<double>(event)) {
      m.bonds.state(b.bond) = static_cast<int>(BondState::kIntact);
      m.bonds.damage(b.bond) = 0;
    }
  }
  return m;
}

class HoleFailureExperiment : public Experiment {
 public:
  ExperimentOutput run(const ExperimentConfig& c, const ExperimentContext& context) const override {
    c.require_known_keys({"experiment",
                          "description",
                          "material",
                          "strategy",
                          "strategy_options",
                          "layup",
                          "weibull_modulus",
                          "seed",
                          "coupon.length_mm",
                          "coupon.width_mm",
                          "coupon.thickness_mm",
                          "coupon.diameter_mm",
                          "coupon.grip_mm",
                          "coupon.hole_diameter_mm",
                          "quick.length_mm",
                          "quick.width_mm",
                          "quick.thickness_mm",
                          "quick.diameter_mm",
                          "quick.grip_mm",
                          "quick.hole_diameter_mm",
                          "interface.normal",
                          "interface.shear",
                          "interface.strength_normal",
                          "interface.strength_shear",
                          "events.max_events",
                          "events.stop_fraction",
                          "events.max_update_rank",
                          "maps.load_fractions",
                          "output.vtu_series"});
    const std::string name = c.name();
    const std::string origin = c.path().string();
    auto size = [&](const std::string& key, double fallback_mm) {
      const double full = c.number(fmt::format("coupon.{}", key), fallback_mm);
      return (context.quick ? c.number(fmt::format("quick.{}", key), full) : full) * kMm;
    };
    StrengthSettings unnotched;
    unnotched.force = context.force;
    unnotched.strategy = c.string("strategy", unnotched.strategy);
    unnotched.strategy_options = parse_strategy_options(
        c.strings("strategy_options", {}), fmt::format("{}: strategy_options", origin));
    // The paper's plate by default (not the strength coupon's sizes of coupon_from_config).
    unnotched.coupon.material = load_material(c.string("material", "eglass-my750"));
    unnotched.coupon.length = size("length_mm", 60);
    unnotched.coupon.width = size("width_mm", 36);
    unnotched.coupon.thickness = size("thickness_mm", 0.5);
    unnotched.coupon.particle_diameter = size("diameter_mm", 1.2);
    try {
      unnotched.coupon.validate();
    } catch (const Error& e) {
      throw Error(fmt::format("{}: {}", origin, e.what()));
    }
    unnotched.grip_length = size("grip_mm", 0);
    const std::string layup_text = c.string("layup", "[0/90/0]");
    try {
      unnotched.layup = parse_layup(layup_text);
    } catch (const Error& e) {
      throw Error(fmt::format("{}: layup: {}", origin, e.what()));
    }
    unnotched.interface.normal = c.number("interface.normal", 0);
    unnotched.interface.shear = c.number("interface.shear", 0);
    unnotched.interface_strength.normal = c.number("interface.strength_normal", 0);
    unnotched.interface_strength.shear = c.number("interface.strength_shear", 0);
    unnotched.weibull_modulus = c.number("weibull_modulus", 0);
    unnotched.seed = static_cast<std::uint64_t>(c.integer("seed", 1));
    unnotched.events.max_events = c.integer("events.max_events", unnotched.events.max_events);
    unnotched.events.stop_fraction =
        c.number("events.stop_fraction", unnotched.events.stop_fraction);
    unnotched.events.max_update_rank =
        static_cast<int>(c.integer("events.max_update_rank", unnotched.events.max_update_rank));
    unnotched.record_snapshots = c.boolean("output.vtu_series", true);
    const double hole = size("hole_diameter_mm", 3);
    require(hole > 0, fmt::format("{}: coupon.hole_diameter_mm must be positive (the notched "
                                  "plate needs a hole), got {} mm",
                                  origin, hole / kMm));
    std::vector<double> fractions = c.numbers("maps.load_fractions", {0.5, 0.8, 1.0});
    for (double f : fractions) {
      require(std::isfinite(f) && f > 0 && f <= 1,
              fmt::format("{}: maps.load_fractions must lie in (0, 1] (fractions of the peak "
                          "grip force), got {}",
                          origin, f));
    }
    std::sort(fractions.begin(), fractions.end());
    StrengthSettings notched = unnotched;
    notched.hole_diameter = hole;
    try {
      unnotched.validate();
      notched.validate();
    } catch (const Error& e) {
      throw Error(fmt::format("{}: {}", origin, e.what()));
    }
    require_strengths(unnotched.coupon.material, fmt::format("{} (kind hole_failure)", origin));

    const std::unique_ptr<Strategy> strategy = default_registry().create(unnotched.strategy);
    for (const auto& [option, value] : unnotched.strategy_options)
      strategy->set_option(option, value);
    SpecimenBuilder builder(*strategy);

    ExperimentOutput out;
    const Material& material = unnotched.coupon.material;
    out.title = fmt::format("Notched strength: {} {} plate with a {:g} mm hole to failure",
                            material.name, layup_text, hole / kMm);
    const std::string dem = fmt::format("dem {}", unnotched.strategy);
    auto row = [&](const std::string& case_name, const std::string& quantity,
                   const std::string& source, double value, const std::string& unit) {
      if (std::isfinite(value))
        out.rows.push_back({name, case_name, quantity, source, value, unit});
    };

    std::vector<StrengthResult> results;
    std::string sections;
    for (const auto& [label, settings] :
         {std::pair<std::string, const StrengthSettings*>{"notched", &notched},
          std::pair<std::string, const StrengthSettings*>{"unnotched", &unnotched}}) {
      spdlog::info("{}: the {} plate in tension to failure", name, label);
      StrengthTest test(*settings);
      const std::string which = label;
      test.on_progress([&](const EventProgress& p) {
        spdlog::info("{} {}: {} events, {} broken, peak {:.4g} N, {:.0f} s", name, which, p.events,
                     p.broken, p.peak_reaction, p.elapsed_seconds);
      });
      results.push_back(test.run(builder));
      const ExperimentOutput one = strength_output(results.back(), context.out_dir, name, label,
                                                   file_stem(fmt::format("{}_{}", name, label)));
      out.rows.insert(out.rows.end(), one.rows.begin(), one.rows.end());
      out.files.insert(out.files.end(), one.files.begin(), one.files.end());
      sections += one.report_markdown;
    }
    const StrengthResult& n = results[0];
    const StrengthResult& u = results[1];

    // Gross section: the unnotched plate's (the gauge cross-section of the same coupon without
    // the hole); net section: what the hole leaves of the width.
    const double gross_area = u.cross_section;
    const double width = unnotched.coupon.width;
    const double net_fraction = 1.0 - hole / width;
    const std::size_t n_peak = static_cast<std::size_t>(n.peak) + 1;
    const std::size_t u_peak = static_cast<std::size_t>(u.peak) + 1;
    const double notched_peak_force = grip_force(n, n_peak);
    const double unnotched_peak_force = grip_force(u, u_peak);
    const double notched_gross = notched_peak_force / gross_area;
    const double notched_net = notched_gross / net_fraction;
    const double unnotched_strength = unnotched_peak_force / gross_area;
    const double notched_first = grip_force(n, 1) / gross_area;
    const double unnotched_first = grip_force(u, 1) / gross_area;

    // The closed form: Lekhnitskii's Kt_inf of the laminate (CLT constants), Heywood's factor.
    std::vector<Ply> plies =
        laminate_plies({unnotched.coupon, unnotched.layup, unnotched.interface});
    const InPlaneConstants laminate = laminate_constants(plies);
    const double kt_inf = orthotropic_hole_stress_concentration(laminate);
    const double fwc = heywood_finite_width_factor(hole, width);
    const double kt = kt_inf * fwc;
    const double predicted_first = unnotched_first / kt;
    double clt_first = NAN;
    for (const CriterionStrength& t : u.theory)
      if (t.criterion == FailureCriterion::kMaxStress && t.strength) clt_first = *t.strength;

    // Where the notched plate first broke.
    const BondBreak& first = n.breaks.front();
    const double d = unnotched.coupon.particle_diameter;
    const double from_edge = (first.position.head<2>() - n.hole_centre).norm() - 0.5 * hole;
    const bool at_edge = from_edge <= kEdgeDiameters * d;
    const int first_ply = n.model->bonds.is_interface(first.bond)
                              ? -1
                              : n.model->particles.ply(n.model->bonds.first(first.bond));

    row("notched", "strength gross", dem, notched_gross * kMPa, "MPa");
    row("notched", "strength net section", dem, notched_net * kMPa, "MPa");
    row("notched", "peak grip force", dem, notched_peak_force, "N");
    row("notched", "first failure gross stress", dem, notched_first * kMPa, "MPa");
    row("notched", "first failure gross stress", "unnotched dem / Kt", predicted_first * kMPa,
        "MPa");
    row("notched", "first failure gross stress", "clt max-stress / Kt", clt_first / kt * kMPa,
        "MPa");
    row("notched", "first failure distance from hole edge", dem, from_edge / kMm, "mm");
    row("notched", "first failure ply", dem, first_ply, "1");
    row("notched", "Kt infinite plate", "lekhnitskii", kt_inf, "1");
    row("notched", "finite width factor", "heywood", fwc, "1");
    row("notched", "Kt", "lekhnitskii heywood", kt, "1");
    row("notched", "notched to unnotched strength", dem, notched_gross / unnotched_strength, "1");
    row("notched", "hole particles removed", dem, n.hole.particles, "1");
    row("notched", "particles", dem, n.particles, "1");
    row("unnotched", "strength gross", dem, unnotched_strength * kMPa, "MPa");
    row("unnotched", "peak grip force", dem, unnotched_peak_force, "N");
    row("unnotched", "first failure gross stress", dem, unnotched_first * kMPa, "MPa");
    row("unnotched", "particles", dem, u.particles, "1");

    // Load-displacement of both plates.
    std::vector<Curve> curves;
    for (const auto* r : {&n, &u}) {
      Curve curve{r == &n ? fmt::format("with the {:g} mm hole", hole / kMm) : "without the hole",
                  {},
                  {},
                  true};
      for (std::size_t k = 0; k < r->stress.size(); ++k) {
        curve.x.push_back(grip_travel(*r, k) / kMm);
        curve.y.push_back(grip_force(*r, k));
      }
      curves.push_back(curve);
    }
    const Figure load =
        plot_curves(curves, context.out_dir, fmt::format("{}_load_displacement", file_stem(name)),
                    fmt::format("{} {}: grip force against grip travel", material.name, layup_text),
                    "grip travel (mm)", "grip force (N)");
    out.files.insert(out.files.end(), load.files.begin(), load.files.end());

    // Damage maps per ply: the notched plate at each fraction of its peak (the first critical
    // state on the way up whose grip force reaches it), and its final state.
    std::vector<std::string> ply_labels;
    for (std::size_t k = 0; k < plies.size(); ++k)
      ply_labels.push_back(
          fmt::format("ply {} ({:g}°)", k, plies[k].angle * 180 / std::numbers::pi));
    std::string maps;
    std::string map_table = markdown_row({"map", "event", "grip force (N)", "gross stress (MPa)",
                                          "broken bonds", "cracks per ply"}) +
                            "|---|--:|--:|--:|--:|---|\n";
    // The maps' states as a VTU series too (time = event), drawn on the undeformed plate: the
    // displacements at an earlier critical state are not kept (only the bonds' states are).
    fs::create_directories(context.out_dir / "vtu");
    const std::string maps_stem = file_stem(fmt::format("{}_damage_maps", name));
    VtkSeries maps_series((context.out_dir / "vtu" / fmt::format("{}.pvd", maps_stem)).string());
    auto add_map = [&](const std::string& label, long event, const Model& state, double force) {
      Model undeformed = state;
      undeformed.particles.displacement.setZero();
      undeformed.particles.rotation.setZero();
      maps_series.add_model(static_cast<double>(event), undeformed);
      std::vector<BondBreak> so_far;
      for (const BondBreak& b : n.breaks)
        if (b.at < static_cast<double>(event)) so_far.push_back(b);
      const std::vector<Crack> cracks = find_cracks(state, so_far);
      std::string per_ply;
      for (std::size_t k = 0; k < plies.size(); ++k) {
        const auto count = std::count_if(cracks.begin(), cracks.end(), [&](const Crack& cr) {
          return !cr.interface && cr.ply == static_cast<int>(k);
        });
        per_ply += fmt::format("{}{}: {}", k == 0 ? "" : ", ", k, count);
      }
      map_table += markdown_row({label, fmt::format("{}", event), fmt::format("{:.1f}", force),
                                 fmt::format("{:.2f}", force / gross_area * kMPa),
                                 fmt::format("{}", so_far.size()), per_ply});
      const std::string stem = file_stem(fmt::format("{}_damage_{}", name, label));
      const Figure f = plot_bond_states(
          state, context.out_dir, stem,
          fmt::format("{}: damage at {} (grip force {:.0f} N)", layup_text, label, force), 0, 0,
          ply_labels);
      out.files.insert(out.files.end(), f.files.begin(), f.files.end());
      maps += figure_markdown(f, fmt::format("damage per ply at {}: broken bonds in tension red, "
                                             "in shear blue",
                                             label)) +
              "\n";
      row("notched", fmt::format("broken bonds at {}", label), dem,
          static_cast<double>(so_far.size()), "1");
    };
    for (double f : fractions) {
      std::size_t k = 1;
      while (k < n_peak && grip_force(n, k) < f * notched_peak_force) ++k;
      add_map(fmt::format("{:g} of peak", f), static_cast<long>(k),
              damage_at(n, static_cast<long>(k)), grip_force(n, k));
    }
    add_map("final", n.events + 1, *n.model, grip_force(n, n.stress.size() - 1));
    out.files.push_back(fs::path("vtu") / fmt::format("{}.pvd", maps_stem));
    for (const std::string& file : maps_series.files()) out.files.push_back(fs::path("vtu") / file);
    maps += fmt::format(
        "ParaView: `vtu/{}.pvd` (these states on the undeformed plate; bond cell "
        "data `state`, `damage`).\n",
        maps_stem);

    std::string& md = out.report_markdown;
    md += fmt::format(
        "The {} {} laminate, {:g} × {:g} mm, {:g} mm plies, {:g} mm particles (strategy {}), with "
        "a central {:g} mm hole (D/W = {:.3f}) and without it, each pulled to failure by the "
        "strength test (uniform grips, events, brittle bonds{}). {} The gross stress is the grip "
        "force over the unnotched plate's cross-section ({:.4g} mm²), the net-section stress "
        "the gross over 1 - D/W.\n\n{}\n\n",
        material.name, layup_text, unnotched.coupon.length / kMm, width / kMm,
        unnotched.coupon.thickness / kMm, d / kMm, unnotched.strategy, hole / kMm, hole / width,
        unnotched.effective_weibull_modulus() > 0
            ? fmt::format(", Weibull scatter m = {:g}, seed {}",
                          unnotched.effective_weibull_modulus(), unnotched.seed)
            : ", no scatter",
        unnotched.interface_strength.given() ? "The interfaces break at the strengths given."
                                             : "The interfaces do not break (no interface "
                                               "strengths given).",
        gross_area / (kMm * kMm), strength_model_note(unnotched));
    md += "## Summary\n\n";
    md += markdown_row({"quantity", "notched", "unnotched", "unit"}) + "|---|--:|--:|---|\n";
    md += markdown_row(
        {"particles", fmt::format("{}", n.particles), fmt::format("{}", u.particles), ""});
    md += markdown_row({"events", fmt::format("{}", n.events), fmt::format("{}", u.events), ""});
    md += markdown_row({"wall time", fmt::format("{:.1f}", n.wall_seconds),
                        fmt::format("{:.1f}", u.wall_seconds), "s"});
    md += markdown_row({"peak grip force", fmt::format("{:.1f}", notched_peak_force),
                        fmt::format("{:.1f}", unnotched_peak_force), "N"});
    md += markdown_row({"strength (gross)", fmt::format("{:.2f}", notched_gross * kMPa),
                        fmt::format("{:.2f}", unnotched_strength * kMPa), "MPa"});
    md += markdown_row(
        {"strength (net section)", fmt::format("{:.2f}", notched_net * kMPa), "–", "MPa"});
    md += markdown_row({"first failure (gross)", fmt::format("{:.2f}", notched_first * kMPa),
                        fmt::format("{:.2f}", unnotched_first * kMPa), "MPa"});
    md += markdown_row({"notched / unnotched strength",
                        fmt::format("{:.3f}", notched_gross / unnotched_strength), "", ""});
    md += fmt::format(
        "\n**First failure against the closed form.** The notched plate first breaks in {} at "
        "{:.2f} mm from the hole's edge ({}), at a gross stress of {:.2f} MPa. Lekhnitskii's "
        "infinite orthotropic plate gives Kt_inf = 1 + sqrt(2 (sqrt(Ex/Ey) - nu_xy) + Ex/Gxy) = "
        "{:.3f} with the laminate's CLT constants (Ex {:.2f} GPa, Ey {:.2f} GPa, nu_xy {:.4f}, "
        "Gxy {:.2f} GPa); Heywood's isotropic finite-width factor (2 + (1 - D/W)^3) / (3 (1 - "
        "D/W)) = {:.4f} makes Kt = {:.3f} (core/stress_concentration.hpp). The unnotched plate's "
        "first failure over Kt, {:.2f} MPa, is the expected first failure at the hole: the DEM is "
        "{} from it (CLT's max-stress first-ply failure over Kt: {:.2f} MPa). The particles "
        "resolve the hole's stress gradient coarsely (D = {:.3g} particle diameters; the edge is "
        "a staircase of the lattice, and the hole's stress gradient decays over about a radius): "
        "the discrete plate concentrates less than the continuum, and its first failure "
        "approaches the closed form as the particles shrink (README, \"Notched strength\").\n\n",
        first_ply >= 0 ? fmt::format("ply {}", first_ply) : std::string("an interface"),
        from_edge / kMm, at_edge ? "at the hole's edge" : "away from the hole's edge",
        notched_first * kMPa, kt_inf, laminate.Ex * 1e-9, laminate.Ey * 1e-9, laminate.nu_xy,
        laminate.Gxy * 1e-9, fwc, kt, predicted_first * kMPa,
        percent_change(notched_first, predicted_first), clt_first / kt * kMPa, hole / d);
    md +=
        figure_markdown(load, "grip force against grip travel, with and without the hole") + "\n\n";
    md +=
        "## Damage maps of the notched plate\n\nAt each chosen fraction of the peak grip force "
        "(the first critical state on the way up that reaches it) and after the last event; "
        "plies side by side, bottom first. Cracks: broken bonds within 1.5 particle diameters "
        "in the same ply (solvers/cracks.hpp).\n\n" +
        map_table + "\n" + maps + "\n";
    md += "## Each plate\n\n" + sections;
    return out;
  }
};

}  // namespace

void register_hole_failure_experiment(ExperimentRegistry& registry) {
  registry.add("hole_failure",
               "the Fig. 16 plate with its hole pulled to failure beside the unnotched plate: "
               "load-displacement, notched strength, first failure against Lekhnitskii's Kt, "
               "damage maps per ply",
               [] { return std::make_unique<HoleFailureExperiment>(); });
}

}  // namespace plydem
