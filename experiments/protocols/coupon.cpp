#include "experiments/protocols/coupon.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/error.hpp"
#include "core/measurements.hpp"

namespace plydem {

Specimen build_coupon(SpecimenBuilder& builder, const CouponSpec& coupon,
                      const std::vector<double>& layup, const InterfaceStiffness& interface,
                      double ply_angle) {
  CouponSpec spec = coupon;
  spec.ply_angle = ply_angle;
  if (layup.empty()) return builder.build(spec);
  LaminateSpec laminate{spec, layup, interface};
  for (double& angle : laminate.ply_angles) angle += ply_angle - coupon.ply_angle;
  return build_laminate(builder, laminate);
}

CouponGrips assign_grips(Particles& p, double grip) {
  CouponGrips g;
  g.x_min = p.reference_position.col(0).minCoeff();
  g.x_max = p.reference_position.col(0).maxCoeff();
  g.span = g.x_max - g.x_min;
  require(g.span > 2 * grip,
          fmt::format("the grips ({} mm each) leave no free length in a {} mm coupon", grip * 1e3,
                      g.span * 1e3));
  for (int i = 0; i < p.size(); ++i) {
    const double x = p.reference_position(i, 0);
    if (x <= g.x_min + grip) {
      p.group(i) = static_cast<int>(BoundaryGroup::kLeftGrip);
      ++g.left;
    } else if (x >= g.x_max - grip) {
      p.group(i) = static_cast<int>(BoundaryGroup::kRightGrip);
      ++g.right;
    }
  }
  require(g.left > 0 && g.right > 0, "a grip holds no particle");
  return g;
}

GripFaces grip_faces(const Particles& p) {
  GripFaces faces{-std::numeric_limits<double>::infinity(),
                  std::numeric_limits<double>::infinity()};
  for (int i = 0; i < p.size(); ++i) {
    const double x = p.reference_position(i, 0);
    if (p.group(i) == static_cast<int>(BoundaryGroup::kLeftGrip))
      faces.left = std::max(faces.left, x);
    else if (p.group(i) == static_cast<int>(BoundaryGroup::kRightGrip))
      faces.right = std::min(faces.right, x);
  }
  require(std::isfinite(faces.left) && std::isfinite(faces.right), "a grip holds no particle");
  return faces;
}

DofConstraints grip_constraints(const Particles& p, double left_ux, double right_ux,
                                GripCondition grips) {
  DofConstraints constraints(p.size());
  const bool clamped = grips == GripCondition::kClamped;
  for (int i = 0; i < p.size(); ++i) {
    const int g = p.group(i);
    if (g == static_cast<int>(BoundaryGroup::kFree)) continue;
    constraints.fix(i, Dof::kUx,
                    g == static_cast<int>(BoundaryGroup::kRightGrip) ? right_ux : left_ux);
    constraints.fix(i, Dof::kUz);
    constraints.fix(i, Dof::kThetaX);
    constraints.fix(i, Dof::kThetaY);
    if (clamped) {
      constraints.fix(i, Dof::kUy);
      constraints.fix(i, Dof::kThetaZ);
    }
  }
  return constraints;
}

DofConstraints uniform_grip_constraints(const Particles& p, const Eigen::Vector3d& strain,
                                        const std::vector<double>& ply_spin) {
  std::vector<bool> held(static_cast<std::size_t>(p.size()));
  for (int i = 0; i < p.size(); ++i)
    held[static_cast<std::size_t>(i)] = p.group(i) != static_cast<int>(BoundaryGroup::kFree);
  return uniform_grip_constraints(p, strain, ply_spin, held);
}

DofConstraints uniform_grip_constraints(const Particles& p, const Eigen::Vector3d& strain,
                                        const std::vector<double>& ply_spin,
                                        const std::vector<bool>& held) {
  require(held.size() == static_cast<std::size_t>(p.size()),
          fmt::format("{} held flags for {} particles", held.size(), p.size()));
  const Eigen::Vector3d low = p.reference_position.colwise().minCoeff().transpose();
  const Eigen::Vector3d high = p.reference_position.colwise().maxCoeff().transpose();
  const Eigen::Vector3d centre = 0.5 * (low + high);
  DofConstraints constraints(p.size());
  for (int i = 0; i < p.size(); ++i) {
    if (!held[static_cast<std::size_t>(i)]) continue;
    require(p.ply(i) >= 0 && p.ply(i) < static_cast<int>(ply_spin.size()),
            fmt::format("particle {} of ply {} has no spin for its grip ({} plies)", i, p.ply(i),
                        ply_spin.size()));
    const double dx = p.reference_position(i, 0) - centre.x();
    const double dy = p.reference_position(i, 1) - centre.y();
    constraints.fix(i, Dof::kUx, strain(0) * dx + 0.5 * strain(2) * dy);
    constraints.fix(i, Dof::kUy, 0.5 * strain(2) * dx + strain(1) * dy);
    constraints.fix(i, Dof::kUz);
    constraints.fix(i, Dof::kThetaX);
    constraints.fix(i, Dof::kThetaY);
    constraints.fix(i, Dof::kThetaZ, ply_spin[static_cast<std::size_t>(p.ply(i))]);
  }
  return constraints;
}

StaticSettings grip_solve_settings(LinearSolverKind linear_solver, bool force) {
  StaticSettings settings;
  settings.force = force;
  settings.pin_rigid_modes = true;  // free grips leave the y translation to pin
  settings.linear_solver = linear_solver;
  return settings;
}

GaugeSection gauge_section(const Particles& p, const CouponGrips& grips, double gauge_fraction,
                           double edge_band_diameters, double particle_diameter) {
  require(std::isfinite(gauge_fraction) && gauge_fraction > 0 && gauge_fraction < 1,
          fmt::format("gauge fraction must lie in (0, 1), got {}", gauge_fraction));
  GaugeSection gauge;
  const double x_mid = 0.5 * (grips.x_min + grips.x_max);
  const double half = 0.5 * gauge_fraction * grips.span;
  gauge.x_begin = x_mid - half;
  gauge.x_end = x_mid + half;
  const double y_min = p.reference_position.col(1).minCoeff();
  const double y_max = p.reference_position.col(1).maxCoeff();
  const double band = std::min(edge_band_diameters * particle_diameter, 0.25 * (y_max - y_min));
  for (int i : particles_between(p, gauge.x_begin, gauge.x_end)) {
    const double y = p.reference_position(i, 1);
    if (y >= y_min + band && y <= y_max - band) gauge.particles.push_back(i);
  }
  gauge.cross_section = cross_section_area(p, gauge.x_begin, gauge.x_end,
                                           std::min(4.0 * particle_diameter, 0.25 * half));
  return gauge;
}

double grip_stress(const Particles& p, double cross_section) {
  double left_force = 0, right_force = 0;
  for (int i = 0; i < p.size(); ++i) {
    if (p.group(i) == static_cast<int>(BoundaryGroup::kLeftGrip)) left_force += p.force(i, 0);
    if (p.group(i) == static_cast<int>(BoundaryGroup::kRightGrip)) right_force += p.force(i, 0);
  }
  // The bonds pull the right grip towards -x and the left one towards +x.
  return 0.5 * (left_force - right_force) / cross_section;
}

std::string narrow_laminate_warning(double width, double thickness,
                                    const std::vector<double>& layup) {
  const double laminate = thickness * static_cast<double>(layup.size());
  if (layup.size() < 2 || !(width < kFreeEdgeWidths * laminate)) return "";
  return fmt::format(
      "the coupon is {:g} mm wide, narrower than {:g} laminate thicknesses ({:g} x {:g} mm = {:g} "
      "mm): the free-edge zones of its plies (each about one laminate thickness wide) take up "
      "much of its width, so its moduli differ from CLT's (an infinitely wide plate) by physics, "
      "not by discretization; compare it with FEM of the same coupon, or make it at least {:g} "
      "mm wide (--width-mm) to compare with CLT",
      width * 1e3, kFreeEdgeWidths, kFreeEdgeWidths, laminate * 1e3,
      kFreeEdgeWidths * laminate * 1e3, kFreeEdgeWidths * laminate * 1e3);
}

void add_coupon_settings(CheckpointHeader& header, const std::string& strategy,
                         const std::vector<std::pair<std::string, double>>& strategy_options,
                         const CouponSpec& coupon, const std::vector<double>& layup,
                         const InterfaceStiffness& interface, double grip_length,
                         double gauge_fraction) {
  header.add("strategy", strategy);
  for (const auto& [name, value] : strategy_options)
    header.add("strategy_option." + name, exact(value));
  const Material& m = coupon.material;
  header.add("material", m.name);
  header.add("material.E1", exact(m.E1));
  header.add("material.E2", exact(m.E2));
  header.add("material.G12", exact(m.G12));
  header.add("material.nu12", exact(m.nu12));
  header.add("material.nu23", exact(m.nu23));
  header.add("material.density", exact(m.density));
  const LaminaStrength& st = m.strength;
  header.add("material.XT", exact(st.XT));
  header.add("material.XC", exact(st.XC));
  header.add("material.YT", exact(st.YT));
  header.add("material.YC", exact(st.YC));
  header.add("material.S12", exact(st.S12));
  header.add("material.G_fibre", exact(st.G_fibre));
  header.add("material.G_matrix", exact(st.G_matrix));
  header.add("material.weibull_modulus", exact(st.weibull_modulus));
  header.add("ply_angle", exact(coupon.ply_angle));
  header.add("length", exact(coupon.length));
  header.add("width", exact(coupon.width));
  header.add("thickness", exact(coupon.thickness));
  header.add("particle_diameter", exact(coupon.particle_diameter));
  header.add("complete_boundary_cells", coupon.complete_boundary_cells ? "true" : "false");
  std::string angles;
  for (double a : layup) {
    if (!angles.empty()) angles.push_back('/');
    angles.append(exact(a));
  }
  header.add("layup", angles);
  header.add("interface.normal", exact(interface.normal));
  header.add("interface.shear", exact(interface.shear));
  header.add("interface.lateral_radius", exact(interface.lateral_radius));
  if (interface.transverse_shear) header.add("interface.transverse_shear", "true");
  header.add("grip_length", exact(grip_length));
  header.add("gauge_fraction", exact(gauge_fraction));
}

}  // namespace plydem
