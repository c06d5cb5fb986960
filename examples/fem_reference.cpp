// FEM references with CalculiX: laminate moduli against classical lamination theory, and the
// hole-in-plate specimen, with run times.
//
// Each laminate is a 20 x 10 mm coupon of 0.2 mm E-glass plies, pulled along x and, turned by
// -90 deg, along y (experiments/fem/calculix.hpp); the table gives FEM/CLT - 1. Laminates differ
// from CLT (an infinitely wide plate) by their free edges: Poisson's ratios by up to ~5% when the
// edge zones are fitted with the rest (--edge-band-mm leaves them out), and moduli by ~0.1-0.4%
// that shrink as 1/W. The hole plate is the
// 60 x 36 x 1.5 mm [0/90/0] plate with a 3 mm hole whose grips move apart 0.1 mm in total; it
// reports the grip force, the peak axial stress in a 0 deg ply beside the hole over the gross
// stress, and a few displacements sampled through the interpolated field. Needs ccx on PATH
// (Debian: calculix-ccx); without it, it says so and exits 0.
//
// Sample runs:
//   build/examples/fem_reference                       # C3D8I, default meshes
//   build/examples/fem_reference --element C3D20R --elements-per-ply 2
//   build/examples/fem_reference --edge-band-mm 2.5   # free-edge zones out of the strain fit
//   build/examples/fem_reference --hole-only --hole-element-mm 0.05 --element-mm 1
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <numbers>

#include "core/error.hpp"
#include "core/material.hpp"
#include "experiments/fem/calculix.hpp"

using namespace plydem;

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

std::vector<Ply> layup(const Material& m, const std::vector<double>& degrees, double thickness) {
  std::vector<Ply> plies;
  for (double d : degrees) plies.push_back(Ply{m, d * kDeg, thickness});
  return plies;
}

void print_laminates(const Material& m, const FemSettings& settings, const std::string& element,
                     int elements_per_ply) {
  fmt::print("{} elements, {} per ply; 20 x 10 mm coupons of 0.2 mm plies; FEM/CLT - 1\n", element,
             elements_per_ply);
  fmt::print("{:<12} {:>10} {:>10} {:>10} {:>10} {:>12} {:>9} {:>8}\n", "layup", "Ex", "Ey",
             "nu_xy", "nu_yx", "gxy/ex FEM", "CLT", "ccx [s]");
  const std::vector<std::pair<std::string, std::vector<double>>> layups = {
      {"[0]", {0}},
      {"[30]", {30}},
      {"[45]", {45}},
      {"[0/90/0]", {0, 90, 0}},
      {"[0/30/45]s", {0, 30, 45, 45, 30, 0}},
      {"[0/30/45]", {0, 30, 45}}};
  for (const auto& [name, degrees] : layups) {
    const FemSpecimen coupon{layup(m, degrees, 0.2e-3), 20e-3, 10e-3};
    const FemTensionResult r = fem_tension_test(coupon, settings);
    const InPlaneConstants& t = r.theory;
    fmt::print("{:<12} {:>10.2e} {:>10.2e} {:>10.2e} {:>10.2e} {:>12.5f} {:>9.5f} {:>8.2f}\n", name,
               r.fem.Ex / t.Ex - 1, r.fem.Ey / t.Ey - 1, r.fem.nu_xy / t.nu_xy - 1,
               r.fem.nu_yx / t.nu_yx - 1, r.fem.shear_coupling_x, t.shear_coupling_x,
               r.along_x.solver_seconds + r.along_y.solver_seconds);
  }
  fmt::print(
      "([0/30/45] is unsymmetric: it bends and twists under tension, which CLT's A/h "
      "alone ignores.)\n\n");
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"CalculiX references: laminate moduli vs CLT, and the hole-in-plate specimen"};
  std::string element = "C3D8I";
  int elements_per_ply = 1;
  double element_mm = 0, hole_element_mm = 0, edge_band_mm = 0;
  int threads = 1;
  bool hole_only = false;
  app.add_flag("--hole-only", hole_only, "only the hole-in-plate specimen");
  app.add_option("--element", element, "C3D8I or C3D20R")
      ->check(CLI::IsMember({"C3D8I", "C3D20R"}));
  app.add_option("--elements-per-ply", elements_per_ply, "elements through each ply");
  app.add_option("--element-mm", element_mm, "in-plane element size (0 = automatic)");
  app.add_option("--hole-element-mm", hole_element_mm,
                 "element size along the hole (0 = automatic)");
  app.add_option("--edge-band-mm", edge_band_mm, "free-edge bands left out of the strain fit");
  app.add_option("--threads", threads, "threads for ccx");
  CLI11_PARSE(app, argc, argv);

  try {
    const Material m = load_material("eglass-my750");
    FemSettings settings;
    settings.mesh.element = element == "C3D20R" ? FemElement::kC3D20R : FemElement::kC3D8I;
    settings.mesh.elements_per_ply = elements_per_ply;
    settings.mesh.element_size = element_mm * 1e-3;
    settings.mesh.hole_element_size = hole_element_mm * 1e-3;
    settings.edge_band = edge_band_mm * 1e-3;
    settings.threads = threads;
    const CalculixAvailability ccx = calculix_availability(settings.executable);
    if (!ccx.available) {
      fmt::print("{}: FEM column skipped\n", ccx.message);
      return 0;
    }

    if (!hole_only) print_laminates(m, settings, element, elements_per_ply);
    const FemSpecimen plate{layup(m, {0, 90, 0}, 0.5e-3), 60e-3, 36e-3, 3e-3};
    FemSettings hole = settings;
    hole.loading.end_displacement = 0.1e-3;
    hole.element_stresses = true;
    const FemSolution f = run_calculix(plate, hole);
    double peak = 0;
    for (int e = 0; e < f.element_stress.rows(); ++e)
      if (f.element_ply(e) == 0) peak = std::max(peak, f.element_stress(e, 0));
    fmt::print("hole plate 60 x 36 x 1.5 mm [0/90/0], 3 mm hole, grips 0.1 mm apart:\n");
    fmt::print("  {} {} elements, {} nodes, {} dofs; ccx {:.2f} s, all {:.2f} s\n", element,
               f.elements, f.nodes, f.degrees_of_freedom, f.solver_seconds, f.wall_seconds);
    fmt::print(
        "  grip force {:.2f} N, gross stress {:.3f} MPa; peak element-mean sigma_xx in the "
        "bottom 0 deg ply {:.3f} MPa = {:.3f} x gross\n",
        f.reaction_force, f.gross_stress * 1e-6, peak * 1e-6, peak / f.gross_stress);
    for (const auto& [x, y] :
         {std::pair{31.5e-3, 18e-3}, {30e-3, 19.5e-3}, {45e-3, 18e-3}, {30e-3, 30e-3}}) {
      const auto u = f.displacement.at(x, y);
      fmt::print("  u({:.1f}, {:.1f}) mm = ({:+.5e}, {:+.5e}, {:+.5e}) m\n", x * 1e3, y * 1e3,
                 u->x(), u->y(), u->z());
    }
  } catch (const Error& e) {
    fmt::print(stderr, "error: {}\n", e.what());
    return 1;
  }
  return 0;
}
