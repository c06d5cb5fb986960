// The FEM bridge's specimen and settings, and the tension tests built on run_calculix: the
// moduli of a laminate (fem_tension_test) and the CalculiX twin of a DEM tension test
// (fem_twin_tension_test). The mesher, the deck writer, the runner and the results reader live
// in calculix_mesh.cpp, calculix_input.cpp, calculix_run.cpp and calculix_results.cpp.
#include "experiments/fem/calculix.hpp"

#include <fmt/format.h>

#include <cmath>
#include <numbers>
#include <optional>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "core/measurements.hpp"
#include "experiments/protocols/coupon.hpp"
#include "strategies/laminate.hpp"

namespace plydem {

const char* fem_element_name(FemElement element) {
  return element == FemElement::kC3D20R ? "C3D20R" : "C3D8I";
}

double FemSpecimen::thickness() const {
  double h = 0;
  for (const Ply& ply : plies) h += ply.thickness;
  return h;
}

void FemSpecimen::validate() const {
  require(!plies.empty(), "the FEM specimen has no plies");
  for (std::size_t k = 0; k < plies.size(); ++k) {
    const Ply& ply = plies[k];
    try {
      plydem::validate(ply.material);
    } catch (const Error& e) {
      throw Error(fmt::format("ply {} (from the bottom): {}", k + 1, e.what()));
    }
    if (!std::isfinite(ply.angle))
      throw Error(fmt::format("ply {} (from the bottom): angle is not a finite number", k + 1));
    if (!(std::isfinite(ply.thickness) && ply.thickness > 0))
      throw Error(fmt::format("ply {} (from the bottom): thickness must be positive, got {} m",
                              k + 1, ply.thickness));
  }
  require(std::isfinite(length) && length > 0,
          fmt::format("FEM specimen length must be positive, got {} m", length));
  require(std::isfinite(width) && width > 0,
          fmt::format("FEM specimen width must be positive, got {} m", width));
  require(std::isfinite(hole_diameter) && hole_diameter >= 0,
          fmt::format("hole diameter must be >= 0, got {} m", hole_diameter));
  if (hole_diameter > 0) {
    require(length >= width,
            fmt::format("a plate with a hole must be at least as long as it is wide "
                        "(length {} mm, width {} mm)",
                        length * 1e3, width * 1e3));
    require(hole_diameter < 0.9 * width,
            fmt::format("the hole ({} mm) must be narrower than 0.9 x the plate's width ({} mm)",
                        hole_diameter * 1e3, width * 1e3));
  }
  const int last = static_cast<int>(plies.size()) - 1;
  for (std::size_t k = 0; k < cracks.size(); ++k) {
    const FemTransverseCrack& c = cracks[k];
    const std::string which = fmt::format("FEM crack {} (at x = {} mm)", k + 1, c.x * 1e3);
    require(hole_diameter == 0, which + ": a specimen with a hole cannot also have cracks");
    require(
        std::isfinite(c.x) && c.x > 1e-9 * length && c.x < length * (1 - 1e-9),
        fmt::format("{}: must lie inside the specimen's length (0, {} mm)", which, length * 1e3));
    require(c.first_ply >= 0 && c.first_ply <= c.last_ply && c.last_ply <= last,
            fmt::format("{}: plies {} .. {} (from the bottom, 1-based) are not plies 1 .. {} of "
                        "the specimen, lowest first",
                        which, c.first_ply + 1, c.last_ply + 1, last + 1));
    require(!(c.first_ply == 0 && c.last_ply == last),
            which + ": cuts every ply, which parts the specimen in two");
    for (std::size_t j = 0; j < k; ++j)
      require(std::abs(cracks[j].x - c.x) > 1e-9 * length,
              fmt::format("{}: lies at the x of crack {}; give one crack per x", which, j + 1));
  }
}

void FemMeshSettings::validate() const {
  require(elements_per_ply >= 1 && elements_per_ply <= 100,
          fmt::format("elements per ply must lie in [1, 100], got {}", elements_per_ply));
  require(std::isfinite(element_size) && element_size >= 0,
          fmt::format("FEM element size must be >= 0 (0 = automatic), got {} m", element_size));
  require(std::isfinite(hole_element_size) && hole_element_size >= 0,
          fmt::format("FEM hole element size must be >= 0 (0 = automatic), got {} m",
                      hole_element_size));
}

void FemSettings::validate() const {
  mesh.validate();
  require(std::isfinite(loading.end_displacement) && loading.end_displacement >= 0,
          fmt::format("FEM end displacement must be >= 0 (0 = 0.1% of the length), got {} m",
                      loading.end_displacement));
  require(std::isfinite(loading.grip_length) && loading.grip_length >= 0,
          fmt::format("FEM grip length must be >= 0, got {} m", loading.grip_length));
  require(std::isfinite(gauge_fraction) && gauge_fraction > 0 && gauge_fraction <= 1,
          fmt::format("gauge fraction must lie in (0, 1], got {}", gauge_fraction));
  require(std::isfinite(edge_band) && edge_band >= 0,
          fmt::format("FEM edge band must be >= 0, got {} m", edge_band));
  require(!executable.empty(), "the CalculiX executable name is empty");
  require(threads >= 1 && threads <= 1024, fmt::format("threads must be >= 1, got {}", threads));
}

namespace {

// The pulls along x and along y (every ply turned by -90 deg), and CLT; only the message when
// ccx is missing.
FemTensionResult run_both_pulls(const FemSpecimen& specimen, const FemSettings& settings) {
  FemTensionResult result;
  result.theory = laminate_constants(specimen.plies);
  result.along_x = run_calculix(specimen, settings);
  if (!result.along_x.available) {
    result.message = result.along_x.message;
    return result;
  }
  FemSpecimen turned = specimen;
  for (Ply& ply : turned.plies) ply.angle -= 0.5 * std::numbers::pi;
  result.along_y = run_calculix(turned, settings);
  return result;
}

// Ex, nu_xy, gamma_xy/eps_x from the pull along x; Ey, nu_yx from the one along y.
void set_moduli_from_pulls(FemTensionResult& result) {
  for (const FemSolution* pull : {&result.along_x, &result.along_y}) {
    if (!(pull->exx > 0))
      throw Error(fmt::format("the FEM coupon did not stretch (fitted strain {})", pull->exx));
  }
  result.available = true;
  const FemSolution& x = result.along_x;
  const FemSolution& y = result.along_y;
  result.fem.Ex = x.gross_stress / x.exx;
  result.fem.nu_xy = -x.eyy / x.exx;
  result.fem.shear_coupling_x = x.gamma_xy / x.exx;
  result.fem.Ey = y.gross_stress / y.exx;
  result.fem.nu_yx = -y.eyy / y.exx;
  result.nu_xz = -x.ezz / x.exx;
}

}  // namespace

FemTensionResult fem_tension_test(const FemSpecimen& specimen, const FemSettings& settings) {
  specimen.validate();
  settings.validate();
  require(specimen.hole_diameter == 0,
          "the FEM tension test measures moduli on a coupon without a hole");
  FemTensionResult result = run_both_pulls(specimen, settings);
  if (!result.along_x.available) return result;
  set_moduli_from_pulls(result);
  return result;
}

namespace {

// The DEM coupon's gauge particles (as the tension test selects them) at their positions in the
// FEM frame: x and y as built, z from the particles' mid-plane.
std::vector<Eigen::Vector3d> gauge_points(const Model& coupon, const TensionSettings& s,
                                          double grip_length) {
  Particles p = coupon.particles;
  const CouponGrips grips = assign_grips(p, grip_length);
  const GaugeSection gauge =
      gauge_section(p, grips, s.gauge_fraction, s.edge_band_diameters, s.coupon.particle_diameter);
  const double z_mid =
      0.5 * (p.reference_position.col(2).minCoeff() + p.reference_position.col(2).maxCoeff());
  std::vector<Eigen::Vector3d> points;
  points.reserve(gauge.particles.size());
  for (int i : gauge.particles) {
    points.emplace_back(p.reference_position(i, 0), p.reference_position(i, 1),
                        p.reference_position(i, 2) - z_mid);
  }
  return points;
}

// Replaces the solution's strain fit by the fit at `points` (the DEM's gauge particles).
void fit_at_points(FemSolution& solution, const std::vector<Eigen::Vector3d>& points) {
  Eigen::Array<double, Eigen::Dynamic, 2> position(static_cast<Eigen::Index>(points.size()), 2);
  Eigen::Array<double, Eigen::Dynamic, 2> displacement(position.rows(), 2);
  Eigen::Index n = 0;
  for (const Eigen::Vector3d& x : points) {
    const std::optional<Eigen::Vector3d> u = solution.displacement.at(x.x(), x.y(), x.z());
    if (!u) continue;
    position.row(n) << x.x(), x.y();
    displacement.row(n) << u->x(), u->y();
    ++n;
  }
  require(n >= 3,
          fmt::format("the FEM twin of the coupon: only {} of its {} gauge particles lie in "
                      "the FEM plate",
                      n, points.size()));
  const GaugeStrain strain = fit_plane_strain(position.topRows(n), displacement.topRows(n));
  solution.exx = strain.exx;
  solution.eyy = strain.eyy;
  solution.gamma_xy = strain.gamma_xy;
}

}  // namespace

double fem_twin_element_size(const TensionSettings& settings, const FemTwinSettings& twin) {
  if (twin.mesh.element_size > 0) return twin.mesh.element_size;
  return std::min(2 * settings.coupon.particle_diameter, settings.coupon.width / 8);
}

FemTensionResult fem_twin_tension_test(const TensionSettings& settings, const TensionResult& dem,
                                       const FemTwinSettings& twin) {
  require(dem.along_x.model && dem.along_y.model,
          "the FEM twin of a tension test needs the DEM's coupons (run the tension test first)");
  const CouponSpec& coupon = settings.coupon;
  FemSpecimen specimen;
  specimen.plies = settings.layup.empty()
                       ? std::vector<Ply>{Ply{coupon.material, dem.ply_angle, coupon.thickness}}
                       : laminate_plies(LaminateSpec{coupon, settings.layup, settings.interface});
  specimen.length = coupon.length;
  specimen.width = coupon.width;

  FemSettings fem;
  fem.mesh = twin.mesh;
  fem.mesh.element_size = fem_twin_element_size(settings, twin);
  fem.loading.grips = settings.grips;
  fem.loading.grip_length = TensionTest(settings).grip_length();
  fem.gauge_fraction = settings.gauge_fraction;
  fem.executable = twin.executable;
  fem.threads = twin.threads;

  FemTensionResult result = run_both_pulls(specimen, fem);
  if (!result.along_x.available) return result;
  fit_at_points(result.along_x,
                gauge_points(*dem.along_x.model, settings, fem.loading.grip_length));
  fit_at_points(result.along_y,
                gauge_points(*dem.along_y.model, settings, fem.loading.grip_length));
  set_moduli_from_pulls(result);
  return result;
}

}  // namespace plydem
