#include "strategies/laminate.hpp"

#include <fmt/format.h>

#include <cctype>
#include <chrono>
#include <cmath>
#include <numbers>

#include "contacts/cell_list.hpp"
#include "core/error.hpp"

namespace plydem {
namespace {

constexpr double kDegree = std::numbers::pi / 180.0;

// One angle in degrees, or the pair 45/-45 for "±45" / "+-45".
std::vector<double> parse_ply(const std::string& token, const std::string& layup) {
  std::string number = token;
  bool plus_minus = false;
  for (const std::string prefix : {"±", "+-"}) {
    if (number.rfind(prefix, 0) == 0) {
      number = number.substr(prefix.size());
      plus_minus = true;
    }
  }
  std::size_t used = 0;
  double degrees = 0;
  try {
    degrees = std::stod(number, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (number.empty() || used != number.size() || !std::isfinite(degrees)) {
    throw Error(fmt::format("layup '{}': '{}' is not a ply angle in degrees", layup, token));
  }
  if (std::abs(degrees) > 360) {
    throw Error(fmt::format("layup '{}': ply angle {} deg is out of range", layup, token));
  }
  if (plus_minus) return {degrees * kDegree, -degrees * kDegree};
  return {degrees * kDegree};
}

}  // namespace

std::vector<double> parse_layup(const std::string& text) {
  std::string layup;
  for (char c : text) {
    if (!std::isspace(static_cast<unsigned char>(c))) layup += c;
  }
  const auto open = layup.find('[');
  const auto close = layup.rfind(']');
  if (open != 0 || close == std::string::npos || close < open) {
    throw Error(fmt::format(
        "layup '{}' is not of the form [a/b/c] with an optional count and 's' after the bracket, "
        "e.g. [0/90/0], [0/30/45]s, [0/90]2s",
        text));
  }
  const std::string body = layup.substr(1, close - 1);
  std::string suffix = layup.substr(close + 1);
  bool symmetric = false;
  if (!suffix.empty() && (suffix.back() == 's' || suffix.back() == 'S')) {
    symmetric = true;
    suffix.pop_back();
  }
  int repeat = 1;
  if (!suffix.empty()) {
    std::size_t used = 0;
    try {
      repeat = std::stoi(suffix, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used != suffix.size() || repeat < 1 || repeat > 100) {
      throw Error(
          fmt::format("layup '{}': '{}' after the bracket is not a repeat count (1..100) "
                      "optionally followed by 's'",
                      text, layup.substr(close + 1)));
    }
  }
  if (body.empty()) throw Error(fmt::format("layup '{}' has no plies", text));
  std::vector<double> group;
  std::size_t start = 0;
  while (start <= body.size()) {
    const std::size_t slash = body.find('/', start);
    const std::string token =
        body.substr(start, slash == std::string::npos ? std::string::npos : slash - start);
    if (token.empty()) throw Error(fmt::format("layup '{}' has an empty ply between '/'", text));
    for (double angle : parse_ply(token, text)) group.push_back(angle);
    if (slash == std::string::npos) break;
    start = slash + 1;
  }
  std::vector<double> angles;
  for (int r = 0; r < repeat; ++r) angles.insert(angles.end(), group.begin(), group.end());
  if (symmetric) angles.insert(angles.end(), angles.rbegin(), angles.rend());
  return angles;
}

std::string format_layup(const std::vector<double>& ply_angles) {
  std::string out = "[";
  for (std::size_t k = 0; k < ply_angles.size(); ++k) {
    out += fmt::format("{}{:g}", k ? "/" : "", std::round(ply_angles[k] / kDegree * 1e6) / 1e6);
  }
  return out + "]";
}

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
  if (r.shear == 0) r.shear = 10 * material.G12 / thickness;
  return r;
}

std::vector<Ply> laminate_plies(const LaminateSpec& spec) {
  std::vector<Ply> plies;
  for (double angle : spec.ply_angles) {
    plies.push_back({spec.coupon.material, angle, spec.coupon.thickness});
  }
  return plies;
}

Specimen build_laminate(const Strategy& strategy, const LaminateSpec& spec) {
  SpecimenBuilder builder(strategy);
  return build_laminate(builder, spec);
}

Specimen build_laminate(SpecimenBuilder& builder, const LaminateSpec& spec) {
  const auto start = std::chrono::steady_clock::now();
  require(!spec.ply_angles.empty(), "a laminate needs at least one ply");
  spec.coupon.validate();
  spec.interface.validate();
  const double t = spec.coupon.thickness;
  const double d = spec.coupon.particle_diameter;
  const int plies = static_cast<int>(spec.ply_angles.size());
  const InterfaceStiffness interface = spec.interface.resolved(spec.coupon.material, t);

  // The plies, each built with its own angle's calibration (once per distinct ply), stacked
  // along z.
  Specimen specimen;
  std::vector<Model> ply_models;
  int particles = 0;
  for (int k = 0; k < plies; ++k) {
    CouponSpec coupon = spec.coupon;
    coupon.ply_angle = spec.ply_angles[k];
    Specimen built = builder.build(coupon);
    specimen.ply_calibrations.push_back(std::move(built.ply_calibrations.front()));
    Model ply = std::move(built.model);
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
  model.check_consistency();
  specimen.build_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return specimen;
}

}  // namespace plydem
