#include "experiments/output/report.hpp"

#include <fmt/format.h>

#include <cmath>
#include <numbers>

#include "core/units.hpp"

namespace plydem {
namespace {

const char* grips_name(GripCondition g) {
  return g == GripCondition::kFree ? "free" : "clamped";
}

nlohmann::json constants_json(const InPlaneConstants& c) {
  return {{"Ex", c.Ex},       {"Ey", c.Ey},   {"nu_xy", c.nu_xy},
          {"nu_yx", c.nu_yx}, {"Gxy", c.Gxy}, {"shear_coupling_x", c.shear_coupling_x}};
}

nlohmann::json matrix_json(const Eigen::Matrix3d& m) {
  nlohmann::json rows = nlohmann::json::array();
  for (int r = 0; r < 3; ++r) rows.push_back({m(r, 0), m(r, 1), m(r, 2)});
  return rows;
}

nlohmann::json pull_json(const PullResult& r) {
  return {{"ply_angle_deg", r.ply_angle / kDegree},
          {"modulus", r.modulus},
          {"poisson", r.poisson},
          {"shear_coupling", r.shear_coupling},
          {"fit_r_squared", r.fit_r_squared},
          {"particles", r.particles},
          {"bonds", r.bonds},
          {"cycles", r.cycles},
          {"final_unbalanced_ratio", r.final_ratio},
          {"linear_solver", r.linear_solver},
          {"linear_iterations", r.linear_iterations},
          {"linear_solver_choice", r.linear_solver_choice},
          {"time_step", r.time_step},
          {"grip_velocity", r.grip_velocity},
          {"loading_transits", r.loading_transits},
          {"cross_section", r.cross_section},
          {"wall_seconds", r.wall_seconds},
          {"strain", r.strain},
          {"lateral_strain", r.lateral_strain},
          {"shear_strain", r.shear_strain},
          {"stress", r.stress}};
}

}  // namespace

std::string format_tension_table(const TensionResult& r, const TensionSettings& s) {
  const bool zero = std::abs(r.ply_angle) < 1e-12 && s.layup.empty();
  struct Row {
    std::string name;
    double dem, clt, scale;
    bool modulus;
  };
  const Row rows[] = {
      {zero ? "E1  (Ex)" : "Ex", r.dem.Ex, r.theory.Ex, kGPaPerPa, true},
      {zero ? "E2  (Ey)" : "Ey", r.dem.Ey, r.theory.Ey, kGPaPerPa, true},
      {zero ? "nu12 (nu_xy)" : "nu_xy", r.dem.nu_xy, r.theory.nu_xy, 1, false},
      {zero ? "nu21 (nu_yx)" : "nu_yx", r.dem.nu_yx, r.theory.nu_yx, 1, false},
  };
  std::string out;
  const std::string specimen =
      s.layup.empty()
          ? fmt::format("ply angle {:g} deg", r.ply_angle / kDegree)
          : fmt::format("laminate {} (interface {:.3g} / {:.3g} N/m^3)", format_layup(s.layup),
                        s.interface.resolved(r.material, s.coupon.thickness).normal,
                        s.interface.resolved(r.material, s.coupon.thickness).shear);
  out += fmt::format("plydem tension test: strategy {}, material {}, {}, grips {}\n", r.strategy,
                     r.material.name, specimen, grips_name(s.grips));
  out += fmt::format("coupon {:g} mm x {:g} mm x {:g} mm{}, particle diameter {:g} mm\n\n",
                     s.coupon.length * kMmPerMetre, s.coupon.width * kMmPerMetre,
                     s.coupon.thickness * kMmPerMetre, s.layup.empty() ? "" : " per ply",
                     s.coupon.particle_diameter * kMmPerMetre);
  out += fmt::format("{:<14} {:>12} {:>12} {:>10}\n", "", "DEM", "CLT", "rel. error");
  for (const Row& row : rows) {
    const std::string unit = row.modulus ? " GPa" : "";
    const int digits = row.modulus ? 3 : 4;
    out += fmt::format("{:<14} {:>12} {:>12} {:>+9.3f}%\n", row.name,
                       fmt::format("{:.{}f}{}", row.dem * row.scale, digits, unit),
                       fmt::format("{:.{}f}{}", row.clt * row.scale, digits, unit),
                       100.0 * (row.dem - row.clt) / row.clt);
  }
  if (r.specimen.volume > 0) {
    out += fmt::format("{:<14} {:>12} {:>12} {:>+9.3f}%\n", zero ? "G12 (Gxy)" : "Gxy",
                       fmt::format("{:.3f} GPa", r.dem.Gxy * kGPaPerPa),
                       fmt::format("{:.3f} GPa", r.theory.Gxy * kGPaPerPa),
                       100.0 * (r.dem.Gxy - r.theory.Gxy) / r.theory.Gxy);
  }
  out += fmt::format("{:<14} {:>12.4f} {:>12.4f}\n", "g_xy/e_x", r.dem.shear_coupling_x,
                     r.theory.shear_coupling_x);
  out += fmt::format("\nreciprocity nu_yx*Ex / (nu_xy*Ey) = {:.5f}\n",
                     r.dem.nu_yx * r.dem.Ex / (r.dem.nu_xy * r.dem.Ey));
  for (const PullResult* pull : {&r.along_x, &r.along_y}) {
    const std::string run =
        s.solver == TensionSolver::kStatic
            ? fmt::format("static solve ({}{}), relative residual {:.2g}", pull->linear_solver,
                          pull->linear_iterations > 0
                              ? fmt::format(", {} iterations", pull->linear_iterations)
                              : std::string(),
                          pull->final_ratio)
            : fmt::format("{} cycles (dt {:.3g} s), unbalanced ratio {:.2g}", pull->cycles,
                          pull->time_step, pull->final_ratio);
    out += fmt::format("coupon at {:>6.1f} deg: {} particles, {} bonds, {}, {:.2f} s\n",
                       pull->ply_angle / kDegree, pull->particles, pull->bonds, run,
                       pull->wall_seconds);
  }
  if (r.specimen.volume > 0) {
    out += fmt::format(
        "Gxy: membrane stiffness of the {:g} deg coupon under affine boundary displacements "
        "({} frame particles, 3 static solves, {:.2f} s)\n",
        r.ply_angle / kDegree, r.specimen.frame_particles, r.specimen.wall_seconds);
  }
  if (!s.layup.empty() && r.specimen.interior_particles > 0) {
    // A laminate's membrane stiffness as its bulk carries it (no free edge, no frame).
    const InPlaneConstants& m = r.specimen.interior_constants;
    out += fmt::format(
        "membrane stiffness, interior window ({} particles, no free edges) vs CLT: Ex {:+.2f}%, "
        "Ey {:+.2f}%, nu_xy {:+.4f}, Gxy {:+.2f}%\n",
        r.specimen.interior_particles, 100 * (m.Ex / r.theory.Ex - 1),
        100 * (m.Ey / r.theory.Ey - 1), m.nu_xy - r.theory.nu_xy, 100 * (m.Gxy / r.theory.Gxy - 1));
  }
  out += fmt::format("calibration: {}; relaxed stiffness vs target: {:.2e} relative\n",
                     r.calibration.method, r.calibration.relaxed_error);
  out += fmt::format("wall time {:.2f} s\n", r.wall_seconds);
  return out;
}

nlohmann::json tension_json(const TensionResult& r, const TensionSettings& s) {
  nlohmann::json j = constants_json(r.dem);
  j["theory"] = constants_json(r.theory);
  j["particles"] = r.along_x.particles;
  j["bonds"] = r.along_x.bonds;
  j["wall_seconds"] = r.wall_seconds;
  j["strategy"] = r.strategy;
  j["material"] = r.material.name;
  j["angle_deg"] = r.ply_angle / kDegree;
  if (!s.layup.empty()) {
    j["layup"] = format_layup(s.layup);
    const InterfaceStiffness interface = s.interface.resolved(r.material, s.coupon.thickness);
    j["interface"] = {{"normal_stiffness_per_area", interface.normal},
                      {"shear_stiffness_per_area", interface.shear},
                      {"lateral_radius_diameters", s.interface.lateral_radius}};
  }
  j["solver"] = s.solver == TensionSolver::kStatic ? "static" : "explicit";
  j["grips"] = grips_name(s.grips);
  j["units"] = "SI (Pa, m, s)";
  j["loading_x"] = pull_json(r.along_x);
  j["loading_y"] = pull_json(r.along_y);
  if (r.specimen.volume > 0) {
    j["specimen_stiffness"] = {
        {"method",
         "affine boundary displacements, static solves (experiments/protocols/stiffness.hpp)"},
        {"stiffness", matrix_json(r.specimen.stiffness)},
        {"constants", constants_json(r.specimen.constants)},
        {"frame_particles", r.specimen.frame_particles},
        {"linear_solver", r.specimen.linear_solver},
        {"linear_iterations", r.specimen.linear_iterations},
        {"linear_solver_choice", r.specimen.linear_solver_choice},
        {"wall_seconds", r.specimen.wall_seconds}};
    if (r.specimen.interior_particles > 0) {
      j["specimen_stiffness"]["interior"] = {
          {"method",
           "virial stress and fitted strain of an interior window, the same solves "
           "(experiments/protocols/stiffness.hpp)"},
          {"stiffness", matrix_json(r.specimen.interior_stiffness)},
          {"constants", constants_json(r.specimen.interior_constants)},
          {"particles", r.specimen.interior_particles},
          {"margin", r.specimen.interior_margin}};
    }
  }
  j["calibration"] = calibration_json(r.calibration);
  // What the user should know about the coupon (experiments/protocols/coupon.hpp).
  j["warnings"] = nlohmann::json::array();
  const std::string narrow = narrow_laminate_warning(s.coupon.width, s.coupon.thickness, s.layup);
  if (!narrow.empty()) j["warnings"].push_back(narrow);
  return j;
}

std::string format_same_coupon_table(const TensionResult& r, const SameCouponReference& ref) {
  struct Row {
    const char* name;
    double dem, reference, clt;
    bool modulus;
  };
  const InPlaneConstants& f = ref.constants;
  const Row rows[] = {{"Ex", r.dem.Ex, f.Ex, r.theory.Ex, true},
                      {"Ey", r.dem.Ey, f.Ey, r.theory.Ey, true},
                      {"nu_xy", r.dem.nu_xy, f.nu_xy, r.theory.nu_xy, false},
                      {"nu_yx", r.dem.nu_yx, f.nu_yx, r.theory.nu_yx, false}};
  std::string out = fmt::format("\n{}, the same coupon: {} ({:.1f} s)\n", ref.name, ref.description,
                                ref.wall_seconds);
  out += fmt::format("{:<14} {:>12} {:>12} {:>16} {:>12} {:>16}\n", "", "DEM", ref.name,
                     fmt::format("DEM vs {}", ref.name), "CLT", fmt::format("{} vs CLT", ref.name));
  for (const Row& row : rows) {
    // Moduli: relative errors; Poisson's ratios: differences (a small ratio's relative error
    // says little).
    auto value = [&](double v) {
      return row.modulus ? fmt::format("{:.3f} GPa", v * kGPaPerPa) : fmt::format("{:.4f}", v);
    };
    auto error = [&](double a, double b) {
      return row.modulus ? fmt::format("{:+.3f}%", 100.0 * (a - b) / b)
                         : fmt::format("{:+.4f}", a - b);
    };
    out += fmt::format("{:<14} {:>12} {:>12} {:>16} {:>12} {:>16}\n", row.name, value(row.dem),
                       value(row.reference), error(row.dem, row.reference), value(row.clt),
                       error(row.reference, row.clt));
  }
  return out;
}

nlohmann::json same_coupon_json(const TensionResult& r, const SameCouponReference& ref) {
  nlohmann::json j = constants_json(ref.constants);
  j.erase("Gxy");
  j["description"] = ref.description;
  j["wall_seconds"] = ref.wall_seconds;
  j["dem_error"] = {{"Ex", (r.dem.Ex - ref.constants.Ex) / ref.constants.Ex},
                    {"Ey", (r.dem.Ey - ref.constants.Ey) / ref.constants.Ey},
                    {"nu_xy", r.dem.nu_xy - ref.constants.nu_xy},
                    {"nu_yx", r.dem.nu_yx - ref.constants.nu_yx}};
  return j;
}

nlohmann::json refusal_json(const Unreachable& r) {
  return {{"strategy", r.strategy},
          {"material", r.material},
          {"angle_deg", r.ply_angle / kDegree},
          {"reason", r.reason},
          {"frame", r.frame},
          {"components", r.components},
          {"target", matrix_json(r.target)},
          {"nearest", matrix_json(r.nearest)},
          {"relative_error", r.relative_error()},
          {"representing", r.representing},
          {"representing_looked_up", r.looked_up},
          {"message", r.message()}};
}

nlohmann::json calibration_json(const Calibration& c) {
  nlohmann::json families = nlohmann::json::array();
  for (const FamilyCalibration& f : c.families) {
    families.push_back({{"family", f.label},
                        {"direction_deg", f.direction / kDegree},
                        {"normal_stiffness", f.stiffness.normal},
                        {"shear_stiffness", f.stiffness.shear}});
  }
  return {{"method", c.method},
          {"lattice_angle_deg", c.lattice_angle / kDegree},
          {"families", families},
          {"target", matrix_json(c.target)},
          {"affine", matrix_json(c.affine)},
          {"relaxed", matrix_json(c.relaxed)},
          {"relaxed_relative_error", c.relaxed_error}};
}

std::string format_calibration(const Calibration& c, const std::string& strategy,
                               const Material& material, double ply_angle) {
  std::string out = fmt::format(
      "plydem calibration: strategy {}, material {}, ply angle {:g} deg\n{}\nlattice "
      "orientation: {:g} deg from x\n\n",
      strategy, material.name, ply_angle / kDegree, c.method, c.lattice_angle / kDegree);
  // Bending and twisting follow from k_n, k_s and the bond radius of the built coupon (for a
  // circular parallel bond k_b = k_n R^2/4, k_t = k_s R^2/2); a uniform strain does not load them.
  out += fmt::format("{:<24} {:>9} {:>13} {:>13}\n", "bond family", "dir [deg]", "k_n [N/m]",
                     "k_s [N/m]");
  for (const FamilyCalibration& f : c.families) {
    out += fmt::format("{:<24} {:>9.2f} {:>13.6g} {:>13.6g}\n", f.label, f.direction / kDegree,
                       f.stiffness.normal, f.stiffness.shear);
  }
  out +=
      "\nplane-stress stiffness (xx, yy, xy) [GPa]: target Q-bar | relaxed (as simulated) | "
      "affine (eq. 5)\n";
  for (int r = 0; r < 3; ++r) {
    std::string line;
    for (const Eigen::Matrix3d* m : {&c.target, &c.relaxed, &c.affine}) {
      line += fmt::format("{:9.4f} {:9.4f} {:9.4f}   ", (*m)(r, 0) * kGPaPerPa,
                          (*m)(r, 1) * kGPaPerPa, (*m)(r, 2) * kGPaPerPa);
    }
    out += line + "\n";
  }
  out += fmt::format("relaxed vs target: {:.3e} relative (Frobenius)\n", c.relaxed_error);
  if (is_positive_definite(c.relaxed)) {
    const InPlaneConstants t = in_plane_constants(c.target), m = in_plane_constants(c.relaxed);
    out += fmt::format(
        "as simulated: Ex {:.4f} Ey {:.4f} Gxy {:.4f} GPa, nu_xy {:.4f} (target {:.4f} {:.4f} "
        "{:.4f} GPa, {:.4f})\n",
        m.Ex * kGPaPerPa, m.Ey * kGPaPerPa, m.Gxy * kGPaPerPa, m.nu_xy, t.Ex * kGPaPerPa,
        t.Ey * kGPaPerPa, t.Gxy * kGPaPerPa, t.nu_xy);
  }
  return out;
}

}  // namespace plydem
