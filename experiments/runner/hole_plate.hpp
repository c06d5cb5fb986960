#pragma once
/// \file
/// The hole-in-plate experiment (paper Sec. 4, Fig. 16): a 60 x 36 x 1.5 mm [0/90/0] E-glass/MY750
/// plate with a central 3 mm hole, pulled by grips at both ends that move apart by 0.1 mm in total
/// (0.05 mm each). The particle model (a laminate of hex2d plies, strategies/laminate.hpp, with the
/// particles inside the hole removed) is solved statically; CalculiX solves the same plate
/// (experiments/fem/calculix.hpp), and the two displacement fields are compared on a common grid.
///
/// Run it with `plydem run experiments/hole.toml` (kind `hole`, experiments/runner/
/// hole_experiment.cpp); the settings and their defaults are spelled out in that file.
///
/// Boundary conditions, the same in both models: the grips prescribe only ux, so the ends contract
/// and shear freely; the rigid modes left are pinned without load. The FEM grips are the end
/// faces, moved by -travel/2 and +travel/2. The DEM grips are the particles whose centres lie
/// within `grip_length` of each ply's outermost centres (0.6 diameters by default: the first
/// column; the plies' lattices differ, so their ends do not line up); a gripped particle stands
/// for material a fraction of a diameter inside the face, and gets the displacement the rigid
/// face gives it there at the nominal strain, ux = travel (x / L - 1/2). Gripping the particles
/// at +-travel/2 instead would load the shorter span between the particle columns, about 2 d / L
/// more strain (measured on the quick run, 1 mm particles: ux L2 error 3.6% instead of 0.9%).
///
/// Comparison (compare_on_grid). A regular grid of cell centres covers the plate, nx x ny with
/// nx = round(L / spacing), ny = round(W / spacing); points inside the hole are left out. At each
/// point and in each ply k the DEM displacement is a moving-least-squares linear fit
/// u = a + b (x - x0) + c (y - y0) over the ply's particles within `interpolation_radius` of the
/// point, weighted by (1 - r^2 / rho^2)^2: it reproduces any linear field exactly, is continuous,
/// and extrapolates by about a particle diameter at most at the free edges and the hole (where
/// fewer than three non-collinear particles lie within rho, at an edge whose last row of particles
/// lies deeper than rho, the fit takes 2 rho). The FEM
/// displacement is interpolated (FemDisplacementField::at) at the same (x, y) on ply k's
/// mid-surface. The relative L2 errors run over all plies' points:
///   ux: |ux_dem - ux_fem| / |ux_fem|;
///   uy: |uy_dem - uy_fem - c| / |uy_fem - mean(uy_fem)|, c = mean(uy_dem - uy_fem),
/// the rigid translation along y (which the two models pin at different points) removed, as
/// compare_displacements does at the particles.

#include <Eigen/Dense>
#include <filesystem>
#include <string>
#include <vector>

#include "experiments/fem/calculix.hpp"
#include "experiments/protocols/plate_hole.hpp"
#include "experiments/runner/experiment.hpp"
#include "solvers/static_solver.hpp"
#include "strategies/laminate.hpp"

namespace plydem {

/// Everything the hole-in-plate experiment needs, in SI units. Defaults are the paper's plate.
struct HolePlateSettings {
  std::string material = "eglass-my750";  ///< a name or a TOML file (core/material.hpp)
  std::string layup = "[0/90/0]";  ///< bottom ply first (strategies/laminate.hpp parse_layup)
  double length = 60e-3;           ///< L, along x [m]
  double width = 36e-3;            ///< W, along y [m]
  double thickness = 1.5e-3;       ///< laminate thickness h; every ply h / n [m]
  double hole_diameter = 3e-3;     ///< D, centred at (L/2, W/2) [m]
  double grip_travel = 0.1e-3;     ///< how far the grips move apart in total [m]

  // The particle model.
  std::string strategy = "hex2d";     ///< hex2d or square (one layer per ply)
  double particle_diameter = 0.5e-3;  ///< [m]
  double grip_length = 0;             ///< [m]; 0 = half a particle diameter (one column)
  /// Between plies: the paper's 1e14 / 1e13 N/m^3, not the library's 10 E2/t, 10 G12/t. An
  /// interface bond with a lateral offset a is sheared by a membrane strain, which adds about
  /// K_s a^2 / h per interface to the plate's modulus: a ~ d/2 here is large against the 0.5 mm
  /// plies (measured at d = 1 mm with the library's default: the plate 35% too stiff).
  InterfaceStiffness interface { 1e14, 1e13 };
  /// Let bonds at free edges, the hole's included, carry the share of their missing partners
  /// (strategies/boundary_cells.hpp); applied after the hole is cut.
  bool complete_boundary_cells = true;

  // The FEM reference.
  FemMeshSettings fem_mesh;  ///< C3D8I, one element per ply, automatic sizes by default
  int fem_threads = 1;       ///< for ccx
  std::string calculix = "ccx";
  /// Build even when the plate's memory estimate exceeds the machine's available memory
  /// (experiments/protocols/resource_estimate.hpp).
  bool force = false;

