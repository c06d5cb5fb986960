#include "contacts/bond_kernel.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <numbers>
#include <numeric>
#include <set>
#include <unordered_map>

#include "contacts/particle_ordering.hpp"
#include "core/error.hpp"

namespace plydem {
namespace {

Eigen::Vector3d row3(const Vector3Array& a, int i) {
  return {a(i, 0), a(i, 1), a(i, 2)};
}

void add_row3(Vector3Array& a, int i, const Eigen::Vector3d& v) {
  a(i, 0) += v.x();
  a(i, 1) += v.y();
  a(i, 2) += v.z();
}

BondResponse evaluate(const Particles& p, const Bonds& bonds, int b) {
  const int i = bonds.first(b);
  const int j = bonds.second(b);
  return parallel_bond_response(bond_parameters(bonds, b), row3(p.displacement, i),
                                row3(p.rotation, i), row3(p.displacement, j), row3(p.rotation, j));
}

// Bond b's force and moments added to its two particles.
BondResponse add_bond_forces(Particles& p, const Bonds& bonds, int b) {
  const BondResponse r = evaluate(p, bonds, b);
  const int i = bonds.first(b);
  const int j = bonds.second(b);
  add_row3(p.force, i, r.force_on_first);
  add_row3(p.force, j, -r.force_on_first);
  add_row3(p.torque, i, r.torque_on_first);
  add_row3(p.torque, j, r.torque_on_second);
  return r;
}

}  // namespace

BondParameters bond_parameters(const Bonds& bonds, int b) {
  BondParameters params;
  params.normal = row3(bonds.normal, b);
  params.lever_first = bonds.lever_first(b);
  params.lever_second = bonds.lever_second(b);
  params.normal_stiffness = bonds.normal_stiffness(b);
  params.shear_stiffness = bonds.shear_stiffness(b);
  params.bending_stiffness = bonds.bending_stiffness(b);
  params.twisting_stiffness = bonds.twisting_stiffness(b);
  params.out_of_plane_shear_ratio = bonds.out_of_plane_shear_ratio(b);
  params.free_offset = row3(bonds.free_offset, b);
  return params;
}

BondPass compute_bond_forces(Particles& particles, const Bonds& bonds) {
  particles.force.setZero();
  particles.torque.setZero();
  BondPass pass;
  for (int b = 0; b < bonds.size(); ++b) {
    if (bonds.is_broken(b)) continue;
    const BondResponse r = add_bond_forces(particles, bonds, b);
    pass.strain_energy += r.energy;
    pass.sum_force_norm += r.force_on_first.norm();
  }
  return pass;
}

BondPass compute_listed_bond_forces(Particles& particles, const Bonds& bonds,
                                    std::span<const int> listed_bonds,
                                    std::span<const int> listed_particles, std::span<double> each) {
  require(
      each.empty() || each.size() == 2 * listed_bonds.size(),
      fmt::format("listed bond forces: {} values for {} bonds", each.size(), listed_bonds.size()));
  for (int i : listed_particles)
    for (int c = 0; c < 3; ++c) {
      particles.force(i, c) = 0;
      particles.torque(i, c) = 0;
    }
  BondPass pass;
  for (std::size_t k = 0; k < listed_bonds.size(); ++k) {
    const int b = listed_bonds[k];
    if (!each.empty()) each[2 * k] = each[2 * k + 1] = 0;
    if (bonds.is_broken(b)) continue;
    const BondResponse r = add_bond_forces(particles, bonds, b);
    const double norm = r.force_on_first.norm();
    pass.strain_energy += r.energy;
    pass.sum_force_norm += norm;
    if (!each.empty()) {
      each[2 * k] = r.energy;
      each[2 * k + 1] = norm;
    }
  }
  return pass;
}

double bond_strain_energy(const Particles& particles, const Bonds& bonds) {
  double energy = 0;
  for (int b = 0; b < bonds.size(); ++b)
    if (!bonds.is_broken(b)) energy += evaluate(particles, bonds, b).energy;
  return energy;
}

std::vector<Eigen::Matrix3d> particle_stresses(const Particles& particles, const Bonds& bonds,
                                               std::span<const Eigen::Vector3d> free_offsets) {
  require(free_offsets.empty() || free_offsets.size() == static_cast<std::size_t>(bonds.size()),
          fmt::format("particle stresses: {} free offsets for {} bonds", free_offsets.size(),
                      bonds.size()));
  std::vector<Eigen::Matrix3d> stress(static_cast<std::size_t>(particles.size()),
                                      Eigen::Matrix3d::Zero());
  for (int b = 0; b < bonds.size(); ++b) {
    if (bonds.is_broken(b)) continue;
    const int i = bonds.first(b), j = bonds.second(b);
    const Eigen::Vector3d offset =
        free_offsets.empty() ? Eigen::Vector3d::Zero() : free_offsets[static_cast<std::size_t>(b)];
    const Eigen::Vector3d force =
        parallel_bond_response(
            bond_parameters(bonds, b), row3(particles.displacement, i), row3(particles.rotation, i),
            row3(particles.displacement, j) - offset, row3(particles.rotation, j))
            .force_on_first;
    const Eigen::Vector3d branch = bonds.length(b) * row3(bonds.normal, b);
    const Eigen::Matrix3d virial = 0.25 * (force * branch.transpose() + branch * force.transpose());
    stress[static_cast<std::size_t>(bonds.first(b))] += virial;
    stress[static_cast<std::size_t>(bonds.second(b))] += virial;
  }
  for (int i = 0; i < particles.size(); ++i) {
    const double volume = particles.volume(i);
    stress[static_cast<std::size_t>(i)] =
        volume > 0 ? Eigen::Matrix3d(stress[static_cast<std::size_t>(i)] / volume)
                   : Eigen::Matrix3d::Zero();
  }
  return stress;
}

BondDeformation bond_deformation(const Particles& p, const Bonds& bonds, int b, double* du_out,
                                 double* dtheta_out) {
  const int i = bonds.first(b), j = bonds.second(b);
  const double n[3] = {bonds.normal(b, 0), bonds.normal(b, 1), bonds.normal(b, 2)};
  const double sigma = 0.5 * (bonds.lever_first(b) + bonds.lever_second(b));
  const double delta = 0.5 * (bonds.lever_second(b) - bonds.lever_first(b));
  double dtheta[3], a[3], du[3];
  for (int c = 0; c < 3; ++c) {
    dtheta[c] = p.rotation(j, c) - p.rotation(i, c);
    a[c] = fmadd(delta, dtheta[c], sigma * (p.rotation(i, c) + p.rotation(j, c)));
  }
  // As half_bond_response computes it (contacts/half_bond.hpp).
  du[0] = (p.displacement(j, 0) - p.displacement(i, 0)) - fmadd(a[1], n[2], -(a[2] * n[1]));
  du[1] = (p.displacement(j, 1) - p.displacement(i, 1)) - fmadd(a[2], n[0], -(a[0] * n[2]));
  du[2] = (p.displacement(j, 2) - p.displacement(i, 2)) - fmadd(a[0], n[1], -(a[1] * n[0]));
  for (int c = 0; c < 3; ++c) du[c] -= bonds.free_offset(b, c);
  for (int c = 0; c < 3 && du_out; ++c) du_out[c] = du[c];
  for (int c = 0; c < 3 && dtheta_out; ++c) dtheta_out[c] = dtheta[c];
  return deformation_of(du, dtheta, n);
}

namespace {

// Half-bond types are merged when their parameters agree to about 1e-12 relative: the normals and
// levers of a regular lattice, computed from positions, differ only in their last bits, and merging
// them is what lets a lattice stream a type index instead of its parameters. Normals are merged
// with the first one seen within 1e-12 (a lattice has a few directions; beyond kMaxDirections the
// packing is irregular and normals are kept exactly), the other parameters by rounding them to 40
// significant bits.
constexpr int kMaxDirections = 16;
constexpr double kSameDirection = 1e-12;

std::int64_t quantize_relative(double x) {
  int exponent = 0;
  const double mantissa = std::frexp(x, &exponent);
  return std::llround(std::ldexp(mantissa, 40)) * 4096 + exponent;
}

std::int64_t bits_of(double x) {
  std::int64_t b;
  std::memcpy(&b, &x, sizeof b);
  return b;
}

// Elastic part (9) and, for breaking, strength radius, tensile strength, cohesion, friction,
// ductility and the mixed-mode law's exponent and ratios (exact bits: strengths are copied, not
// computed, so equal ones are equal to the bit).
using TypeKey = std::array<std::int64_t, 17>;

struct KeyHash {
  std::size_t operator()(const TypeKey& key) const {
    std::uint64_t h = 1469598103934665603ull;
    for (std::int64_t k : key) {
      h ^= static_cast<std::uint64_t>(k) + 0x9e3779b97f4a7c15ull + (h << 6) + (h >> 2);
    }
    return static_cast<std::size_t>(h);
  }
};

// The screen's constants of a bond of intact stiffness `f` and strength `s` (HalfBondFailure):
// alpha, beta and the thresholds T_t, T_c as forces, lowered by kScreenMargin. An unbreakable bond
// (both strengths infinite) never passes the screen.
struct ScreenConstants {
  double displacement = 0;  // alpha
  double rotation = 0;      // beta
  double tension = std::numeric_limits<double>::infinity();
  double shear = std::numeric_limits<double>::infinity();
};

bool breakable_strength(const BondStrength& s) {
  return std::isfinite(s.tensile) || std::isfinite(s.cohesion);
}

ScreenConstants screen_constants(const HalfBondFailure& f, const BondStrength& s) {
  ScreenConstants c;
  if (!breakable_strength(s)) return c;
  const double area = std::numbers::pi * s.radius * s.radius;
  const double tension = area * s.tensile, shear = area * s.cohesion;  // +inf if never
  const double bending = kMomentContribution * 4.0 * f.bending_stiffness / s.radius;
  const double twisting = kMomentContribution * 2.0 * f.twisting_stiffness / s.radius;
  auto square = [](double x) { return x * x; };
  c.displacement =
      2.0 * std::max(square(f.normal_stiffness / tension),
                     square((f.shear_stiffness + s.friction * f.normal_stiffness) / shear));
  c.rotation = 2.0 * std::max(square(bending / tension), square(twisting / shear));
  // The mixed-mode law reaches U = sqrt(x^2 + y^2) >= kappa only where max(x, y) >= kappa /
  // sqrt(2): its screen thresholds are PFC's over sqrt(2) (alpha and beta bound it already).
  const double reach = s.mixed_mode() ? std::numbers::sqrt2 / 2 : 1.0;
  c.tension = (1.0 - kScreenMargin) * reach * tension;
  c.shear = (1.0 - kScreenMargin) * reach * shear;
  return c;
}

// Whether the intact bonds take more distinct strengths than the types keep
// (StrengthStorage::kAutomatic).
bool too_many_strengths(const Bonds& bonds) {
  std::set<std::array<std::int64_t, 8>> distinct;
  for (int b = 0; b < bonds.size() && static_cast<int>(distinct.size()) <= kMaxTypeStrengths; ++b) {
    if (bonds.is_broken(b)) continue;
    distinct.insert({bits_of(bonds.strength_radius(b)), bits_of(bonds.tensile_strength(b)),
                     bits_of(bonds.cohesion(b)), bits_of(bonds.friction_coefficient(b)),
                     bits_of(bonds.ductility(b)), bits_of(bonds.mixed_mode_exponent(b)),
                     bits_of(bonds.fracture_energy_ratio(b)), bits_of(bonds.peak_energy_ratio(b))});
  }
  return static_cast<int>(distinct.size()) > kMaxTypeStrengths;
}

// The index of the lattice direction that `normal` matches within kSameDirection, or -1.
int find_direction(const std::vector<Eigen::Vector3d>& directions, const Eigen::Vector3d& normal) {
  for (std::size_t d = 0; d < directions.size(); ++d) {
    if ((directions[d] - normal).cwiseAbs().maxCoeff() < kSameDirection) return static_cast<int>(d);
  }
  return -1;
}

int find_direction(const std::vector<Eigen::Vector3d>& directions, const double* normal) {
  return find_direction(directions, Eigen::Vector3d(normal[0], normal[1], normal[2]));
}

// The intact bonds' directions, both senses, if they are at most kMaxDirections; else none (an
// irregular packing: normals are then kept exactly).
std::vector<Eigen::Vector3d> lattice_directions(const Bonds& bonds) {
  std::vector<Eigen::Vector3d> directions;
  for (int b = 0; b < bonds.size(); ++b) {
    if (bonds.is_broken(b)) continue;
    const Eigen::Vector3d normal = bonds.normal.row(b).matrix().transpose();
    for (const Eigen::Vector3d& sensed : {normal, Eigen::Vector3d(-normal)}) {
      if (find_direction(directions, sensed) >= 0) continue;
      if (static_cast<int>(directions.size()) == kMaxDirections) return {};
      directions.push_back(sensed);
    }
  }
  return directions;
}

// The key under which a half-bond type of lattice direction `d` (or -1) is merged with others.
TypeKey type_key(const HalfBondType& h, int d, const BondStrength& strength, bool breaking,
                 bool slot_strengths) {
  TypeKey key{d >= 0 ? d : bits_of(h.normal[0]),
              d >= 0 ? 0 : bits_of(h.normal[1]),
              d >= 0 ? 0 : bits_of(h.normal[2]),
              quantize_relative(h.lever_own),
              quantize_relative(h.lever_other),
              quantize_relative(h.shear_stiffness),
              quantize_relative(h.normal_excess),
              quantize_relative(h.bending_stiffness),
              quantize_relative(h.twisting_excess),
              0,
              0,
              0,
              0,
              0,
              0,
              0,
              0};
  if (breaking) {
    key[9] = bits_of(strength.radius);
    key[10] = slot_strengths ? 0 : bits_of(strength.tensile);
    key[11] = slot_strengths ? 0 : bits_of(strength.cohesion);
    key[12] = bits_of(strength.friction);
    key[13] = bits_of(strength.ductility);
    key[14] = bits_of(strength.mixed_mode_exponent);
    key[15] = bits_of(strength.fracture_energy_ratio);
    key[16] = bits_of(strength.peak_energy_ratio);
  }
  return key;
}

// The failure data of half-bond type h of a bond of intact stiffness k (none without breaking;
// the screen's constants only with strengths per type).
HalfBondFailure failure_data(const HalfBondType& h, const BondStiffness& k,
                             const BondStrength& strength, bool breaking, bool slot_strengths) {
  HalfBondFailure f;
  if (!breaking) return f;
  f.lever_mean = 0.5 * (h.lever_own + h.lever_other);
  f.lever_half_difference = 0.5 * (h.lever_other - h.lever_own);
  f.normal_stiffness = k.normal;
  f.shear_stiffness = k.shear;
  f.bending_stiffness = k.bending;
  f.twisting_stiffness = k.twisting;
  f.strength = strength;
  f.shear_stiffness_squared = k.shear * k.shear;
  f.tension_threshold = f.shear_threshold = std::numeric_limits<double>::infinity();
  if (breakable_strength(strength)) {
    const double bending = kMomentContribution * 4.0 * k.bending / strength.radius;
    f.bending_factor = bending * bending;
    f.twisting_factor = kMomentContribution * 2.0 * k.twisting / strength.radius;
    f.shear_friction = (1.0 - kScreenMargin) * strength.friction;
  }
  if (!slot_strengths) {
    const ScreenConstants c = screen_constants(f, strength);
    f.screen_displacement = c.displacement;
    f.screen_rotation = c.rotation;
    f.tension_threshold = c.tension;
    f.shear_threshold = c.shear;
  }
  return f;
}

// Bond b's stiffnesses; for breaking the intact ones (the arrays hold (1 - damage) times them).
BondStiffness stiffness_of(const Bonds& bonds, int b, bool breaking) {
  const double scale = breaking ? 1.0 / (1.0 - bonds.damage(b)) : 1.0;
  BondStiffness k;
  k.normal = scale * bonds.normal_stiffness(b);
  k.shear = scale * bonds.shear_stiffness(b);
  k.bending = scale * bonds.bending_stiffness(b);
  k.twisting = scale * bonds.twisting_stiffness(b);
  return k;
}

// The type of bond b's first end, of stiffness k, before its normal is snapped to a direction
// (lever_shear is left for after).
HalfBondType first_end_type(const Bonds& bonds, int b, const BondStiffness& k) {
  HalfBondType h;
  h.shear_stiffness = k.shear;
  h.normal_excess = k.normal - k.shear;
  h.bending_stiffness = k.bending;
  h.twisting_excess = k.twisting - k.bending;
  for (int c = 0; c < 3; ++c) h.normal[c] = bonds.normal(b, c);
  h.lever_own = bonds.lever_first(b);
  h.lever_other = bonds.lever_second(b);
  return h;
}

// The same bond seen from its other end.
HalfBondType mirrored(HalfBondType h) {
  for (double& x : h.normal) x = -x;
  std::swap(h.lever_own, h.lever_other);
  h.lever_shear = h.lever_own * h.shear_stiffness;
  return h;
}

HalfBondLanes lanes_of(const HalfBondType& h) {
  HalfBondLanes v;
  for (int c = 0; c < 3; ++c) lanes::broadcast(h.normal[c], v.normal[c]);
  lanes::broadcast(h.lever_own, v.lever_own);
  lanes::broadcast(h.lever_other, v.lever_other);
  lanes::broadcast(h.shear_stiffness, v.shear_stiffness);
  lanes::broadcast(h.lever_shear, v.lever_shear);
  lanes::broadcast(h.normal_excess, v.normal_excess);
  lanes::broadcast(h.bending_stiffness, v.bending_stiffness);
  lanes::broadcast(h.twisting_excess, v.twisting_excess);
  return v;
}

HalfBondFailureLanes lanes_of(const HalfBondFailure& f) {
  HalfBondFailureLanes w;
  lanes::broadcast(f.lever_mean, w.lever_mean);
  lanes::broadcast(f.lever_half_difference, w.lever_half_difference);
  lanes::broadcast(f.normal_stiffness, w.normal_stiffness);
  lanes::broadcast(f.screen_displacement, w.screen_displacement);
  lanes::broadcast(f.screen_rotation, w.screen_rotation);
  lanes::broadcast(f.tension_threshold, w.tension_threshold);
  lanes::broadcast(f.shear_threshold, w.shear_threshold);
  lanes::broadcast(f.shear_friction, w.shear_friction);
  lanes::broadcast(f.bending_factor, w.bending_factor);
  lanes::broadcast(f.twisting_factor, w.twisting_factor);
  lanes::broadcast(f.shear_stiffness_squared, w.shear_stiffness_squared);
  return w;
}

}  // namespace

// Both ends of every intact bond, grouped by their own kernel particle (CSR): particle k's
// entries are offset[k] .. offset[k + 1] - 1.
struct GatherBonds::Ends {
  std::vector<int> offset;                      // [particle + 1]
  std::vector<int> fill;                        // [particle] its next entry to fill
  std::vector<std::int32_t> other, type, bond;  // [entry]; bond: 2 b (first end) or 2 b + 1

