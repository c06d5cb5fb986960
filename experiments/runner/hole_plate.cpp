#include "experiments/runner/hole_plate.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <limits>
#include <numeric>

#include "core/error.hpp"
#include "core/material.hpp"
#include "core/stopwatch.hpp"
#include "experiments/output/external_tool.hpp"
#include "experiments/output/vtk_output.hpp"
#include "experiments/protocols/plate_hole.hpp"
#include "experiments/protocols/resource_estimate.hpp"
#include "strategies/boundary_cells.hpp"
#include "strategies/registry.hpp"

namespace plydem {
namespace {

using Clock = Stopwatch::Clock;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Points of one ply, bucketed for the moving-least-squares interpolation.
class PlyInterpolator {
 public:
  PlyInterpolator(const Particles& p, int ply, double radius) : p_(p), radius_(radius) {
    for (int i = 0; i < p.size(); ++i)
      if (p.ply(i) == ply) index_.push_back(i);
    require(!index_.empty(), fmt::format("ply {} of the particle model is empty", ply + 1));
    x0_ = y0_ = std::numeric_limits<double>::max();
    double x1 = -x0_, y1 = -y0_;
    for (int i : index_) {
      x0_ = std::min(x0_, p.reference_position(i, 0));
      y0_ = std::min(y0_, p.reference_position(i, 1));
      x1 = std::max(x1, p.reference_position(i, 0));
      y1 = std::max(y1, p.reference_position(i, 1));
    }
    nx_ = static_cast<int>((x1 - x0_) / radius_) + 1;
    ny_ = static_cast<int>((y1 - y0_) / radius_) + 1;
    cells_.assign(static_cast<size_t>(nx_) * ny_, {});
    for (int i : index_) {
      const int cx = static_cast<int>((p.reference_position(i, 0) - x0_) / radius_);
      const int cy = static_cast<int>((p.reference_position(i, 1) - y0_) / radius_);
      cells_[static_cast<size_t>(cy) * nx_ + cx].push_back(i);
    }
  }

  // Weighted linear least squares u = a + b dx + c dy around (x, y) within the radius, or within
  // twice the radius where fewer than three particles or only collinear ones lie within it (a
  // plate edge whose last row of particles lies more than a radius inside); nullopt if neither
  // works.
  std::optional<Eigen::Vector2d> at(double x, double y) const {
    if (std::optional<Eigen::Vector2d> u = fit(x, y, radius_)) return u;
    return fit(x, y, 2 * radius_);
  }

 private:
  std::optional<Eigen::Vector2d> fit(double x, double y, double rho) const {
    const int reach = static_cast<int>(std::ceil(rho / radius_));
    const int cx = static_cast<int>(std::floor((x - x0_) / radius_));
    const int cy = static_cast<int>(std::floor((y - y0_) / radius_));
    Eigen::Matrix3d a = Eigen::Matrix3d::Zero();
    Eigen::Matrix<double, 3, 2> b = Eigen::Matrix<double, 3, 2>::Zero();
    int count = 0;
    for (int j = std::max(cy - reach, 0); j <= std::min(cy + reach, ny_ - 1); ++j) {
      for (int i = std::max(cx - reach, 0); i <= std::min(cx + reach, nx_ - 1); ++i) {
        for (int q : cells_[static_cast<size_t>(j) * nx_ + i]) {
          const double dx = (p_.reference_position(q, 0) - x) / rho;
          const double dy = (p_.reference_position(q, 1) - y) / rho;
          const double r2 = dx * dx + dy * dy;
          if (r2 >= 1) continue;
          const double w = (1 - r2) * (1 - r2);
          const Eigen::Vector3d basis(1, dx, dy);
          a += w * basis * basis.transpose();
          b.col(0) += w * basis * p_.displacement(q, 0);
          b.col(1) += w * basis * p_.displacement(q, 1);
          ++count;
        }
      }
    }
    if (count < 3) return std::nullopt;
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(a, Eigen::EigenvaluesOnly);
    if (eigen.eigenvalues()(0) <= 1e-3 * eigen.eigenvalues()(2)) return std::nullopt;
    const Eigen::Matrix<double, 3, 2> coefficients = a.ldlt().solve(b);
    return Eigen::Vector2d(coefficients(0, 0), coefficients(0, 1));
  }

