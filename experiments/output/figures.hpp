#pragma once
/// \file
/// Figures of experiment runs, drawn by gnuplot (experiments/output/external_tool.hpp) as PNG
/// files:
///   - a model's bonds in plan view coloured by their normal stiffness, like the paper's
///     Figs. 10-13 (fibre bonds red, matrix bonds blue); the plies of a laminate side by side;
///   - curves (stress-strain), lines and points;
///   - a 2D field map: a value at scattered points (particles, nodes) as coloured dots.
///
/// Each figure writes its data (`STEM.dat`) and script (`STEM.gp`) into `OUT/plots/` so that a
/// user can edit and redraw it, and the picture as `OUT/STEM.png`. When gnuplot is missing the
/// figure is skipped, not an error: Figure::skipped says why, and the report shows that line.
/// A gnuplot that runs and fails throws plydem::Error with its messages.

#include <Eigen/Dense>
#include <filesystem>
#include <string>
#include <vector>

#include "core/model.hpp"

namespace plydem {

/// What one figure left behind.
struct Figure {
  std::filesystem::path png;  ///< relative to the output folder; empty when skipped
  /// Every file written, relative to the output folder (data, script, PNG).
  std::vector<std::filesystem::path> files;
  std::string skipped;  ///< why the figure was not drawn (gnuplot missing), else ""
};

/// The bonds of `model` in plan view (x-y, mm), each a line coloured by its normal stiffness
/// [MN/m]. Ply k of a laminate is drawn shifted along y by k times 1.15 widths, so that every ply
/// shows, labelled by `ply_labels` (default "ply k"); interface bonds (BondKind::kInterface) are
/// left out. Only the part x_min <= x <= x_min + `window` is drawn (0 = all): the full coupon is a
/// thin strip in which single bonds cannot be seen. Colours span the 1st to 97th percentile of k_n
/// (the stiffer completed edge bonds saturate).
Figure plot_bonds_by_stiffness(const Model& model, const std::filesystem::path& out_dir,
                               const std::string& stem, const std::string& title, double window = 0,
                               const std::vector<std::string>& ply_labels = {});

/// A site's crack (failure at the material point) on the crack pattern: the trace of its plane
/// in plan view, a segment through `centre` along `along`.
struct CrackTrace {
  Eigen::Vector2d centre = Eigen::Vector2d::Zero();  ///< [m]
  Eigen::Vector2d along = Eigen::Vector2d::UnitY();  ///< unit direction of the trace
  double length = 0;                                 ///< [m]
  int ply = 0;                                       ///< drawn beside that ply's bonds
  bool fibre = false;                                ///< a fibre mode's crack (else a matrix one)
};

/// The bonds of `model` in plan view (x-y, mm) by their state (core/model.hpp BondState): intact
/// bonds thin grey, softened ones (0 < damage < 1) orange, broken in tension red, in shear blue:
/// the crack pattern. Plies side by side as in plot_bonds_by_stiffness (interface bonds left
/// out; a broken interface bond is drawn as a cross at its first particle, in its mode's colour).
/// The sites' cracks (`cracks`) are drawn over them, fibre modes purple, matrix modes green.
/// Only x_begin <= x <= x_end is drawn (x_end <= x_begin: all). Throws plydem::Error if the model
/// has no bonds in that window.
Figure plot_bond_states(const Model& model, const std::filesystem::path& out_dir,
                        const std::string& stem, const std::string& title, double x_begin = 0,
                        double x_end = 0, const std::vector<std::string>& ply_labels = {},
                        const std::vector<CrackTrace>& cracks = {});

/// A points curve's marker in plot_curves.
enum class Marker {
  kDisc,    ///< filled
  kSquare,  ///< filled
  kCircle,  ///< open, on a thinner line: a second set of the same quantity (a coarser size)
};

/// One curve of plot_curves.
struct Curve {
  std::string label;
  std::vector<double> x, y;  ///< in the units of the axes' labels
  bool points = true;        ///< points joined by lines; false: a plain (dashed) line
  /// Curves that belong together (one laminate's model and references) share a colour: an index
  /// into plot_curves' palette of eight (taken modulo 8); -1: gnuplot's own sequence.
  int colour = -1;
  Marker marker = Marker::kDisc;  ///< of a points curve
};

/// Axes of plot_curves beyond their labels.
struct PlotAxes {
  bool log_y = false;            ///< logarithmic y axis (every y must then be positive)
  std::string key = "left top";  ///< where gnuplot puts the legend (`set key ...`)
};

/// Curves in one x-y plot, e.g. stress-strain: measured points beside theory lines.
/// Throws plydem::Error if a curve's x and y differ in length or there is no point at all, or a
/// y value is not positive on a logarithmic axis.
Figure plot_curves(const std::vector<Curve>& curves, const std::filesystem::path& out_dir,
                   const std::string& stem, const std::string& title, const std::string& x_label,
                   const std::string& y_label, const PlotAxes& axes = {});

/// A scalar field at scattered points (x, y in mm) as coloured dots in plan view, equal axes.
/// Throws plydem::Error if the arrays differ in length or are empty.
Figure plot_field_map(const std::vector<double>& x, const std::vector<double>& y,
                      const std::vector<double>& value, const std::filesystem::path& out_dir,
                      const std::string& stem, const std::string& title,
                      const std::string& value_label);

/// The figure as a Markdown image line with its caption, or the line saying why it is missing.
std::string figure_markdown(const Figure& figure, const std::string& caption);

}  // namespace plydem