  // Counts the ends; throws plydem::Error for a bond that does not join two distinct particles.
  Ends(const Bonds& bonds, const std::vector<int>& kernel_index) {
    const int n = static_cast<int>(kernel_index.size());
    offset.assign(n + 1, 0);
    for (int b = 0; b < bonds.size(); ++b) {
      const int i = bonds.first(b), j = bonds.second(b);
      if (!(i >= 0 && i < n && j >= 0 && j < n && i != j)) {
        throw Error(
            fmt::format("bond {} joins particles {} and {}: not two distinct particles of "
                        "the {} in the model",
                        b, i, j, n));
      }
      if (bonds.is_broken(b)) continue;
      ++offset[kernel_index[i] + 1];
      ++offset[kernel_index[j] + 1];
    }
    std::partial_sum(offset.begin(), offset.end(), offset.begin());
    fill.assign(offset.begin(), offset.end() - 1);
    const std::size_t entries = static_cast<std::size_t>(offset[n]);
    other.resize(entries);
    type.resize(entries);
    bond.resize(entries);
  }

  void add(int own, int other_end, std::int32_t end_bond, std::int32_t end_type) {
    other[fill[own]] = other_end;
    bond[fill[own]] = end_bond;
    type[fill[own]++] = end_type;
  }
};

GatherBonds::GatherBonds(const Bonds& bonds, const std::vector<int>& order,
                         const GatherBreaking& breaking) {
  const int n = static_cast<int>(order.size());
  check_permutation(order, n);
  require(!bonds.has_free_offsets(),
          "the gather kernel (backends cpu, cuda and emulation) does not carry the bonds' free "
          "offsets (cure stresses, thermal.delta_T): use the reference backend or a static solve");
  particles_ = n;
  padded_ = (n + lanes::kCount - 1) / lanes::kCount * lanes::kCount;
  std::vector<int> kernel_index(n);
  for (int k = 0; k < n; ++k) kernel_index[order[k]] = k;
  breaking_ = breaking.enabled;
  softening_ = breaking.enabled && breaking.softening;

  Ends ends(bonds, kernel_index);
  // Strengths per slot when the bonds take too many distinct ones for the types.
  if (breaking_) {
    slot_strengths_ = breaking.storage == StrengthStorage::kSlots;
    if (breaking.storage == StrengthStorage::kAutomatic)
      slot_strengths_ = too_many_strengths(bonds);
  }
  const std::vector<Eigen::Vector3d> directions = lattice_directions(bonds);
  std::vector<int> type_direction = assign_types(bonds, kernel_index, directions, ends);
  lay_out_slots(ends, directions, type_direction);
  fill_cells(ends, type_direction, bonds.size());
  share_uniform_types();
  if (!breaking_) failure_.assign(1, HalfBondFailure{});  // the elastic kernel reads none
  if (!breaking_) failure_uniform_.assign(1, HalfBondFailureLanes{});
  fill_slot_state(bonds);
}

// Half-bond types, created in mirror pairs: the type of a bond's second end is the exact mirror
// image of its first end's (normal negated, levers swapped, the same stiffnesses and strength),
// so that both ends compute the same numbers (gather_half_bonds). Returns each type's lattice
// direction (or -1).
std::vector<int> GatherBonds::assign_types(const Bonds& bonds, const std::vector<int>& kernel_index,
                                           const std::vector<Eigen::Vector3d>& directions,
                                           Ends& ends) {
  types_.assign(1, HalfBondType{});
  failure_.assign(1, HalfBondFailure{});
  std::vector<std::int32_t> mirror(1, 0);
  std::vector<int> type_direction(1, -1);
  std::unordered_map<TypeKey, std::int32_t, KeyHash> type_index;
  auto add_type = [&](const HalfBondType& h, int d, const HalfBondFailure& f) {
    types_.push_back(h);
    failure_.push_back(f);
    type_direction.push_back(d);
    mirror.push_back(0);
    return static_cast<std::int32_t>(types_.size() - 1);
  };
  for (int b = 0; b < bonds.size(); ++b) {
    if (bonds.is_broken(b)) continue;
    const int i = kernel_index[bonds.first(b)], j = kernel_index[bonds.second(b)];
    const BondStiffness k = stiffness_of(bonds, b, breaking_);
    HalfBondType h = first_end_type(bonds, b, k);
    const int d = find_direction(directions, h.normal);
    if (d >= 0)
      for (int c = 0; c < 3; ++c) h.normal[c] = directions[d](c);
    h.lever_shear = h.lever_own * h.shear_stiffness;
    const HalfBondType h_mirror = mirrored(h);
    const int d_mirror = find_direction(directions, h_mirror.normal);
    const BondStrength strength = breaking_ ? bond_strength(bonds, b) : BondStrength{};
    const TypeKey key = type_key(h, d, strength, breaking_, slot_strengths_);
    const TypeKey key_mirror = type_key(h_mirror, d_mirror, strength, breaking_, slot_strengths_);
    std::int32_t t_first = 0, t_second = 0;
    if (const auto it = type_index.find(key); it != type_index.end()) {
      t_first = it->second;
      t_second = mirror[t_first];
    } else if (const auto jt = type_index.find(key_mirror); jt != type_index.end()) {
      t_second = jt->second;
      t_first = mirror[t_second];
    } else {
      t_first = add_type(h, d, failure_data(h, k, strength, breaking_, slot_strengths_));
      t_second = add_type(h_mirror, d_mirror,
                          failure_data(h_mirror, k, strength, breaking_, slot_strengths_));
      mirror[t_first] = t_second;
      mirror[t_second] = t_first;
    }
    type_index.try_emplace(key, t_first);
    type_index.try_emplace(key_mirror, t_second);
    ends.add(i, j, 2 * b, t_first);
    ends.add(j, i, 2 * b + 1, t_second);
  }
  return type_direction;
}

// Lattice slots: one slot per direction, numbered by angle (so that the slot order does not
// depend on the bond order), if no particle has two bonds along one direction; `type_direction`
// becomes each type's slot. Otherwise as many slots as the most bonds of one particle.
void GatherBonds::lay_out_slots(const Ends& ends, const std::vector<Eigen::Vector3d>& directions,
                                std::vector<int>& type_direction) {
  lattice_slots_ = !directions.empty();
  if (lattice_slots_) {
    std::vector<int> by_angle(directions.size());
    std::iota(by_angle.begin(), by_angle.end(), 0);
    auto angle = [&](int d) {
      return std::pair(std::atan2(directions[d].y(), directions[d].x()), directions[d].z());
    };
    std::sort(by_angle.begin(), by_angle.end(), [&](int a, int b) { return angle(a) < angle(b); });
    std::vector<int> slot_of_direction(directions.size());
    for (std::size_t s = 0; s < by_angle.size(); ++s)
      slot_of_direction[by_angle[s]] = static_cast<int>(s);
    for (int& d : type_direction) d = d < 0 ? d : slot_of_direction[d];
    width_ = static_cast<int>(directions.size());
    for (int k = 0; k < particles_ && lattice_slots_; ++k) {
      unsigned used = 0;
      for (int e = ends.offset[k]; e < ends.offset[k + 1]; ++e) {
        const unsigned bit = 1u << type_direction[ends.type[e]];
        if (used & bit) lattice_slots_ = false;
        used |= bit;
      }
    }
  }
  if (!lattice_slots_) {
    width_ = 0;
    for (int k = 0; k < particles_; ++k)
      width_ = std::max(width_, ends.offset[k + 1] - ends.offset[k]);
  }
}

// The slot table: every end in its slot (a lattice's by direction, else by the other end's
// index), the empty slots pointing at their own particle.
void GatherBonds::fill_cells(const Ends& ends, const std::vector<int>& type_slot, int bond_count) {
  const std::size_t cells = static_cast<std::size_t>(width_) * padded_;
  neighbour_.resize(cells);
  type_.assign(cells, 0);
  slot_bond_.assign(cells, -1);
  bond_cells_.assign(static_cast<std::size_t>(bond_count), {-1, -1});
  for (int s = 0; s < width_; ++s)
    std::iota(neighbour_.begin() + static_cast<std::ptrdiff_t>(s) * padded_,
              neighbour_.begin() + static_cast<std::ptrdiff_t>(s + 1) * padded_, 0);
  std::vector<int> entries;
  for (int k = 0; k < particles_; ++k) {
    entries.resize(ends.offset[k + 1] - ends.offset[k]);
    std::iota(entries.begin(), entries.end(), ends.offset[k]);
    if (!lattice_slots_) {
      std::sort(entries.begin(), entries.end(),
                [&](int a, int b) { return ends.other[a] < ends.other[b]; });
    }
    for (std::size_t r = 0; r < entries.size(); ++r) {
      const int e = entries[r];
      const int slot = lattice_slots_ ? type_slot[ends.type[e]] : static_cast<int>(r);
      const std::size_t cell = static_cast<std::size_t>(slot) * padded_ + k;
      neighbour_[cell] = ends.other[e];
      type_[cell] = ends.type[e];
      slot_bond_[cell] = ends.bond[e];
      bond_cells_[ends.bond[e] >> 1][ends.bond[e] & 1] = static_cast<std::int64_t>(cell);
    }
  }
}

// The types blocks share, repeated across the lanes, and each block's slots: uniform, mixed or
// empty, and whether their other ends are consecutive.
void GatherBonds::share_uniform_types() {
  uniform_.assign(1, HalfBondLanes{});
  failure_uniform_.assign(1, HalfBondFailureLanes{});
  std::vector<std::int32_t> uniform_index(types_.size(), 0);
  auto uniform_of = [&](std::int32_t t) {
    if (uniform_index[t] == 0) {
      uniform_index[t] = static_cast<std::int32_t>(uniform_.size());
      uniform_.push_back(lanes_of(types_[t]));
      failure_uniform_.push_back(lanes_of(failure_[t]));
    }
    return uniform_index[t];
  };
  const int blocks = padded_ / lanes::kCount;
  block_type_.assign(static_cast<std::size_t>(blocks) * width_, 0);
  block_run_.assign(static_cast<std::size_t>(blocks) * width_, -1);
  for (int b = 0; b < blocks; ++b) {
    for (int s = 0; s < width_; ++s) {
      const std::int32_t* type = types(s) + b * lanes::kCount;
      bool same_type = true;
      for (int l = 1; l < lanes::kCount; ++l) same_type &= type[l] == type[0];
      const std::size_t cell = static_cast<std::size_t>(b) * width_ + s;
      block_type_[cell] = same_type ? (type[0] == 0 ? 0 : uniform_of(type[0])) : -1;
      block_run_[cell] = block_run_of(b, s);
    }
  }
}

// Per-slot strengths and softening state, both ends of a bond alike.
void GatherBonds::fill_slot_state(const Bonds& bonds) {
  const std::size_t cells = static_cast<std::size_t>(width_) * padded_;
  if (slot_strengths_) {
    slot_alpha_ = lanes::Array(cells);
    slot_beta_ = lanes::Array(cells);
    slot_tension_ = lanes::Array(cells);
    slot_shear_ = lanes::Array(cells);
    slot_tensile_.assign(cells, 0.0);
    slot_cohesion_.assign(cells, 0.0);
  }
  if (softening_) {
    slot_damage_ = lanes::Array(cells);
    slot_kappa_ = lanes::Array(cells);
  }
  for (int b = 0; b < bonds.size() && (slot_strengths_ || softening_); ++b) {
    if (bonds.is_broken(b)) continue;
    const BondStrength strength = bond_strength(bonds, b);
    const ScreenConstants screen = screen_constants(failure_[type_[bond_cells_[b][0]]], strength);
    const double kappa = softening_history(bonds.damage(b), strength);
    for (const std::int64_t c : bond_cells_[b]) {
      const auto cell = static_cast<std::size_t>(c);
      if (slot_strengths_) {
        slot_alpha_[cell] = screen.displacement;
        slot_beta_[cell] = screen.rotation;
        slot_tension_[cell] = screen.tension;
        slot_shear_[cell] = screen.shear;
        slot_tensile_[cell] = strength.tensile;
        slot_cohesion_[cell] = strength.cohesion;
      }
      if (softening_) {
        slot_damage_[cell] = bonds.damage(b);
        slot_kappa_[cell] = kappa;
      }
    }
  }
}

std::int32_t GatherBonds::block_run_of(int block, int slot) const {
  const std::int32_t* other = neighbours(slot) + block * lanes::kCount;
  bool consecutive = other[0] + lanes::kCount <= padded_;
  for (int l = 1; l < lanes::kCount; ++l) consecutive &= other[l] == other[0] + l;
  return consecutive ? other[0] : -1;
}

void GatherBonds::clear_slot(int own, int s) {
  const std::size_t c = cell(s, own);
  type_[c] = 0;
  neighbour_[c] = own;
  if (softening_) slot_damage_[c] = 1.0;
  // The block's slot was uniform or mixed; with one lane now empty it is mixed, or empty if no
  // lane has a bond left (a uniform type needs every lane to hold it).
  const int block = own / lanes::kCount;
  const std::int32_t* type = types(s) + block * lanes::kCount;
  bool empty = true;
  for (int l = 0; l < lanes::kCount; ++l) empty &= type[l] == 0;
  const std::size_t block_cell = static_cast<std::size_t>(block) * width_ + s;
  block_type_[block_cell] = empty ? 0 : -1;
  block_run_[block_cell] = block_run_of(block, s);
}

void assess_slot(GatherBonds& g, int k, int slot, const double du[3], const double dtheta[3],
                 const double n[3], const double u_own[3], BreakingPass& pass) {
  const std::size_t cell = g.cell(slot, k);
  if (!g.holds(cell)) return;
  const HalfBondFailure& f = g.failure(g.types(slot)[k]);
  BondStrength strength = f.strength;
  if (g.slot_strengths()) {
    strength.tensile = g.slot_tensile_strength(cell);
    strength.cohesion = g.slot_cohesion(cell);
  }
  const double damage = g.softening() ? g.slot_damage()[cell] : 0.0;
  const double kappa = g.softening() ? g.slot_kappa()[cell] : 1.0;
  const BondStiffness intact{f.normal_stiffness, f.shear_stiffness, f.bending_stiffness,
                             f.twisting_stiffness};
  const BondDamageUpdate u =
      update_bond_damage(deformation_of(du, dtheta, n), intact, strength, damage, kappa);
  if (!u.changed) return;
  if (g.softening()) {
    g.slot_damage()[cell] = u.damage;
    g.slot_kappa()[cell] = u.kappa;
  }
  if (u.broken) g.clear_slot(k, slot);
  pass.changed = true;
  const std::int32_t bond = g.slot_bond(cell);
  if ((bond & 1) == 0)
    pass.events->push_back(
        damage_event(bond >> 1, pass.cycle, u, damage, intact, du, dtheta, n, u_own));
}

void GatherBonds::drop_bond(int first, int second) {
  if (!(first >= 0 && first < particles_ && second >= 0 && second < particles_ && first != second))
    throw Error(
        fmt::format("cannot drop a bond between kernel particles {} and {}: not two "
                    "distinct particles of the {}",
                    first, second, particles_));
  auto slot_of = [&](int own, int other) {
    for (int s = 0; s < width_; ++s) {
      const std::size_t cell = static_cast<std::size_t>(s) * padded_ + own;
      if (type_[cell] != 0 && neighbour_[cell] == other) return s;
    }
    throw Error(fmt::format("kernel particles {} and {} have no bond to drop", first, second));
  };
  const int slots[2] = {slot_of(first, second), slot_of(second, first)};
  clear_slot(first, slots[0]);
  clear_slot(second, slots[1]);
}

std::size_t GatherBonds::bytes() const {
  return (neighbour_.size() + type_.size() + block_type_.size() + block_run_.size() +
          slot_bond_.size()) *
             sizeof(std::int32_t) +
         types_.size() * sizeof(HalfBondType) + uniform_.size() * sizeof(HalfBondLanes) +
         failure_.size() * sizeof(HalfBondFailure) +
         failure_uniform_.size() * sizeof(HalfBondFailureLanes) +
         bond_cells_.size() * sizeof(bond_cells_[0]) + slot_alpha_.bytes() + slot_beta_.bytes() +
         slot_tension_.bytes() + slot_shear_.bytes() +
         (slot_tensile_.size() + slot_cohesion_.size()) * sizeof(double) + slot_damage_.bytes() +
         slot_kappa_.bytes();
}

}  // namespace plydem