  // The comparison.
  double grid_spacing = 0.5e-3;     ///< [m]
  double interpolation_radius = 0;  ///< rho [m]; 0 = 1.5 particle diameters

  /// Throws plydem::Error naming the first bad setting.
  void validate() const;
};

/// The solved particle model of the plate.
struct HolePlateDem {
  Model model;  ///< laminate with the hole cut, solved: displacements set
  HoleRemoval hole;
  int plies = 0;
  int grip_particles = 0;  ///< both grips
  StaticResult solve;
  /// The x-force the grips carry, 0.5 (R_right - R_left) from the reactions [N].
  double grip_force = 0;
  /// grip_force / grip_travel [N/m].
  double stiffness = 0;
  double build_seconds = 0;  ///< building, calibrating, cutting the hole
  double solve_seconds = 0;  ///< the static solve
};

/// Builds the laminate with `settings.strategy`, cuts the hole, grips both ends and solves the
/// static problem. Throws plydem::Error for bad settings or a failed solve.
HolePlateDem solve_hole_plate_dem(const HolePlateSettings& settings);

/// The FEM plate: the same plies (laminate_plies), size and hole.
FemSpecimen hole_plate_specimen(const HolePlateSettings& settings);

/// Runs CalculiX on hole_plate_specimen with the grips moved apart by grip_travel. A missing ccx
/// comes back with available = false (experiments/fem/calculix.hpp run_calculix).
FemSolution solve_hole_plate_fem(const HolePlateSettings& settings);

/// A rectangle of the plate sampled on a regular grid of cell centres.
struct ComparisonGrid {
  double x_min = 0, x_max = 0, y_min = 0, y_max = 0;  ///< [m]
  double spacing = 0;  ///< target spacing [m]; nx = max(1, round((x_max - x_min) / spacing))
};

/// Both fields on the comparison grid. Values are NaN where a point is not compared (inside the
/// hole, or where one of the fields is undefined).
struct GridComparison {
  ComparisonGrid grid;
  int nx = 0, ny = 0;
  double dx = 0, dy = 0;  ///< point (i, j) sits at (x_min + (i + 1/2) dx, y_min + (j + 1/2) dy)
  int plies = 0;
  /// Per ply k (bottom first): (i, j) arrays [m], i along x.
  std::vector<Eigen::ArrayXXd> ux_dem, uy_dem, ux_fem, uy_fem;
  int points = 0;       ///< compared (point, ply) pairs
  int skipped = 0;      ///< (point, ply) pairs outside the hole where a field was undefined
  double ux_error = 0;  ///< relative L2 error of ux (file comment)
  double uy_error = 0;  ///< relative L2 error of uy, rigid y translation removed
  /// c = mean(uy_dem - uy_fem), the rigid y translation removed from uy [m].
  double uy_shift = 0;
};

/// Samples the solved particle model (`plies` plies, ply k at z = k t as build_laminate puts it)
/// and the FEM field on `grid` (file comment): DEM ply k against the FEM on that ply's
/// mid-surface. Points inside the hole (centre, diameter; diameter 0 = none) are left out.
/// `interpolation_radius` is rho of the moving least squares. Throws plydem::Error if the FEM
/// field is empty, the grid or the radius is not positive, or fewer than 2 points are compared.
GridComparison compare_on_grid(const FemDisplacementField& fem, const Model& dem, int plies,
                               const ComparisonGrid& grid, double hole_centre_x,
                               double hole_centre_y, double hole_diameter,
                               double interpolation_radius);

/// The settings of a config of kind `hole` (experiments/hole.toml); `quick` takes the [quick]
/// sizes. Throws plydem::Error naming an unknown key or a bad value.
HolePlateSettings hole_plate_settings(const ExperimentConfig& config, bool quick);

/// The DEM field alone sampled on `grid` as compare_on_grid samples it (the FEM arrays NaN, no
/// errors computed): the maps of a run without CalculiX.
GridComparison sample_dem_on_grid(const Model& dem, int plies, const ComparisonGrid& grid,
                                  double hole_centre_x, double hole_centre_y, double hole_diameter,
                                  double interpolation_radius);

/// What write_hole_plate_maps wrote, relative to the output folder.
struct HolePlateMaps {
  std::vector<std::filesystem::path> files;  ///< the map data, then each PNG and its .gp
  std::vector<std::string> figures;          ///< the PNGs
  std::string figure_note;                   ///< why no figure was drawn (gnuplot missing), or ""
};

/// The top ply's displacement maps of the plate and of the window around the hole (`plate`,
/// `window`; with_fem: beside CalculiX's, and DEM - FEM): STEM_plate_map.dat, STEM_hole_map.dat
/// and, where gnuplot is installed, STEM_ux.png, STEM_uy.png, STEM_difference.png with their
/// gnuplot scripts, in `out_dir`. Throws plydem::Error if a file cannot be written.
HolePlateMaps write_hole_plate_maps(const HolePlateSettings& settings, const GridComparison& plate,
                                    const GridComparison& window, bool with_fem,
                                    const std::filesystem::path& out_dir, const std::string& stem);

/// A length for the report: metres as millimetres, rounded to the micrometre ("1.5").
std::string format_mm(double metres);

}  // namespace plydem
