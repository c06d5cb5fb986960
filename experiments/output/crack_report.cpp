#include "experiments/output/crack_report.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <fstream>
#include <map>

#include "core/error.hpp"
#include "core/units.hpp"
#include "experiments/output/figures.hpp"

namespace plydem {
namespace fs = std::filesystem;

namespace {

constexpr std::size_t kDensitySamples = 200;

void write_file(const fs::path& path, const std::string& text) {
  std::ofstream file(path, std::ios::binary);
  file << text;
  if (!file) throw Error(fmt::format("cannot write {}", path.string()));
}

}  // namespace

std::string crack_place(bool interface, int ply) {
  return interface ? fmt::format("interface {}/{}", ply + 1, ply + 2)
                   : fmt::format("ply {}", ply + 1);
}

CrackReport crack_report(const Model& model, const std::vector<BondBreak>& breaks,
                         const std::vector<double>& strain, const fs::path& out_dir,
                         const std::string& stem, const std::string& title) {
  CrackReport r;
  r.cracks = find_cracks(model, breaks);
  const double x_begin = model.particles.reference_position.col(0).minCoeff();
  const double x_end = model.particles.reference_position.col(0).maxCoeff();
  const double span = std::max(x_end - x_begin, 2.0 * model.particles.radius.maxCoeff());

  std::map<std::pair<bool, int>, CrackCount> by_place;
  for (const Crack& c : r.cracks) {
    CrackCount& n = by_place[{c.interface, c.ply}];
    n.interface = c.interface;
    n.ply = c.ply;
    ++n.cracks;
    n.length += c.length;
    const std::string mode = c.mode();
    if (mode == "tension")
      ++n.tension;
    else if (mode == "shear")
      ++n.shear;
    else
      ++n.mixed;
  }
  for (auto& [key, n] : by_place) {
    n.density = n.cracks / span;
    r.counts.push_back(n);
  }
  const fs::path csv = fs::path(fmt::format("{}_cracks.csv", stem));
  write_file(out_dir / csv, cracks_csv(r.cracks));
  r.files.push_back(csv);

  std::string& md = r.markdown;
  md += fmt::format("#### {}\n\n", title);
  if (r.cracks.empty()) {
    md += "No bond broke: no crack.\n\n";
    return r;
  }
  md += fmt::format(
      "{} broken bonds form {} crack{} (broken bonds whose contact points lie within 1.5 "
      "particle diameters in the same ply or interface, solvers/cracks.hpp); every crack in "
      "`{}`.\n\n",
      breaks.size(), r.cracks.size(), r.cracks.size() == 1 ? "" : "s", csv.generic_string());
  md +=
      "| where | cracks | total length (mm) | longest (mm) | density (1/mm) | tension / shear / "
      "mixed |\n|---|--:|--:|--:|--:|---|\n";
  for (const CrackCount& n : r.counts) {
    double longest = 0;
    for (const Crack& c : r.cracks)
      if (c.interface == n.interface && c.ply == n.ply) longest = std::max(longest, c.length);
    md +=
        fmt::format("| {} | {} | {:.4g} | {:.4g} | {:.4g} | {} / {} / {} |\n",
                    crack_place(n.interface, n.ply), n.cracks, n.length / kMetresPerMm,
                    longest / kMetresPerMm, n.density * kMetresPerMm, n.tension, n.shear, n.mixed);
  }
  md += "\n";

  // Crack density of each cracked ply against the applied strain.
  if (strain.size() < 2) return r;
  std::vector<int> plies;
  for (const CrackCount& n : r.counts)
    if (!n.interface) plies.push_back(n.ply);
  if (plies.empty()) return r;
  const std::size_t events = strain.size() - 1;
  std::vector<std::size_t> samples;
  for (std::size_t k = 1; k <= kDensitySamples; ++k) {
    const std::size_t e = std::max<std::size_t>(1, events * k / kDensitySamples);
    if (samples.empty() || samples.back() != e) samples.push_back(e);
  }
  std::string table = "strain";
  for (int ply : plies) table += fmt::format(",{}_per_mm", crack_place(false, ply));
  table += "\n";
  std::vector<Curve> curves;
  for (int ply : plies) curves.push_back({crack_place(false, ply), {0.0}, {0.0}, true});
  std::vector<BondBreak> so_far;
  std::size_t next = 0;
  for (std::size_t e : samples) {
    while (next < breaks.size() && breaks[next].at <= static_cast<double>(e))
      so_far.push_back(breaks[next++]);
    const std::vector<Crack> now = find_cracks(model, so_far);
    table += fmt::format("{:.8g}", strain[e]);
    for (std::size_t k = 0; k < plies.size(); ++k) {
      const double density = crack_density(now, plies[k], x_begin, x_begin + span);
      table += fmt::format(",{:.6g}", density * kMetresPerMm);
      curves[k].x.push_back(strain[e] * 100);
      curves[k].y.push_back(density * kMetresPerMm);
    }
    table += "\n";
  }
  const fs::path density_csv = fs::path(fmt::format("{}_crack_density.csv", stem));
  write_file(out_dir / density_csv, table);
  r.files.push_back(density_csv);
  const Figure figure = plot_curves(curves, out_dir, fmt::format("{}_crack_density", stem),
                                    fmt::format("{}: crack density against applied strain", title),
                                    "applied strain [%]", "cracks per mm");
  r.files.insert(r.files.end(), figure.files.begin(), figure.files.end());
  md += figure_markdown(figure, "Crack density of each ply against the applied strain") + "\n";
  return r;
}

}  // namespace plydem
