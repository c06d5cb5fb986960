#include "core/model.hpp"

#include <fmt/format.h>

#include <cmath>
#include <cstddef>
#include <set>
#include <string>
#include <utility>

#include "core/error.hpp"
#include "core/units.hpp"

namespace plydem {

namespace {

// The generic row operations, once for every field of a struct (Particles or Bonds).

template <class S>
void resize_fields(S& s, int n) {
  S::for_each_field([&](FieldInfo info, auto member) {
    auto& a = s.*member;
    using Scalar = typename FieldType<decltype(member)>::Scalar;
    a.setConstant(n, a.cols(), static_cast<Scalar>(info.fill));
  });
}

template <class S>
void append_fields(S& to, const S& from, int particle_offset) {
  S::for_each_field([&](FieldInfo info, auto member) {
    auto& a = to.*member;
    const auto& b = from.*member;
    FieldType<decltype(member)> joined(a.rows() + b.rows(), a.cols());
    joined.topRows(a.rows()) = a;
    joined.bottomRows(b.rows()) = b;
    if constexpr (field_kind<FieldType<decltype(member)>>() == FieldKind::kInt) {
      if (info.particle_index) joined.bottomRows(b.rows()) += particle_offset;
    }
    a = std::move(joined);
  });
}

template <class S>
S select_fields(const S& s, const std::vector<int>& rows, const char* what) {
  const int n = s.size();
  for (std::size_t r = 0; r < rows.size(); ++r) {
    if (!(rows[r] >= 0 && rows[r] < n))
      throw Error(
          fmt::format("selecting {}: entry {} names {} {} of {}", what, r, what, rows[r], n));
  }
  S out;
  S::for_each_field([&](FieldInfo, auto member) {
    const auto& a = s.*member;
    auto& b = out.*member;
    b.resize(static_cast<Eigen::Index>(rows.size()), a.cols());
    for (std::size_t r = 0; r < rows.size(); ++r)
      b.row(static_cast<Eigen::Index>(r)) = a.row(rows[r]);
  });
  return out;
}

void require_permutation(const std::vector<int>& order, int count, const char* what) {
  if (static_cast<int>(order.size()) != count)
    throw Error(
        fmt::format("a permutation of {} lists {}, there are {}", what, order.size(), count));
  std::vector<char> seen(static_cast<std::size_t>(count), 0);
  for (int k = 0; k < count; ++k) {
    const int i = order[k];
    if (!(i >= 0 && i < count) || seen[i])
      throw Error(fmt::format("a permutation of {} is not one: entry {} names {} {}", what, k, i,
                              (i >= 0 && i < count) ? "twice" : "that does not exist"));
    seen[i] = 1;
  }
}

template <class S>
void check_field_sizes(const S& s, const char* what) {
  const int n = s.size();
  S::for_each_field([&](FieldInfo info, auto member) {
    const auto rows = (s.*member).rows();
    if (rows != n)
      throw Error(fmt::format("{} arrays differ in size: '{}' has {} rows, there are {} {}", what,
                              info.name, rows, n, what));
  });
}

// The strength fields of bond k: what core/bond_failure.hpp needs to decide.
void check_bond_strength(const Bonds& b, int k) {
  const bool breakable = std::isfinite(b.tensile_strength(k)) || std::isfinite(b.cohesion(k));
  for (const auto& [name, value] : {std::pair{"tensile strength", b.tensile_strength(k)},
                                    std::pair{"cohesion", b.cohesion(k)}}) {
    if (!(value > 0))
      throw Error(
          fmt::format("bond {} has a {} of {} Pa: a strength must be positive (+inf for "
                      "a bond that never breaks)",
                      k, name, value));
  }
  if (breakable && !(std::isfinite(b.strength_radius(k)) && b.strength_radius(k) > 0))
    throw Error(fmt::format("bond {} has a strength but its cross-section radius is {} m", k,
                            b.strength_radius(k)));
  if (!(std::isfinite(b.friction_coefficient(k)) && b.friction_coefficient(k) >= 0))
    throw Error(fmt::format("bond {} has a friction coefficient of {} (must be finite and >= 0)", k,
                            b.friction_coefficient(k)));
  if (!(std::isfinite(b.ductility(k)) && b.ductility(k) >= 1))
    throw Error(fmt::format("bond {} has a ductility of {} (kappa_u >= 1; 1 = brittle)", k,
                            b.ductility(k)));
  const double eta = b.mixed_mode_exponent(k);
  if (!(std::isfinite(eta) && eta >= 0))
    throw Error(fmt::format(
        "bond {} has a mixed-mode exponent of {} (must be finite and >= 0; 0 = PFC's law)", k,
        eta));
  if (eta > 0) {
    for (const auto& [name, value] :
         {std::pair{"fracture energy ratio GIIc/GIc", b.fracture_energy_ratio(k)},
          std::pair{"peak energy ratio", b.peak_energy_ratio(k)}}) {
      if (!(std::isfinite(value) && value > 0))
        throw Error(fmt::format("mixed-mode bond {} has a {} of {} (must be finite and > 0)", k,
                                name, value));
    }
    if (b.friction_coefficient(k) != 0)
      throw Error(fmt::format(
          "mixed-mode bond {} has a friction coefficient of {}: the quadratic criterion has no "
          "friction term (it must be 0)",
          k, b.friction_coefficient(k)));
  }
  if (!(b.damage(k) >= 0 && b.damage(k) <= 1))
    throw Error(fmt::format("bond {} has a damage of {} (must lie in [0, 1])", k, b.damage(k)));
  if (!(b.state(k) >= 0 && b.state(k) <= static_cast<int>(BondState::kBrokenShear)))
    throw Error(
        fmt::format("bond {} has state {}, which is no BondState (0 intact, 1 broken in "
                    "tension, 2 broken in shear)",
                    k, b.state(k)));
}

}  // namespace

void Particles::resize(int n) {
  resize_fields(*this, n);
}

void Particles::append(const Particles& other) {
  append_fields(*this, other, 0);
}

Particles Particles::select(const std::vector<int>& rows) const {
  return select_fields(*this, rows, "particle");
}

void Particles::permute(const std::vector<int>& order) {
  require_permutation(order, size(), "particles");
  *this = select(order);
}

void Particles::check_sizes() const {
  check_field_sizes(*this, "particle");
}

void Bonds::resize(int n) {
  resize_fields(*this, n);
}

void Bonds::append(const Bonds& other, int particle_offset) {
  append_fields(*this, other, particle_offset);
}

Bonds Bonds::select(const std::vector<int>& rows) const {
  return select_fields(*this, rows, "bond");
}

void Bonds::permute(const std::vector<int>& order) {
  require_permutation(order, size(), "bonds");
  *this = select(order);
}

void Bonds::rename_particles(const std::vector<int>& new_index) {
  const int n = static_cast<int>(new_index.size());
  for_each_field([&](FieldInfo info, auto member) {
    if constexpr (field_kind<FieldType<decltype(member)>>() == FieldKind::kInt) {
      if (!info.particle_index) return;
      auto& a = this->*member;
      for (Eigen::Index b = 0; b < a.size(); ++b) {
        if (!(a(b) >= 0 && a(b) < n && new_index[a(b)] >= 0))
          throw Error(
              fmt::format("bond {} refers to a missing particle ({}, {})", b, first(b), second(b)));
      }
      for (Eigen::Index b = 0; b < a.size(); ++b) a(b) = new_index[a(b)];
    }
  });
}

void Bonds::assign_rows(const std::vector<int>& rows, const Bonds& from) {
  require(static_cast<int>(rows.size()) == from.size(),
          fmt::format("assigning {} bonds to {} rows", from.size(), rows.size()));
  for (std::size_t r = 0; r < rows.size(); ++r)
    require(rows[r] >= 0 && rows[r] < size(),
            fmt::format("assigning bonds: row {} is not one of the {} bonds", rows[r], size()));
  for_each_field([&](FieldInfo, auto member) {
    auto& a = this->*member;
    const auto& b = from.*member;
    for (std::size_t r = 0; r < rows.size(); ++r)
      a.row(rows[r]) = b.row(static_cast<Eigen::Index>(r));
  });
}

void Bonds::check_sizes() const {
  check_field_sizes(*this, "bond");
}

Model select_particles(const Model& model, const std::vector<int>& kept) {
  const int n = model.particles.size();
  std::vector<int> new_index(static_cast<std::size_t>(n), -1);
  for (std::size_t k = 0; k < kept.size(); ++k) {
    const int i = kept[k];
    if (!(i >= 0 && i < n) || new_index[i] >= 0)
      throw Error(fmt::format("selecting particles: entry {} names particle {} {}", k, i,
                              (i >= 0 && i < n) ? "twice" : "that does not exist"));
    new_index[i] = static_cast<int>(k);
  }
  const Bonds& b = model.bonds;
  std::vector<int> kept_bonds;
  for (int c = 0; c < b.size(); ++c) {
    const int i = b.first(c), j = b.second(c);
    if (!(i >= 0 && i < n && j >= 0 && j < n))
      throw Error(fmt::format("bond {} refers to a missing particle ({}, {})", c, i, j));
    if (new_index[i] >= 0 && new_index[j] >= 0) kept_bonds.push_back(c);
  }
  Model out;
  out.thickness = model.thickness;
  out.description = model.description;
  out.particles = model.particles.select(kept);
  out.bonds = b.select(kept_bonds);
  out.bonds.rename_particles(new_index);
  return out;
}

void set_bond_geometry(const Particles& particles, Bonds& bonds, int b) {
  const int i = bonds.first(b);
  const int j = bonds.second(b);
  const Eigen::Vector3d branch =
      (particles.reference_position.row(j) - particles.reference_position.row(i))
          .matrix()
          .transpose();
  const double length = branch.norm();
  if (!(length > 0)) {
    throw Error(fmt::format("bond {} joins particles {} and {} at the same position", b, i, j));
  }
  bonds.normal.row(b) = (branch / length).transpose().array();
  bonds.length(b) = length;
  const double gap = length - particles.radius(i) - particles.radius(j);
  bonds.lever_first(b) = particles.radius(i) + 0.5 * gap;
  bonds.lever_second(b) = particles.radius(j) + 0.5 * gap;
}

void Model::check_consistency() const {
  const int n = particles.size();
  const auto& p = particles;
  require(n > 0, "the model has no particles");
  p.check_sizes();
  for (int i = 0; i < n; ++i) {
    if (!(p.reference_position.row(i).isFinite().all()))
      throw Error(fmt::format("particle {} has a non-finite position", i));
    if (!(std::isfinite(p.mass(i)) && p.mass(i) > 0))
      throw Error(fmt::format("particle {} has a non-positive mass {}", i, p.mass(i)));
    if (!(std::isfinite(p.moment_of_inertia(i)) && p.moment_of_inertia(i) > 0))
      throw Error(fmt::format("particle {} has a non-positive moment of inertia", i));
    if (!(std::isfinite(p.radius(i)) && p.radius(i) > 0))
      throw Error(fmt::format("particle {} has a non-positive radius", i));
  }
  const Bonds& b = bonds;
  const int m = b.size();
  b.check_sizes();
  std::set<std::pair<int, int>> seen;
  for (int k = 0; k < m; ++k) {
    const int i = b.first(k), j = b.second(k);
    if (!(i >= 0 && i < n && j >= 0 && j < n))
      throw Error(fmt::format("bond {} refers to a missing particle ({}, {})", k, i, j));
    if (!(i != j)) throw Error(fmt::format("bond {} joins particle {} to itself", k, i));
    if (!(seen.insert({std::min(i, j), std::max(i, j)}).second))
      throw Error(
          fmt::format("bond {} duplicates another bond between particles {} and {}", k, i, j));
    for (double s : {b.normal_stiffness(k), b.shear_stiffness(k), b.bending_stiffness(k),
                     b.twisting_stiffness(k)}) {
      if (!(std::isfinite(s) && s >= 0))
        throw Error(
            fmt::format("bond {} has a negative or non-finite stiffness {}: the calibration "
                        "produced an unstable lattice",
                        k, s));
    }
    if (!(std::isfinite(b.out_of_plane_shear_ratio(k)) && b.out_of_plane_shear_ratio(k) >= 0))
      throw Error(
          fmt::format("bond {} has an out-of-plane shear ratio of {} (k_z / k_s must be "
                      "finite and >= 0)",
                      k, b.out_of_plane_shear_ratio(k)));
    if (!(std::isfinite(b.length(k)) && b.length(k) > 0))
      throw Error(fmt::format("bond {} has a non-positive length", k));
    if (!(std::abs(b.normal.row(k).matrix().norm() - 1.0) < 1e-12))
      throw Error(fmt::format("bond {} has a normal that is not a unit vector", k));
    if (!(b.kind(k) == static_cast<int>(BondKind::kInPly) ||
          b.kind(k) == static_cast<int>(BondKind::kInterface)))
      throw Error(fmt::format("bond {} has kind {}, which is no BondKind (0 in-ply, 1 interface)",
                              k, b.kind(k)));
    check_bond_strength(b, k);
  }
}

bool Bonds::breakable() const {
  for (int k = 0; k < size(); ++k) {
    if (std::isfinite(tensile_strength(k)) || std::isfinite(cohesion(k))) return true;
  }
  return false;
}

std::string describe_particle(const Particles& particles, int i) {
  const auto& x = particles.reference_position;
  return fmt::format("particle {} at ({:.4g}, {:.4g}, {:.4g}) mm", i, kMmPerMetre * x(i, 0),
                     kMmPerMetre * x(i, 1), kMmPerMetre * x(i, 2));
}

}  // namespace plydem