  const Particles& p_;
  double radius_;
  std::vector<int> index_;
  double x0_ = 0, y0_ = 0;
  int nx_ = 0, ny_ = 0;
  std::vector<std::vector<int>> cells_;
};

// The grid sampling shared by compare_on_grid and the DEM-only maps (fem == nullptr).
GridComparison sample_grid(const FemDisplacementField* fem, const Model& dem, int plies,
                           const ComparisonGrid& grid, double hole_x, double hole_y,
                           double hole_diameter, double interpolation_radius) {
  require(plies >= 1, "the particle model needs at least one ply");
  require(std::isfinite(grid.spacing) && grid.spacing > 0,
          fmt::format("the comparison grid spacing must be positive, got {} m", grid.spacing));
  require(std::isfinite(grid.x_min) && std::isfinite(grid.x_max) && grid.x_max > grid.x_min &&
              std::isfinite(grid.y_min) && std::isfinite(grid.y_max) && grid.y_max > grid.y_min,
          "the comparison grid must be a rectangle of positive size");
  require(std::isfinite(interpolation_radius) && interpolation_radius > 0,
          fmt::format("the interpolation radius must be positive, got {} m", interpolation_radius));
  require(std::isfinite(hole_diameter) && hole_diameter >= 0, "hole diameter must be >= 0");
  GridComparison out;
  out.grid = grid;
  out.plies = plies;
  out.nx = std::max(1, static_cast<int>(std::lround((grid.x_max - grid.x_min) / grid.spacing)));
  out.ny = std::max(1, static_cast<int>(std::lround((grid.y_max - grid.y_min) / grid.spacing)));
  out.dx = (grid.x_max - grid.x_min) / out.nx;
  out.dy = (grid.y_max - grid.y_min) / out.ny;
  const double ply_thickness = dem.thickness / plies;
  const double hole_r2 = 0.25 * hole_diameter * hole_diameter;
  for (int k = 0; k < plies; ++k) {
    const PlyInterpolator dem_ply(dem.particles, k, interpolation_radius);
    // The FEM's ply k mid-surface: plies stacked from z = -h/2 (experiments/fem/calculix.hpp).
    const double z = -0.5 * dem.thickness + (k + 0.5) * ply_thickness;
    Eigen::ArrayXXd ux_d = Eigen::ArrayXXd::Constant(out.nx, out.ny, kNaN);
    Eigen::ArrayXXd uy_d = ux_d, ux_f = ux_d, uy_f = ux_d;
    for (int j = 0; j < out.ny; ++j) {
      for (int i = 0; i < out.nx; ++i) {
        const double x = grid.x_min + (i + 0.5) * out.dx;
        const double y = grid.y_min + (j + 0.5) * out.dy;
        const double r2 = (x - hole_x) * (x - hole_x) + (y - hole_y) * (y - hole_y);
        if (r2 < hole_r2) continue;
        const std::optional<Eigen::Vector2d> d = dem_ply.at(x, y);
        std::optional<Eigen::Vector3d> f;
        if (fem) f = fem->at(x, y, z);
        if (!d || (fem && !f)) {
          ++out.skipped;
          continue;
        }
        ux_d(i, j) = d->x();
        uy_d(i, j) = d->y();
        if (f) {
          ux_f(i, j) = f->x();
          uy_f(i, j) = f->y();
        }
        ++out.points;
      }
    }
    out.ux_dem.push_back(std::move(ux_d));
    out.uy_dem.push_back(std::move(uy_d));
    out.ux_fem.push_back(std::move(ux_f));
    out.uy_fem.push_back(std::move(uy_f));
  }
  return out;
}

}  // namespace

std::string format_mm(double metres) {
  return fmt::format("{:g}", std::round(metres * 1e6) / 1e3);
}

void HolePlateSettings::validate() const {
  const std::pair<const char*, double> sizes[] = {{"plate length", length},
                                                  {"plate width", width},
                                                  {"plate thickness", thickness},
                                                  {"grip travel", grip_travel},
                                                  {"particle diameter", particle_diameter},
                                                  {"comparison grid spacing", grid_spacing}};
  for (const auto& [name, value] : sizes) {
    require(std::isfinite(value) && value > 0,
            fmt::format("{} must be positive, got {} mm", name, value * 1e3));
  }
  require(std::isfinite(hole_diameter) && hole_diameter >= 0,
          fmt::format("hole diameter must be >= 0, got {} mm", hole_diameter * 1e3));
  require(hole_diameter < width && hole_diameter < length,
          fmt::format("a {} mm hole does not fit in a {} x {} mm plate", hole_diameter * 1e3,
                      length * 1e3, width * 1e3));
  require(grip_travel < 0.05 * length,
          fmt::format("grip travel {} mm is beyond a small-strain model's reach for a {} mm plate",
                      grip_travel * 1e3, length * 1e3));
  require(std::isfinite(grip_length) && grip_length >= 0 && 2 * grip_length < length,
          fmt::format("grip length must lie in [0, L/2), got {} mm", grip_length * 1e3));
  require(std::isfinite(interpolation_radius) && interpolation_radius >= 0,
          "interpolation radius must be >= 0 (0 = 1.5 particle diameters)");
  require(fem_threads >= 1, "fem threads must be >= 1");
  hole_boundary_completion(*default_registry().create(strategy), strategy);
  interface.validate();
  fem_mesh.validate();
  parse_layup(layup);
}

FemSpecimen hole_plate_specimen(const HolePlateSettings& settings) {
  settings.validate();
  LaminateSpec spec;
  spec.coupon.material = load_material(settings.material);
  spec.ply_angles = parse_layup(settings.layup);
  spec.coupon.thickness = settings.thickness / static_cast<double>(spec.ply_angles.size());
  return FemSpecimen{laminate_plies(spec), settings.length, settings.width, settings.hole_diameter};
}

HolePlateDem solve_hole_plate_dem(const HolePlateSettings& settings) {
  settings.validate();
  const auto start = Clock::now();
  LaminateSpec spec;
  spec.coupon.material = load_material(settings.material);
  spec.ply_angles = parse_layup(settings.layup);
  spec.coupon.length = settings.length;
  spec.coupon.width = settings.width;
  spec.coupon.thickness = settings.thickness / static_cast<double>(spec.ply_angles.size());
  spec.coupon.particle_diameter = settings.particle_diameter;
  // Completed below, once the hole's edge exists.
  spec.coupon.complete_boundary_cells = false;
  spec.interface = settings.interface;
  const std::unique_ptr<Strategy> strategy = default_registry().create(settings.strategy);

  HolePlateDem dem;
  dem.plies = static_cast<int>(spec.ply_angles.size());
  const BoundaryCompletion completion = hole_boundary_completion(*strategy, settings.strategy);
  // The plate (hole included: an upper bound), its solved copy and one static solve.
  check_resources(estimate_resources(*strategy, spec.coupon, spec.ply_angles, spec.interface,
                                     SolverUse::kStatic, 2),
                  settings.force, "--force");
  dem.model = build_laminate(*strategy, spec).model;
  if (settings.hole_diameter > 0) {
    dem.hole =
        remove_hole(dem.model, 0.5 * settings.length, 0.5 * settings.width, settings.hole_diameter);
  }
  Particles& p = dem.model.particles;
  if (settings.complete_boundary_cells) complete_ply_boundary_cells(dem.model, completion);

  // Grips: per ply, the particles within grip_length of that ply's outermost centres (the plies'
  // lattices differ, so their last columns do not line up).
  const double grip =
      settings.grip_length > 0 ? settings.grip_length : 0.6 * settings.particle_diameter;
  std::vector<double> x_min(dem.plies, std::numeric_limits<double>::max());
  std::vector<double> x_max(dem.plies, -std::numeric_limits<double>::max());
  for (int i = 0; i < p.size(); ++i) {
    x_min[p.ply(i)] = std::min(x_min[p.ply(i)], p.reference_position(i, 0));
    x_max[p.ply(i)] = std::max(x_max[p.ply(i)], p.reference_position(i, 0));
  }
  DofConstraints constraints(p.size());
  int left = 0, right = 0;
  for (int i = 0; i < p.size(); ++i) {
    const double x = p.reference_position(i, 0);
    // The grip faces of the plate are x = 0 and x = L; a gripped particle stands for the material
    // around its centre, a fraction of a diameter inside, which the rigid faces move by the
    // nominal strain: ux = travel (x / L - 1/2).
    const double ux = settings.grip_travel * (x / settings.length - 0.5);
    if (x <= x_min[p.ply(i)] + grip) {
      p.group(i) = static_cast<int>(BoundaryGroup::kLeftGrip);
      ++left;
    } else if (x >= x_max[p.ply(i)] - grip) {
      p.group(i) = static_cast<int>(BoundaryGroup::kRightGrip);
      ++right;
    } else {
      p.group(i) = static_cast<int>(BoundaryGroup::kFree);
      continue;
    }
    // Free grips (FEM_NOTES): ux only in plane; the plate stays flat at its ends.
    constraints.fix(i, Dof::kUx, ux);
    constraints.fix(i, Dof::kUz);
    constraints.fix(i, Dof::kThetaX);
    constraints.fix(i, Dof::kThetaY);
  }
  require(left > 0 && right > 0, "a grip of the hole plate holds no particle");
  dem.grip_particles = left + right;
  dem.build_seconds = seconds_since(start);

  const auto solve_start = Clock::now();
  StaticSettings static_settings;
  static_settings.pin_rigid_modes = true;
  dem.solve = solve_static(dem.model, constraints, static_settings);
  dem.solve_seconds = seconds_since(solve_start);
  double left_force = 0, right_force = 0;
  for (int i = 0; i < p.size(); ++i) {
    if (p.group(i) == static_cast<int>(BoundaryGroup::kLeftGrip))
      left_force += dem.solve.reaction(i, 0);
    if (p.group(i) == static_cast<int>(BoundaryGroup::kRightGrip))
      right_force += dem.solve.reaction(i, 0);
  }
  dem.grip_force = 0.5 * (right_force - left_force);
  dem.stiffness = dem.grip_force / settings.grip_travel;
  return dem;
}

FemSolution solve_hole_plate_fem(const HolePlateSettings& settings) {
  const FemSpecimen plate = hole_plate_specimen(settings);
  FemSettings fem;
  fem.mesh = settings.fem_mesh;
  fem.loading.end_displacement = settings.grip_travel;
  fem.loading.grips = GripCondition::kFree;
  fem.executable = settings.calculix;
  fem.threads = settings.fem_threads;
  return run_calculix(plate, fem);
}

GridComparison compare_on_grid(const FemDisplacementField& fem, const Model& dem, int plies,
                               const ComparisonGrid& grid, double hole_centre_x,
                               double hole_centre_y, double hole_diameter,
                               double interpolation_radius) {
  require(!fem.empty(), "the FEM displacement field is empty");
  GridComparison out = sample_grid(&fem, dem, plies, grid, hole_centre_x, hole_centre_y,
                                   hole_diameter, interpolation_radius);
  require(out.points >= 2,
          fmt::format("only {} grid points lie in both the particle model and the FEM plate",
                      out.points));
  double shift = 0, fem_mean = 0;
  for (int k = 0; k < plies; ++k) {
    const Eigen::ArrayXXd& d = out.uy_dem[k];
    const Eigen::ArrayXXd& f = out.uy_fem[k];
    for (Eigen::Index e = 0; e < d.size(); ++e) {
      if (std::isnan(d(e))) continue;
      shift += d(e) - f(e);
      fem_mean += f(e);
    }
  }
  shift /= out.points;
  fem_mean /= out.points;
  double ux_diff = 0, ux_norm = 0, uy_diff = 0, uy_norm = 0;
  for (int k = 0; k < plies; ++k) {
    for (Eigen::Index e = 0; e < out.ux_dem[k].size(); ++e) {
      if (std::isnan(out.ux_dem[k](e))) continue;
      ux_diff += std::pow(out.ux_dem[k](e) - out.ux_fem[k](e), 2);
      ux_norm += std::pow(out.ux_fem[k](e), 2);
      uy_diff += std::pow(out.uy_dem[k](e) - out.uy_fem[k](e) - shift, 2);
      uy_norm += std::pow(out.uy_fem[k](e) - fem_mean, 2);
    }
  }
  require(ux_norm > 0 && uy_norm > 0, "the FEM displacement field is zero on the grid");
  out.ux_error = std::sqrt(ux_diff / ux_norm);
  out.uy_error = std::sqrt(uy_diff / uy_norm);
  out.uy_shift = shift;
  return out;
}

HolePlateSettings hole_plate_settings(const ExperimentConfig& config, bool quick) {
  config.require_known_keys({"experiment",
                             "description",
                             "material",
                             "layup",
                             "length_mm",
                             "width_mm",
                             "thickness_mm",
                             "hole_diameter_mm",
                             "grip_travel_mm",
                             "dem.strategy",
                             "dem.particle_diameter_mm",
                             "dem.grip_length_mm",
                             "dem.interface_normal_n_per_m3",
                             "dem.interface_shear_n_per_m3",
                             "dem.complete_boundary_cells",
                             "fem.element",
                             "fem.elements_per_ply",
                             "fem.element_mm",
                             "fem.hole_element_mm",
                             "fem.threads",
                             "compare.grid_spacing_mm",
                             "compare.interpolation_radius_mm",
                             "quick.particle_diameter_mm",
                             "quick.grid_spacing_mm",
                             "quick.interface_normal_n_per_m3",
                             "quick.interface_shear_n_per_m3",
                             "quick.fem_element_mm",
                             "quick.fem_hole_element_mm"});
  HolePlateSettings s;
  s.material = config.string("material", s.material);
  s.layup = config.string("layup", s.layup);
  s.length = config.number("length_mm", s.length * 1e3) * 1e-3;
  s.width = config.number("width_mm", s.width * 1e3) * 1e-3;
  s.thickness = config.number("thickness_mm", s.thickness * 1e3) * 1e-3;
  s.hole_diameter = config.number("hole_diameter_mm", s.hole_diameter * 1e3) * 1e-3;
  s.grip_travel = config.number("grip_travel_mm", s.grip_travel * 1e3) * 1e-3;
  s.strategy = config.string("dem.strategy", s.strategy);
  s.particle_diameter = config.number("dem.particle_diameter_mm", s.particle_diameter * 1e3) * 1e-3;
  s.grip_length = config.number("dem.grip_length_mm", 0) * 1e-3;
  s.interface.normal = config.number("dem.interface_normal_n_per_m3", 1e14);
  s.interface.shear = config.number("dem.interface_shear_n_per_m3", 1e13);
  s.complete_boundary_cells = config.boolean("dem.complete_boundary_cells", true);
  const std::string element = config.string("fem.element", "C3D8I");
  if (element == "C3D8I") {
    s.fem_mesh.element = FemElement::kC3D8I;
  } else if (element == "C3D20R") {
    s.fem_mesh.element = FemElement::kC3D20R;
  } else {
    throw Error(fmt::format("{}: fem.element must be \"C3D8I\" or \"C3D20R\", got \"{}\"",
                            config.path().string(), element));
  }
  s.fem_mesh.elements_per_ply = static_cast<int>(config.integer("fem.elements_per_ply", 1));
  s.fem_mesh.element_size = config.number("fem.element_mm", 0) * 1e-3;
  s.fem_mesh.hole_element_size = config.number("fem.hole_element_mm", 0) * 1e-3;
  s.fem_threads = static_cast<int>(config.integer("fem.threads", 1));
  s.grid_spacing = config.number("compare.grid_spacing_mm", s.grid_spacing * 1e3) * 1e-3;
  s.interpolation_radius = config.number("compare.interpolation_radius_mm", 0) * 1e-3;
  if (quick) {
    s.particle_diameter = config.number("quick.particle_diameter_mm", 1.0) * 1e-3;
    s.grid_spacing = config.number("quick.grid_spacing_mm", 1.0) * 1e-3;
    s.interface.normal = config.number("quick.interface_normal_n_per_m3", 1e13);
    s.interface.shear = config.number("quick.interface_shear_n_per_m3", 1e12);
    s.fem_mesh.element_size = config.number("quick.fem_element_mm", 0) * 1e-3;
    s.fem_mesh.hole_element_size = config.number("quick.fem_hole_element_mm", 0) * 1e-3;
  }
  s.validate();
  return s;
}

namespace {

// The maps' data: the top ply (the plate's surface, as the paper's Fig. 16) of a grid, in mm and
// micrometres, one line per point, a blank line after each row of constant y (gnuplot "with
// image"). uy of the DEM is shifted by -c (the rigid y translation) so that both maps share a
// colour scale. NaN marks points not compared (the hole).
void write_map_data(const std::filesystem::path& path, const GridComparison& g, bool with_fem) {
  std::ofstream out(path);
  out << "# x [mm]  y [mm]  ux_dem  ux_fem  uy_dem - c  uy_fem  ux_dem - ux_fem  "
         "uy_dem - c - uy_fem  [um], top ply\n";
  const int k = g.plies - 1;
  auto um = [](double v) {
    return std::isnan(v) ? std::string("NaN") : fmt::format("{:.6g}", v * 1e6);
  };
  for (int j = 0; j < g.ny; ++j) {
    for (int i = 0; i < g.nx; ++i) {
      const double x = g.grid.x_min + (i + 0.5) * g.dx, y = g.grid.y_min + (j + 0.5) * g.dy;
      const double ux_d = g.ux_dem[k](i, j), uy_d = g.uy_dem[k](i, j) - g.uy_shift;
      const double ux_f = with_fem ? g.ux_fem[k](i, j) : kNaN;
      const double uy_f = with_fem ? g.uy_fem[k](i, j) : kNaN;
      out << fmt::format("{:.6g} {:.6g} {} {} {} {} {} {}\n", x * 1e3, y * 1e3, um(ux_d), um(ux_f),
                         um(uy_d), um(uy_f), um(ux_d - ux_f), um(uy_d - uy_f));
    }
    out << "\n";
  }
  if (!out) throw Error(fmt::format("cannot write {}", path.string()));
}

// [min, max] over the finite values of the arrays, in micrometres, widened if flat.
std::pair<double, double> range_um(const std::vector<const Eigen::ArrayXXd*>& arrays,
                                   double shift = 0) {
  double lo = std::numeric_limits<double>::max(), hi = -lo;
  for (const Eigen::ArrayXXd* a : arrays) {
    for (Eigen::Index e = 0; e < a->size(); ++e) {
      const double v = (*a)(e);
      if (std::isnan(v)) continue;
      lo = std::min(lo, (v - shift) * 1e6);
      hi = std::max(hi, (v - shift) * 1e6);
    }
  }
  if (!(hi > lo)) {
    lo -= 1;
    hi += 1;
  }
  return {lo, hi};
}

struct MapPanel {
  std::string data;  // file
  int column = 3;    // gnuplot column
  std::string title;
  std::pair<double, double> range;
  const GridComparison* grid = nullptr;
};

std::string map_script(const std::string& png, const std::vector<MapPanel>& panels, int rows,
                       int columns, double hole_x_mm, double hole_y_mm, double hole_d_mm) {
  std::string s = fmt::format(
      "# Drawn by plydem (experiments/runner/hole_plate.cpp); rerun with: gnuplot <this file>\n"
      "set terminal pngcairo size {},{} font \",10\"\n"
      "set output '{}'\n"
      "set multiplot layout {},{}\n"
      "set size ratio -1\n"
      "set palette rgb 33,13,10\n"
      "set xlabel 'x [mm]'\nset ylabel 'y [mm]'\nset cblabel '[um]'\n"
      "set tics out\n",
      640 * columns, 420 * rows, png, rows, columns);
  if (hole_d_mm > 0) {
    s += fmt::format(
        "set object 1 circle at {:.6g},{:.6g} size {:.6g} fs empty border lc rgb 'black' "
        "front\n",
        hole_x_mm, hole_y_mm, 0.5 * hole_d_mm);
  }
  for (const MapPanel& p : panels) {
    const GridComparison& g = *p.grid;
    s += fmt::format(
        "set title '{}'\nset xrange [{:.6g}:{:.6g}]\nset yrange [{:.6g}:{:.6g}]\n"
        "set cbrange [{:.6g}:{:.6g}]\nplot '{}' using 1:2:{} with image notitle\n",
        p.title, g.grid.x_min * 1e3, g.grid.x_max * 1e3, g.grid.y_min * 1e3, g.grid.y_max * 1e3,
        p.range.first, p.range.second, p.data, p.column);
  }
  return s + "unset multiplot\n";
}

}  // namespace

GridComparison sample_dem_on_grid(const Model& dem, int plies, const ComparisonGrid& grid,
                                  double hole_centre_x, double hole_centre_y, double hole_diameter,
                                  double interpolation_radius) {
  return sample_grid(nullptr, dem, plies, grid, hole_centre_x, hole_centre_y, hole_diameter,
                     interpolation_radius);
}

HolePlateMaps write_hole_plate_maps(const HolePlateSettings& s, const GridComparison& plate,
                                    const GridComparison& window, bool with_fem,
                                    const std::filesystem::path& out_dir, const std::string& stem) {
  HolePlateMaps maps;
  const int plies = plate.plies;
  const double cx = 0.5 * s.length, cy = 0.5 * s.width;
  // Maps: DEM beside FEM, one colour scale per row.
  const std::string plate_data = fmt::format("{}_plate_map.dat", stem);
  const std::string window_data = fmt::format("{}_hole_map.dat", stem);
  write_map_data(out_dir / plate_data, plate, with_fem);
  write_map_data(out_dir / window_data, window, with_fem);
  maps.files.push_back(plate_data);
  maps.files.push_back(window_data);
  const GnuplotAvailability gnuplot = gnuplot_availability();
  if (gnuplot.available) {
    const int top = plies - 1;
    const std::string dem_title = fmt::format("DEM ({}), top ply", s.strategy);
    const std::string fem_title = "FEM (CalculiX), top ply";
    for (const char* component : {"ux", "uy"}) {
      const bool is_ux = component[1] == 'x';
      const int dem_col = is_ux ? 3 : 5, fem_col = is_ux ? 4 : 6;
      std::vector<MapPanel> panels;
      for (const GridComparison* g : {&plate, &window}) {
        const Eigen::ArrayXXd& d = is_ux ? g->ux_dem[top] : g->uy_dem[top];
        const Eigen::ArrayXXd& f = is_ux ? g->ux_fem[top] : g->uy_fem[top];
        const double shift = is_ux ? 0.0 : g->uy_shift;
        std::pair<double, double> range = range_um({&d}, shift);
        if (with_fem) {
          const std::pair<double, double> fr = range_um({&f});
          range = {std::min(range.first, fr.first), std::max(range.second, fr.second)};
        }
        const std::string data = g == &plate ? plate_data : window_data;
        const std::string where = g == &plate ? "" : ", near the hole";
        panels.push_back({data, dem_col,
                          fmt::format("{}: {}{}{}", component, dem_title, where,
                                      is_ux ? "" : " (rigid y shift removed)"),
                          range, g});
        if (with_fem) {
          panels.push_back(
              {data, fem_col, fmt::format("{}: {}{}", component, fem_title, where), range, g});
        }
      }
      const std::string png = fmt::format("{}_{}.png", stem, component);
      run_gnuplot(
          map_script(png, panels, 2, with_fem ? 2 : 1, cx * 1e3, cy * 1e3, s.hole_diameter * 1e3),
          out_dir, fmt::format("{}_{}.gp", stem, component));
      maps.figures.push_back(png);
    }
    if (with_fem) {
      std::vector<MapPanel> panels;
      for (const char* component : {"ux", "uy"}) {
        const bool is_ux = component[1] == 'x';
        Eigen::ArrayXXd diff =
            is_ux ? Eigen::ArrayXXd(plate.ux_dem[top] - plate.ux_fem[top])
                  : Eigen::ArrayXXd(plate.uy_dem[top] - plate.uy_fem[top] - plate.uy_shift);
        const std::pair<double, double> r = range_um({&diff});
        const double m = std::max(std::abs(r.first), std::abs(r.second));
        panels.push_back({plate_data,
                          is_ux ? 7 : 8,
                          fmt::format("{}: DEM - FEM, top ply", component),
                          {-m, m},
                          &plate});
      }
      const std::string png = fmt::format("{}_difference.png", stem);
      run_gnuplot(map_script(png, panels, 1, 2, cx * 1e3, cy * 1e3, s.hole_diameter * 1e3), out_dir,
                  fmt::format("{}_difference.gp", stem));
      maps.figures.push_back(png);
    }
    for (const std::string& f : maps.figures) {
      maps.files.push_back(f);
      maps.files.push_back(f.substr(0, f.size() - 4) + ".gp");
    }
  } else {
    maps.figure_note = fmt::format("Figures not drawn: {}. The map data are in `{}` and `{}`.\n\n",
                                   gnuplot.message, plate_data, window_data);
  }
  return maps;
}

}  // namespace plydem
