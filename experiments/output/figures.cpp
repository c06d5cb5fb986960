#include "experiments/output/figures.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>

#include "core/error.hpp"
#include "core/units.hpp"
#include "experiments/output/external_tool.hpp"

namespace plydem {
namespace fs = std::filesystem;

namespace {

// gnuplot string literal in single quotes ('' escapes a quote).
std::string gp_quote(const std::string& text) {
  std::string out = "'";
  for (char c : text) {
    if (c == '\'')
      out += "''";
    else
      out += c;
  }
  out += '\'';
  return out;
}

// Writes OUT/plots/STEM.dat and draws OUT/STEM.png with `script` (which reads 'STEM.dat' and
// writes '../STEM.png'); skipped when gnuplot is missing.
Figure draw(const fs::path& out_dir, const std::string& stem, const std::string& data,
            const std::string& script) {
  Figure figure;
  const fs::path plots = out_dir / "plots";
  fs::create_directories(plots);
  {
    const fs::path data_path = plots / fmt::format("{}.dat", stem);
    std::ofstream file(data_path, std::ios::binary);
    file << data;
    if (!file) throw Error(fmt::format("cannot write {}", data_path.string()));
  }
  figure.files.push_back(fs::path("plots") / fmt::format("{}.dat", stem));
  const GnuplotAvailability gnuplot = gnuplot_availability();
  if (!gnuplot.available) {
    figure.skipped = fmt::format("figure {}.png not drawn: {}", stem, gnuplot.message);
    return figure;
  }
  run_gnuplot(script, plots, fmt::format("{}.gp", stem));
  figure.files.push_back(fs::path("plots") / fmt::format("{}.gp", stem));
  figure.png = fmt::format("{}.png", stem);
  figure.files.push_back(figure.png);
  return figure;
}

// Canvas height for a plot of data aspect `height / width` on a 1200 px wide canvas.
int canvas_height(double aspect) {
  return std::clamp(static_cast<int>(std::lround(1100 * aspect + 160)), 320, 1400);
}

}  // namespace

Figure plot_bonds_by_stiffness(const Model& model, const fs::path& out_dir, const std::string& stem,
                               const std::string& title, double window,
                               const std::vector<std::string>& ply_labels) {
  const Particles& p = model.particles;
  const Bonds& b = model.bonds;
  if (p.size() == 0 || b.size() == 0) {
    throw Error(fmt::format("figure {}: the model has no particles or no bonds", stem));
  }
  const double x_min = p.reference_position.col(0).minCoeff();
  const double y_min = p.reference_position.col(1).minCoeff();
  const double y_max = p.reference_position.col(1).maxCoeff();
  const double x_end = window > 0 ? x_min + window : p.reference_position.col(0).maxCoeff();
  const double ply_shift = 1.15 * std::max(y_max - y_min, 1e-12);
  const int plies = p.ply.maxCoeff() + 1;
  constexpr double mm = kMmPerMetre;
  std::string data = "# x1 [mm], y1 [mm], dx [mm], dy [mm], k_n [MN/m], ply\n";
  int drawn = 0;
  double k_min = INFINITY, k_max = -INFINITY;
  for (int k = 0; k < b.size(); ++k) {
    if (b.is_interface(k)) continue;  // interface bonds stand along z
    const int i = b.first(k), j = b.second(k);
    if (std::max(p.reference_position(i, 0), p.reference_position(j, 0)) > x_end) continue;
    const double shift = p.ply(i) * ply_shift;
    const double kn = b.normal_stiffness(k) * 1e-6;
    k_min = std::min(k_min, kn);
    k_max = std::max(k_max, kn);
    data +=
        fmt::format("{:.6g} {:.6g} {:.6g} {:.6g} {:.6g} {}\n", p.reference_position(i, 0) * mm,
                    (p.reference_position(i, 1) + shift) * mm,
                    (p.reference_position(j, 0) - p.reference_position(i, 0)) * mm,
                    (p.reference_position(j, 1) - p.reference_position(i, 1)) * mm, kn, p.ply(i));
    ++drawn;
  }
  if (drawn == 0) throw Error(fmt::format("figure {}: no bond lies in the drawn window", stem));
  {
    // Colours span the 1st to 97th percentile: the few completed edge bonds
    // (strategies/boundary_cells.hpp) are stiffer than the bulk and would wash out the families.
    std::vector<double> kn;
    for (int k = 0; k < b.size(); ++k) {
      if (!b.is_interface(k)) kn.push_back(b.normal_stiffness(k) * 1e-6);
    }
    std::sort(kn.begin(), kn.end());
    const auto at = [&](double q) {
      return kn[static_cast<std::size_t>(q * static_cast<double>(kn.size() - 1))];
    };
    k_min = at(0.01);
    k_max = at(0.97);
  }
  if (k_max <= k_min) k_max = k_min * 1.001 + 1e-9;
  const double height = (y_max - y_min + (plies - 1) * ply_shift + 0.15 * (y_max - y_min)) * mm;
  const double width = (x_end - x_min) * mm;
  std::string labels;
  for (int k = 0; k < plies && plies > 1; ++k) {
    const std::string label = k < static_cast<int>(ply_labels.size())
                                  ? ply_labels[static_cast<std::size_t>(k)]
                                  : fmt::format("ply {}", k);
    labels += fmt::format("set label {} at first {:.6g}, first {:.6g} left front noenhanced\n",
                          gp_quote(label), x_min * mm,
                          (y_max + k * ply_shift + 0.075 * (y_max - y_min)) * mm);
  }
  const std::string script = fmt::format(
      "set terminal pngcairo size 1200,{} font ',11'\n"
      "set output '../{}.png'\n"
      "set title {} noenhanced\n"
      "set size ratio -1\n"
      "set xlabel 'x [mm]'\nset ylabel 'y [mm]'\n"
      "set cblabel 'bond normal stiffness k_n [MN/m]'\n"
      "set palette defined (0 '#1f3fbf', 1 '#2fa8e0', 2 '#f0d020', 3 '#d01010')\n"
      "set cbrange [{:.6g}:{:.6g}]\n"
      "set xrange [{:.6g}:{:.6g}]\n"
      "{}"
      "plot '{}.dat' using 1:2:3:4:5 with vectors nohead lw 1.2 lc palette notitle\n",
      canvas_height(height / std::max(width, 1e-12)), stem, gp_quote(title), k_min, k_max,
      x_min * mm - 0.02 * width, x_min * mm + 1.02 * width, labels, stem);
  return draw(out_dir, stem, data, script);
}

namespace {

// One data block of segments (x1 y1 dx dy) and its plot clause, when it has any: gnuplot numbers
// the blocks it finds, so `index` counts only those written.
void add_segment_block(const std::string& name, const std::string& style, const std::string& rows,
                       int count, const std::string& stem, int& index, std::string& data,
                       std::string& plot) {
  if (count == 0) return;
  data += fmt::format("# {}\n{}\n\n", name, rows);
  plot += fmt::format("{}'{}.dat' index {} using 1:2:3:4 with vectors nohead {} title '{} ({})'",
                      index > 0 ? ", " : "", stem, index, style, name, count);
  ++index;
}

// The sites' cracks of plot_bond_states: a data block per mode (fibre, matrix) appended to `data`
// as gnuplot's blocks `index`, `index` + 1, ... (counted on), and their plot clauses.
std::string crack_traces(const std::vector<CrackTrace>& cracks, const std::string& stem,
                         double x_begin, double x_end, double ply_shift, int& index,
                         std::string& data) {
  constexpr double mm = kMmPerMetre;
  std::string blocks[2];
  int counts[2] = {0, 0};
  for (const CrackTrace& c : cracks) {
    if (c.centre.x() < x_begin || c.centre.x() > x_end) continue;
    const Eigen::Vector2d start = c.centre - 0.5 * c.length * c.along;
    const int block = c.fibre ? 0 : 1;
    blocks[block] += fmt::format("{:.6g} {:.6g} {:.6g} {:.6g}\n", start.x() * mm,
                                 (start.y() + c.ply * ply_shift) * mm, c.length * c.along.x() * mm,
                                 c.length * c.along.y() * mm);
    ++counts[block];
  }
  static const char* const kNames[2] = {"site cracks, fibre modes", "site cracks, matrix modes"};
  static const char* const kStyles[2] = {"lw 3.5 lc rgb '#8010a0'", "lw 3.5 lc rgb '#108040'"};
  std::string plot;
  for (int block = 0; block < 2; ++block)
    add_segment_block(kNames[block], kStyles[block], blocks[block], counts[block], stem, index,
                      data, plot);
  return plot;
}

}  // namespace

Figure plot_bond_states(const Model& model, const fs::path& out_dir, const std::string& stem,
                        const std::string& title, double x_begin, double x_end,
                        const std::vector<std::string>& ply_labels,
                        const std::vector<CrackTrace>& cracks) {
  const Particles& p = model.particles;
  const Bonds& b = model.bonds;
  if (p.size() == 0 || b.size() == 0) {
    throw Error(fmt::format("figure {}: the model has no particles or no bonds", stem));
  }
  if (!(x_end > x_begin)) {
    x_begin = p.reference_position.col(0).minCoeff();
    x_end = p.reference_position.col(0).maxCoeff();
  }
  const double y_min = p.reference_position.col(1).minCoeff();
  const double y_max = p.reference_position.col(1).maxCoeff();
  const double ply_shift = 1.15 * std::max(y_max - y_min, 1e-12);
  const int plies = p.ply.maxCoeff() + 1;
  constexpr double mm = kMmPerMetre;
  // The bonds by state: intact, softened, broken in tension, broken in shear.
  std::string blocks[4];
  int counts[4] = {0, 0, 0, 0};
  std::string crosses[2];  // broken interface bonds: tension, shear
  int cross_counts[2] = {0, 0};
  for (int k = 0; k < b.size(); ++k) {
    const int i = b.first(k), j = b.second(k);
    const double xi = p.reference_position(i, 0), xj = p.reference_position(j, 0);
    if (std::min(xi, xj) < x_begin || std::max(xi, xj) > x_end) continue;
    const int state = b.state(k);
    const int mode = state == static_cast<int>(BondState::kBrokenTension) ? 0 : 1;
    if (b.is_interface(k)) {
      if (state == static_cast<int>(BondState::kIntact)) continue;
      crosses[mode] += fmt::format("{:.6g} {:.6g}\n", xi * mm,
                                   (p.reference_position(i, 1) + p.ply(i) * ply_shift) * mm);
      ++cross_counts[mode];
      continue;
    }
    const int block =
        state == static_cast<int>(BondState::kIntact) ? (b.damage(k) > 0 ? 1 : 0) : 2 + mode;
    blocks[block] +=
        fmt::format("{:.6g} {:.6g} {:.6g} {:.6g}\n", xi * mm,
                    (p.reference_position(i, 1) + p.ply(i) * ply_shift) * mm, (xj - xi) * mm,
                    (p.reference_position(j, 1) - p.reference_position(i, 1)) * mm);
    ++counts[block];
  }
  if (counts[0] + counts[1] + counts[2] + counts[3] == 0) {
    throw Error(fmt::format("figure {}: no bond lies in the drawn window", stem));
  }
  static const char* const kNames[4] = {"intact", "softened", "broken in tension",
                                        "broken in shear"};
  static const char* const kStyles[4] = {"lw 0.6 lc rgb '#c8c8c8'", "lw 2 lc rgb '#f08c00'",
                                         "lw 2.5 lc rgb '#d01010'", "lw 2.5 lc rgb '#1040d0'"};
  std::string data =
      "# x1 [mm], y1 [mm], dx [mm], dy [mm] (broken interface bonds: x, y), one block per state\n";
  // Only non-empty blocks are written: gnuplot numbers the blocks it finds.
  std::string plot = "plot ";
  int index = 0;
  for (int block = 0; block < 4; ++block)
    add_segment_block(kNames[block], kStyles[block], blocks[block], counts[block], stem, index,
                      data, plot);
  for (int mode = 0; mode < 2; ++mode) {
    if (cross_counts[mode] == 0) continue;
    const char* name = mode == 0 ? "tension" : "shear";
    data += fmt::format("# broken interface bonds, {}\n{}\n\n", name, crosses[mode]);
    plot += fmt::format(
        "{}'{}.dat' index {} using 1:2 with points pt 2 ps 1.2 lc rgb '{}' title 'interface "
        "broken in {} ({})'",
        index > 0 ? ", " : "", stem, index, mode == 0 ? "#d01010" : "#1040d0", name,
        cross_counts[mode]);
    ++index;
  }
  plot += crack_traces(cracks, stem, x_begin, x_end, ply_shift, index, data);
  std::string labels;
  for (int k = 0; k < plies && plies > 1; ++k) {
    const std::string label = k < static_cast<int>(ply_labels.size())
                                  ? ply_labels[static_cast<std::size_t>(k)]
                                  : fmt::format("ply {}", k);
    labels += fmt::format("set label {} at first {:.6g}, first {:.6g} left front noenhanced\n",
                          gp_quote(label), x_begin * mm,
                          (y_max + k * ply_shift + 0.075 * (y_max - y_min)) * mm);
  }
  const double height = (y_max - y_min + (plies - 1) * ply_shift + 0.15 * (y_max - y_min)) * mm;
  const double width = (x_end - x_begin) * mm;
  const std::string script = fmt::format(
      "set terminal pngcairo size 1200,{} font ',11'\n"
      "set output '../{}.png'\n"
      "set title {} noenhanced\n"
      "set size ratio -1\n"
      "set xlabel 'x [mm]'\nset ylabel 'y [mm]'\n"
      "set key outside bottom center horizontal noenhanced\n"
      "set xrange [{:.6g}:{:.6g}]\n"
      "{}{}\n",
      canvas_height(height / std::max(width, 1e-12)) + 80, stem, gp_quote(title),
      x_begin * mm - 0.02 * width, x_begin * mm + 1.02 * width, labels, plot);
  return draw(out_dir, stem, data, script);
}

namespace {

// gnuplot's style of a curve: its line, and a points curve's marker.
std::string curve_style(const Curve& c) {
  if (!c.points) return "lines dt 2 lw 2";
  switch (c.marker) {
    case Marker::kSquare:
      return "linespoints pt 5 ps 1.1 lw 2";
    case Marker::kCircle:
      return "linespoints pt 6 ps 1.2 lw 1";
    case Marker::kDisc:
      break;
  }
  return "linespoints pt 7 ps 1.2 lw 2";
}

// A curve's colour (Okabe and Ito's eight, told apart with colour-blind vision too), or nothing:
// gnuplot's sequence.
std::string curve_colour(const Curve& c) {
  static constexpr std::array<const char*, 8> kPalette = {
      "#0072b2", "#d55e00", "#009e73", "#cc79a7", "#e69f00", "#56b4e9", "#000000", "#f0e442"};
  if (c.colour < 0) return "";
  return fmt::format(" lc rgb '{}'",
                     kPalette[static_cast<std::size_t>(c.colour) % kPalette.size()]);
}

}  // namespace

Figure plot_curves(const std::vector<Curve>& curves, const fs::path& out_dir,
                   const std::string& stem, const std::string& title, const std::string& x_label,
                   const std::string& y_label, const PlotAxes& axes) {
  std::string data;
  std::string plot = "plot ";
  int index = 0;
  for (const Curve& c : curves) {
    if (c.x.size() != c.y.size()) {
      throw Error(fmt::format("figure {}: curve '{}' has {} x and {} y values", stem, c.label,
                              c.x.size(), c.y.size()));
    }
    if (c.x.empty()) continue;
    if (axes.log_y) {
      for (double y : c.y) {
        if (!(y > 0)) {
          throw Error(fmt::format("figure {}: curve '{}' has y = {} on a logarithmic axis", stem,
                                  c.label, y));
        }
      }
    }
    data += fmt::format("# {}\n", c.label);
    for (std::size_t i = 0; i < c.x.size(); ++i) {
      data += fmt::format("{:.9g} {:.9g}\n", c.x[i], c.y[i]);
    }
    data += "\n\n";
    plot += fmt::format("{}'{}.dat' index {} with {}{} title {}", index > 0 ? ", " : "", stem,
                        index, curve_style(c), curve_colour(c), gp_quote(c.label));
    ++index;
  }
  if (index == 0) throw Error(fmt::format("figure {}: no curve has points", stem));
  const std::string script = fmt::format(
      "set terminal pngcairo size 1000,700 font ',11'\n"
      "set output '../{}.png'\n"
      "set title {} noenhanced\n"
      "set xlabel {} noenhanced\nset ylabel {} noenhanced\n"
      "set key {} noenhanced\nset grid\n{}{}\n",
      stem, gp_quote(title), gp_quote(x_label), gp_quote(y_label), axes.key,
      axes.log_y ? "set logscale y\n" : "", plot);
  return draw(out_dir, stem, data, script);
}

Figure plot_field_map(const std::vector<double>& x, const std::vector<double>& y,
                      const std::vector<double>& value, const fs::path& out_dir,
                      const std::string& stem, const std::string& title,
                      const std::string& value_label) {
  if (x.size() != y.size() || x.size() != value.size() || x.empty()) {
    throw Error(fmt::format("figure {}: {} x, {} y and {} values (need equal, non-zero counts)",
                            stem, x.size(), y.size(), value.size()));
  }
  std::string data = "# x [mm], y [mm], value\n";
  for (std::size_t i = 0; i < x.size(); ++i) {
    data += fmt::format("{:.9g} {:.9g} {:.9g}\n", x[i], y[i], value[i]);
  }
  const auto [xl, xh] = std::minmax_element(x.begin(), x.end());
  const auto [yl, yh] = std::minmax_element(y.begin(), y.end());
  const double aspect = (*yh - *yl) / std::max(*xh - *xl, 1e-12);
  const std::string script = fmt::format(
      "set terminal pngcairo size 1200,{} font ',11'\n"
      "set output '../{}.png'\n"
      "set title {} noenhanced\n"
      "set size ratio -1\n"
      "set xlabel 'x [mm]'\nset ylabel 'y [mm]'\n"
      "set cblabel {} noenhanced\n"
      "set palette rgbformulae 33,13,10\n"
      "plot '{}.dat' using 1:2:3 with points pt 7 ps 0.6 lc palette notitle\n",
      canvas_height(aspect), stem, gp_quote(title), gp_quote(value_label), stem);
  return draw(out_dir, stem, data, script);
}

std::string figure_markdown(const Figure& figure, const std::string& caption) {
  if (!figure.skipped.empty()) return fmt::format("*{}* ({})\n", caption, figure.skipped);
  return fmt::format("![{}]({})\n\n*{}*\n", caption, figure.png.generic_string(), caption);
}

}  // namespace plydem
