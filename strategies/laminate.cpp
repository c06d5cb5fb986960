#include "strategies/laminate.hpp"

#include <fmt/format.h>

#include <cctype>
#include <cmath>
#include <numbers>

#include "contacts/cell_list.hpp"
#include "core/error.hpp"
#include "core/stopwatch.hpp"

namespace plydem {

void InterfaceStiffness::validate() const {
  const std::pair<const char*, double> values[] = {{"interface normal stiffness", normal},
                                                   {"interface shear stiffness", shear}};
  for (const auto& [name, value] : values) {
    require(std::isfinite(value) && value >= 0,
            fmt::format("{} must be >= 0 N/m^3 (0 = perfectly bonded), got {}", name, value));
  }
  require(std::isfinite(lateral_radius) && lateral_radius > 0,
          fmt::format("interface lateral radius must be positive, got {}", lateral_radius));
}

InterfaceStiffness InterfaceStiffness::resolved(const Material& material, double thickness) const {
  InterfaceStiffness r = *this;
  if (r.normal == 0) r.normal = 10 * material.E2 / thickness;
  if (r.shear == 0) r.shear = (transverse_shear ? 100 : 10) * material.G12 / thickness;
  return r;
}

std::vector<Ply> laminate_plies(const LaminateSpec& spec) {
  std::vector<Ply> plies;
  for (double angle : spec.ply_angles) {
    plies.push_back({spec.coupon.material, angle, spec.coupon.thickness});
  }
  return plies;
}

namespace {

// InterfaceStiffness::transverse_shear: the out-of-plane shear ratio of ply k's in-ply bonds (see
// the header), so that the ply carries t diag(G13, G23) in its axes.
void set_ply_transverse_shear(Specimen& specimen, int k, const Material& material, double angle,
                              double thickness, const std::string& strategy) {
  Model& model = specimen.model;
  const Particles& p = model.particles;
  Bonds& bonds = model.bonds;
  const std::vector<FamilyCalibration>& families = specimen.ply_calibrations[k].families;
  struct Term {
    int bond;
    double weight;  // w_b
    Eigen::Vector2d direction;
  };
  std::vector<Term> terms;
  double area = 0;
  for (int i = 0; i < p.size(); ++i)
    if (p.ply(i) == k) area += p.volume(i) / thickness;
  for (int b = 0; b < bonds.size(); ++b) {
    if (bonds.is_interface(b) || p.ply(bonds.first(b)) != k) continue;
    const Eigen::Vector3d n = bonds.normal.row(b).transpose();
    require(std::abs(n.z()) < 1e-9,
            fmt::format("transverse shear in the plies needs plies of one particle layer (every "
                        "in-ply bond in the ply's plane), but strategy {} bonds ply {} out of its "
                        "plane (bond {}); build this laminate without interface transverse_shear, "
                        "or with hex2d or square",
                        strategy, k + 1, b));
    const int f = bonds.family(b);
    require(f >= 0 && f < static_cast<int>(families.size()),
            fmt::format("transverse shear: bond {} of ply {} has family {} of {}", b, k + 1, f,
                        families.size()));
    const double bulk = families[f].stiffness.shear;
    if (bulk <= 0 || bonds.shear_stiffness(b) <= 0) continue;
    terms.push_back({b, bonds.shear_stiffness(b) / bulk, Eigen::Vector2d(n.x(), n.y())});
  }
  require(!terms.empty(),
          fmt::format("transverse shear in the plies: strategy {} gives ply {} no bond with a "
                      "shear stiffness to carry it",
                      strategy, k + 1));
  // sum_b w_b (d^T Q d) d d^T = A t G_t, Q = [[q0, q2], [q2, q1]]: three equations (xx, yy, xy).
  const double c = std::cos(angle), s = std::sin(angle);
  Eigen::Matrix2d rotation;
  rotation << c, -s, s, c;
  const Eigen::Matrix2d target = area * thickness * rotation *
                                 Eigen::Vector2d(material.G12, material.G23()).asDiagonal() *
                                 rotation.transpose();
  auto components = [](const Eigen::Vector2d& d) {
    return Eigen::Vector3d(d.x() * d.x(), d.y() * d.y(), 2 * d.x() * d.y());
  };
  Eigen::Matrix3d system = Eigen::Matrix3d::Zero();
  for (const Term& t : terms) {
    const Eigen::Vector3d q = components(t.direction);  // d^T Q d = q . (q0, q1, q2)
    const Eigen::Vector3d e(t.direction.x() * t.direction.x(), t.direction.y() * t.direction.y(),
                            t.direction.x() * t.direction.y());  // (xx, yy, xy) of d d^T
    system += t.weight * e * q.transpose();
  }
  const Eigen::Vector3d rhs(target(0, 0), target(1, 1), target(0, 1));
  const Eigen::FullPivLU<Eigen::Matrix3d> lu(system);
  require(lu.rank() == 3,
          fmt::format("transverse shear in the plies: the in-ply bonds of ply {} (strategy {}) "
                      "span too few directions to carry both G13 and G23",
                      k + 1, strategy));
  const Eigen::Vector3d qv = lu.solve(rhs);
  for (const Term& t : terms) {
    const double q = components(t.direction).dot(qv);
    require(q >= 0, fmt::format("transverse shear in the plies: ply {} (strategy {}) would need a "
                                "negative out-of-plane shear stiffness along bond {}",
                                k + 1, strategy, t.bond));
    const double length = bonds.length(t.bond);
    const double k_z = t.weight * q / (length * length);
    bonds.out_of_plane_shear_ratio(t.bond) = k_z / bonds.shear_stiffness(t.bond);
  }
}

}  // namespace

Specimen build_laminate(const Strategy& strategy, const LaminateSpec& spec) {
  SpecimenBuilder builder(strategy);
  return build_laminate(builder, spec);
}

Specimen build_laminate(SpecimenBuilder& builder, const LaminateSpec& spec) {
  const Stopwatch clock;
  require(!spec.ply_angles.empty(), "a laminate needs at least one ply");
  spec.coupon.validate();
  spec.interface.validate();
  const double t = spec.coupon.thickness;
  const double d = spec.coupon.particle_diameter;
  const int plies = static_cast<int>(spec.ply_angles.size());
  const InterfaceStiffness interface = spec.interface.resolved(spec.coupon.material, t);

  // The plies, each built with its own angle's calibration (calibrated and built once per
  // distinct ply: SpecimenBuilder::ply), stacked along z.
  Specimen specimen;
  std::vector<Model> ply_models;
  int particles = 0;
  for (int k = 0; k < plies; ++k) {
    CouponSpec coupon = spec.coupon;
    coupon.ply_angle = spec.ply_angles[k];
    const Specimen& built = builder.ply(coupon);
    specimen.ply_calibrations.push_back(built.ply_calibrations.front());
    Model ply = built.model;
    ply.particles.reference_position.col(2) += k * t;
    ply.particles.ply.setConstant(k);
    particles += ply.particles.size();
    ply_models.push_back(std::move(ply));
  }

  // Interface bonds between the facing surfaces of adjacent plies, found in the x-y plane.
  struct InterfaceBond {
    int first, second, interface;
  };
  std::vector<InterfaceBond> interface_bonds;
  std::vector<int> offset(plies + 1, 0);
  for (int k = 0; k < plies; ++k) offset[k + 1] = offset[k] + ply_models[k].particles.size();
  for (int k = 0; k + 1 < plies; ++k) {
    const Particles& lower = ply_models[k].particles;
    const Particles& upper = ply_models[k + 1].particles;
    const double top = lower.reference_position.col(2).maxCoeff();
    const double bottom = upper.reference_position.col(2).minCoeff();
    std::vector<int> global;
    std::vector<bool> from_lower;
    for (int i = 0; i < lower.size(); ++i) {
      if (lower.reference_position(i, 2) >= top - 0.5 * d) {
        global.push_back(offset[k] + i);
        from_lower.push_back(true);
      }
    }
    for (int i = 0; i < upper.size(); ++i) {
      if (upper.reference_position(i, 2) <= bottom + 0.5 * d) {
        global.push_back(offset[k + 1] + i);
        from_lower.push_back(false);
      }
    }
    PositionArray flat(static_cast<Eigen::Index>(global.size()), 3);
    for (std::size_t s = 0; s < global.size(); ++s) {
      const Particles& p = from_lower[s] ? lower : upper;
      const int local = global[s] - offset[from_lower[s] ? k : k + 1];
      flat.row(static_cast<Eigen::Index>(s)) << p.reference_position(local, 0),
          p.reference_position(local, 1), 0.0;
    }
    // |x_i - x_j| <= contact_radius * (r_i + r_j) with r = d/2: contact_radius = lateral radius.
    const Eigen::ArrayXd half = Eigen::ArrayXd::Constant(flat.rows(), 0.5);
    const double scale = d;  // work in diameters
    const int before = static_cast<int>(interface_bonds.size());
    for (const auto& [a, b] :
         find_contact_pairs(flat / scale, half, spec.interface.lateral_radius)) {
      if (from_lower[a] == from_lower[b]) continue;
      const int i = from_lower[a] ? global[a] : global[b];
      const int j = from_lower[a] ? global[b] : global[a];
      interface_bonds.push_back({i, j, k});
    }
    require(static_cast<int>(interface_bonds.size()) > before,
            fmt::format("no interface bonds between plies {} and {}", k + 1, k + 2));
  }

  Model& model = specimen.model;
  model.thickness = plies * t;
  model.description =
      fmt::format("{} laminate of {} plies ({}), {} particles, interface {:.3g} / {:.3g} N/m^3",
                  format_layup(spec.ply_angles), plies, ply_models.front().description, particles,
                  interface.normal, interface.shear);
  Particles& p = model.particles;
  Bonds& b = model.bonds;
  for (int k = 0; k < plies; ++k) {
    p.append(ply_models[k].particles);
    b.append(ply_models[k].bonds, offset[k]);
  }
  // Each particle's interface area (its volume over the ply thickness), split over its bonds.
  std::vector<int> count(particles, 0);
  for (const InterfaceBond& ib : interface_bonds) {
    ++count[ib.first];
    ++count[ib.second];
  }
  Bonds between;
  between.resize(static_cast<int>(interface_bonds.size()));
  for (int c = 0; c < between.size(); ++c) {
    const InterfaceBond& ib = interface_bonds[c];
    const double area = 0.5 * (p.volume(ib.first) / t / count[ib.first] +
                               p.volume(ib.second) / t / count[ib.second]);
    between.first(c) = ib.first;
    between.second(c) = ib.second;
    between.normal_stiffness(c) = interface.normal * area;
    between.shear_stiffness(c) = interface.shear * area;
    between.bending_stiffness(c) = 0;
    between.twisting_stiffness(c) = 0;
    between.family(c) = ib.interface;
    between.kind(c) = static_cast<int>(BondKind::kInterface);
    set_bond_geometry(p, between, c);
  }
  b.append(between);
  if (interface.transverse_shear)
    for (int k = 0; k < plies; ++k)
      set_ply_transverse_shear(specimen, k, spec.coupon.material, spec.ply_angles[k], t,
                               builder.strategy().description());
  model.check_consistency();
  specimen.build_seconds = clock.seconds();
  return specimen;
}

}  // namespace plydem
