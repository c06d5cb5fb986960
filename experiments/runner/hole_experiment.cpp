// The hole-in-plate experiment kind (`plydem run experiments/hole.toml`, kind `hole`): the plate
// of experiments/runner/hole_plate.hpp solved as particles and by CalculiX, the two displacement
// fields compared on a grid over the plate and on a finer one around the hole.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "core/material.hpp"
#include "experiments/output/vtk_output.hpp"
#include "experiments/runner/experiment.hpp"
#include "experiments/runner/hole_plate.hpp"

namespace plydem {
namespace {

// A `hole` config's settings: the plate's, and the stem that names rows and files.
struct HoleExperimentSettings {
  HolePlateSettings plate;
  std::string stem;
};

HoleExperimentSettings parse_hole(const ExperimentConfig& config,
                                  const ExperimentContext& context) {
  HolePlateSettings s = hole_plate_settings(config, context.quick);
  s.calculix = context.calculix;
  s.force = context.force;
  const std::string stem = config.name().empty() ? std::string("hole") : config.name();
  return {s, stem};
}

// The solved plate in both models and their comparison.
struct HoleResults {
  HolePlateDem dem;
  FemSolution fem;
  ComparisonGrid hole_grid;      ///< the window around the hole
  GridComparison plate, window;  ///< on the plate's grid and the window's
  FieldComparison at_particles;  ///< the FEM sampled at each particle (when it ran)
  double rho = 0;                ///< the moving least squares' radius [m]
};

HoleResults run_hole(const HoleExperimentSettings& settings, const ExperimentContext&) {
  const HolePlateSettings& s = settings.plate;
  HoleResults r;
  r.rho = s.interpolation_radius > 0 ? s.interpolation_radius : 1.5 * s.particle_diameter;
  const double cx = 0.5 * s.length, cy = 0.5 * s.width;
  const double rho = r.rho;
  r.dem = solve_hole_plate_dem(s);
  r.fem = solve_hole_plate_fem(s);
  const HolePlateDem& dem = r.dem;
  const FemSolution& fem = r.fem;
  const int plies = dem.plies;

  // The full plate and a window of 4 D around the hole at half a particle diameter.
  const ComparisonGrid plate_grid{0, s.length, 0, s.width, s.grid_spacing};
  const double half_window = s.hole_diameter > 0 ? 2 * s.hole_diameter : 0.1 * s.width;
  r.hole_grid =
      ComparisonGrid{std::max(0.0, cx - half_window), std::min(s.length, cx + half_window),
                     std::max(0.0, cy - half_window), std::min(s.width, cy + half_window),
                     0.5 * s.particle_diameter};
  if (fem.available) {
    r.plate = compare_on_grid(fem.displacement, dem.model, plies, plate_grid, cx, cy,
                              s.hole_diameter, rho);
    r.window = compare_on_grid(fem.displacement, dem.model, plies, r.hole_grid, cx, cy,
                               s.hole_diameter, rho);
    r.at_particles = compare_displacements(fem.displacement, dem.model.particles,
                                           0.5 * (plies - 1) * dem.model.thickness / plies);
  } else {
    r.plate = sample_dem_on_grid(dem.model, plies, plate_grid, cx, cy, s.hole_diameter, rho);
    r.window = sample_dem_on_grid(dem.model, plies, r.hole_grid, cx, cy, s.hole_diameter, rho);
  }
  return r;
}

// The numbers the rows and the report share.
struct HoleNumbers {
  Material material;
  InPlaneConstants clt;      ///< of the laminate
  double clt_stiffness = 0;  ///< the plate without the hole by CLT [N/m]
  int in_ply_bonds = 0, interface_bonds = 0;
  double max_ux_dem = 0, max_ux_fem = 0;  ///< on the plate's grid [m]
};

HoleNumbers hole_numbers(const HolePlateSettings& s, const HoleResults& r) {
  const HolePlateDem& dem = r.dem;
  const GridComparison& plate = r.plate;
  // Numbers.
  const Material material = load_material(s.material);
  const InPlaneConstants clt = laminate_constants(hole_plate_specimen(s).plies);
  const double clt_stiffness = clt.Ex * s.width * s.thickness / s.length;  // no hole
  int in_ply_bonds = 0;
  for (int c = 0; c < dem.model.bonds.size(); ++c) in_ply_bonds += !dem.model.bonds.is_interface(c);
  const int interface_bonds = dem.model.bonds.size() - in_ply_bonds;
  auto max_abs = [&](const std::vector<Eigen::ArrayXXd>& fields, double shift) {
    double m = 0;
    for (const Eigen::ArrayXXd& a : fields)
      for (Eigen::Index e = 0; e < a.size(); ++e)
        if (!std::isnan(a(e))) m = std::max(m, std::abs(a(e) - shift));
    return m;
  };
  return {material,
          clt,
          clt_stiffness,
          in_ply_bonds,
          interface_bonds,
          max_abs(plate.ux_dem, 0),
          max_abs(plate.ux_fem, 0)};
}

void add_hole_rows(const HoleExperimentSettings& settings, const HoleResults& r,
                   const HoleNumbers& numbers, ExperimentOutput& out) {
  const HolePlateSettings& s = settings.plate;
  const std::string& stem = settings.stem;
  const std::string case_name = fmt::format("{} hole", format_layup(parse_layup(s.layup)));
  const HolePlateDem& dem = r.dem;
  const FemSolution& fem = r.fem;
  const GridComparison &plate = r.plate, &window = r.window;
  const FieldComparison& at_particles = r.at_particles;
  const std::string dem_source = fmt::format("dem {}", s.strategy);
  const std::string cmp_source = fmt::format("dem {} vs calculix", s.strategy);
  auto row = [&](const std::string& quantity, const std::string& source, double value,
                 const std::string& unit) {
    out.rows.push_back({stem, case_name, quantity, source, value, unit});
  };
  row("particles", dem_source, dem.model.particles.size(), "1");
  row("bonds", dem_source, dem.model.bonds.size(), "1");
  row("particles removed by the hole", dem_source, dem.hole.particles, "1");
  row("build time", dem_source, dem.build_seconds, "s");
  row("static solve time", dem_source, dem.solve_seconds, "s");
  row("plate stiffness", dem_source, dem.stiffness * 1e-6, "kN/mm");
  row("plate stiffness", "clt, plate without hole", numbers.clt_stiffness * 1e-6, "kN/mm");
  row("max ux", dem_source, numbers.max_ux_dem * 1e6, "um");
  // uy about its mean: the rigid y translation is pinned differently in the two models.
  if (fem.available) {
    row("plate stiffness", "calculix", fem.reaction_force / fem.end_displacement * 1e-6, "kN/mm");
    row("max ux", "calculix", numbers.max_ux_fem * 1e6, "um");
    row("fem elements", "calculix", fem.elements, "1");
    row("fem degrees of freedom", "calculix", fem.degrees_of_freedom, "1");
    row("calculix time", "calculix", fem.solver_seconds, "s");
    row("ux L2 error", cmp_source, 100 * plate.ux_error, "%");
    row("uy L2 error", cmp_source, 100 * plate.uy_error, "%");
    row("ux L2 error near the hole", cmp_source, 100 * window.ux_error, "%");
    row("uy L2 error near the hole", cmp_source, 100 * window.uy_error, "%");
    row("ux L2 error at the particles", cmp_source, 100 * at_particles.ux_error, "%");
    row("uy L2 error at the particles", cmp_source, 100 * at_particles.uy_error, "%");
  }
}

std::string hole_markdown(const HoleExperimentSettings& settings, const HoleResults& r,
                          const HoleNumbers& numbers, const HolePlateMaps& maps,
                          const ExperimentContext& context) {
  const HolePlateSettings& s = settings.plate;
  const std::string& stem = settings.stem;
  const std::string layup = format_layup(parse_layup(s.layup));
  const HolePlateDem& dem = r.dem;
  const FemSolution& fem = r.fem;
  const GridComparison &plate = r.plate, &window = r.window;
  const FieldComparison& at_particles = r.at_particles;
  const ComparisonGrid& hole_grid = r.hole_grid;
  const int plies = dem.plies;
  const double rho = r.rho;
  std::string md;
  if (context.quick) {
    md +=
        "*Quick run (`--quick`): coarse particles and grids, for a first look; the numbers "
        "below are not the experiment's.*\n\n";
  }
  md += fmt::format(
      "The paper's Sec. 4 / Fig. 16 plate: {} {} (plies of {} mm), {} x {} mm, a {} mm hole "
      "at the centre. The grips move apart by {} mm in total ({} mm each) and prescribe only ux, "
      "so the ends contract freely; the same in both models. DEM: strategy {}, one layer per ply, "
      "particle diameter {} mm, interface bonds {:.3g} / {:.3g} N/m^3 (normal / shear), particles "
      "with their centre inside the hole removed, {}solved statically; its grips are the "
      "particles within {} mm of each ply's outermost centres, each held where the rigid grip face "
      "puts the material at its centre, ux = travel (x / L - 1/2). FEM: CalculiX, {} solid "
      "elements, {} per ply, O-grid around the hole, grips on the end faces.\n\n",
      layup, numbers.material.name, format_mm(s.thickness / plies), format_mm(s.length),
      format_mm(s.width), format_mm(s.hole_diameter), format_mm(s.grip_travel),
      format_mm(0.5 * s.grip_travel), s.strategy, format_mm(s.particle_diameter),
      s.interface.resolved(numbers.material, s.thickness / plies).normal,
      s.interface.resolved(numbers.material, s.thickness / plies).shear,
      s.complete_boundary_cells ? "free edges (the hole's too) completed as boundary cells, " : "",
      format_mm(s.grip_length > 0 ? s.grip_length : 0.6 * s.particle_diameter),
      fem_element_name(s.fem_mesh.element), s.fem_mesh.elements_per_ply);
  md += "| | DEM | FEM (CalculiX) |\n|---|---|---|\n";
  const std::string na = fem.available ? "" : "not run";
  md += fmt::format(
      "| model | {} particles ({} removed by the hole), {} bonds ({} in plies, {} "
      "interface) | {} |\n",
      dem.model.particles.size(), dem.hole.particles, dem.model.bonds.size(), numbers.in_ply_bonds,
      numbers.interface_bonds,
      fem.available ? fmt::format("{} elements, {} nodes, {} degrees of freedom", fem.elements,
                                  fem.nodes, fem.degrees_of_freedom)
                    : na);
  md += fmt::format(
      "| solve time | build {:.2f} s, static solve {:.2f} s ({}, {} free dofs) | {} |\n",
      dem.build_seconds, dem.solve_seconds, dem.solve.method_name, dem.solve.free_dofs,
      fem.available
          ? fmt::format("ccx {:.2f} s (all {:.2f} s)", fem.solver_seconds, fem.wall_seconds)
          : na);
  md += fmt::format("| grip force | {:.2f} N | {} |\n", dem.grip_force,
                    fem.available ? fmt::format("{:.2f} N", fem.reaction_force) : na);
  md += fmt::format(
      "| plate stiffness (force / travel) | {:.3f} kN/mm | {} |\n", dem.stiffness * 1e-6,
      fem.available ? fmt::format("{:.3f} kN/mm", fem.reaction_force / fem.end_displacement * 1e-6)
                    : na);
  md += fmt::format("| max ux on the grid | {:.2f} um | {} |\n", numbers.max_ux_dem * 1e6,
                    fem.available ? fmt::format("{:.2f} um", numbers.max_ux_fem * 1e6) : na);
  md += fmt::format(
      "\nFor scale: the plate without the hole, by CLT (Ex = {:.3f} GPa), would "
      "have a stiffness Ex W h / L = {:.3f} kN/mm.\n\n",
      numbers.clt.Ex * 1e-9, numbers.clt_stiffness * 1e-6);
  if (fem.available) {
    md += fmt::format(
        "Relative L2 errors of the DEM displacement against CalculiX (all plies; uy with the "
        "rigid y translation c = {:.3g} um removed):\n\n"
        "| where | points | ux | uy |\n|---|---|---|---|\n"
        "| plate, grid {} x {} ({:.3g} x {:.3g} mm) | {} | {:.2f}% | {:.2f}% |\n"
        "| near the hole, {} x {} mm, grid {} x {} | {} | {:.2f}% | {:.2f}% |\n"
        "| at the particles | {} | {:.2f}% | {:.2f}% |\n\n",
        plate.uy_shift * 1e6, plate.nx, plate.ny, plate.dx * 1e3, plate.dy * 1e3, plate.points,
        100 * plate.ux_error, 100 * plate.uy_error, format_mm(hole_grid.x_max - hole_grid.x_min),
        format_mm(hole_grid.y_max - hole_grid.y_min), window.nx, window.ny, window.points,
        100 * window.ux_error, 100 * window.uy_error, at_particles.points,
        100 * at_particles.ux_error, 100 * at_particles.uy_error);
    md += fmt::format(
        "How they are compared: a regular grid of cell centres over the plate, points inside the "
        "hole left out. At each point and in each ply the DEM displacement is a moving "
        "least-squares linear fit over the ply's particles within rho = {} mm (weights "
        "(1 - r^2/rho^2)^2; exact for linear fields; 2 rho where fewer than three non-collinear "
        "particles lie within rho, at the plate's edges); the FEM displacement is CalculiX's field "
        "interpolated on that "
        "ply's mid-surface. \"At the particles\" samples the FEM at each particle instead. "
        "Maps show the top ply, the plate's surface as in the paper's Fig. 16.\n\n",
        format_mm(rho));
  } else {
    md += fmt::format("**FEM column not run: {}.** The DEM field is shown alone.\n\n", fem.message);
  }
  md += maps.figure_note;
  for (const std::string& f : maps.figures) md += fmt::format("![{}]({})\n\n", f, f);
  md += fmt::format(
      "ParaView: `{}_particles.vtu` (displacement, ply, group) and `{}_bonds.vtu` "
      "(family, stiffness, force), in the reference configuration.\n",
      stem, stem);
  return md;
}

ExperimentOutput report_hole(const HoleExperimentSettings& settings, const HoleResults& r,
                             const ExperimentContext& context) {
  const HolePlateSettings& s = settings.plate;
  const std::string& stem = settings.stem;
  const std::filesystem::path& out_dir = context.out_dir;
  const std::string layup = format_layup(parse_layup(s.layup));
  const HolePlateDem& dem = r.dem;
  ExperimentOutput output;
  output.title =
      fmt::format("Hole in plate: {} {} x {} x {} mm, {} mm hole", layup, format_mm(s.length),
                  format_mm(s.width), format_mm(s.thickness), format_mm(s.hole_diameter));

  // ParaView files of the solved particle model.
  {
    const std::string particles = fmt::format("{}_particles.vtu", stem);
    const std::string bonds = fmt::format("{}_bonds.vtu", stem);
    VtkOptions vtk;
    vtk.displacement_scale = 0;  // reference configuration; "Warp By Vector" shows the field
    write_particles_vtu(dem.model, (out_dir / particles).string(), vtk);
    write_bonds_vtu(dem.model, (out_dir / bonds).string(), vtk);
    output.files.push_back(particles);
    output.files.push_back(bonds);
  }

  const HolePlateMaps maps =
      write_hole_plate_maps(s, r.plate, r.window, r.fem.available, out_dir, stem);
  output.files.insert(output.files.end(), maps.files.begin(), maps.files.end());
  const HoleNumbers numbers = hole_numbers(s, r);
  add_hole_rows(settings, r, numbers, output);
  output.report_markdown = hole_markdown(settings, r, numbers, maps, context);
  return output;
}

}  // namespace

void register_hole_experiment(ExperimentRegistry& registry) {
  registry.add("hole",
               "hole-in-plate (paper Fig. 16): [0/90/0] plate with a central hole, DEM "
               "displacement field against CalculiX",
               parse_hole, run_hole, report_hole);
}

}  // namespace plydem
