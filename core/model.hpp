#pragma once
/// \file
/// The model as the engine sees it: particles and bonds as plain arrays (structure of arrays).
/// Strategies fill these; the bond kernel, the integrator and the solvers read and advance them.
/// SI units throughout (m, kg, N, s, rad).
///
/// Each struct declares its fields once, in `for_each_field`; every operation on whole rows
/// (resize, append, select, permute, the size check) runs over that list, so a new field is one
/// member plus its line in the list, and the build fails (a static_assert below each struct) if
/// the line is forgotten.

#include <Eigen/Dense>
#include <cstddef>
#include <limits>
#include <string>
#include <type_traits>
#include <vector>

#include "core/bond_state.hpp"

namespace plydem {

using Vector3Array = Eigen::Array<double, Eigen::Dynamic, 3>;

/// Boundary groups of particles. A tension test moves kLeftGrip and kRightGrip.
enum class BoundaryGroup : int { kFree = 0, kLeftGrip = 1, kRightGrip = 2 };

/// What a bond joins. In-ply bonds come from a ply's packing, interface bonds join two adjacent
/// plies (strategies/laminate.hpp). Stored as int in Bonds::kind.
enum class BondKind : int { kInPly = 0, kInterface = 1 };

// BondState (core/bond_state.hpp): whether a bond still holds, or how it broke.

/// What one row of a field holds.
enum class FieldKind { kVector3, kScalar, kInt };

/// A field's entry in the declaration: the name outputs and messages use, and whether its values
/// are particle indices (bond ends), which append() shifts and rename_particles() renames.
struct FieldInfo {
  const char* name = "";
  bool particle_index = false;
  /// The value resize() gives every row (an unbreakable bond's strength is +infinity, not 0).
  double fill = 0;
};

namespace detail {
template <class T>
struct FieldOf;
template <class T, class Owner>
struct FieldOf<T Owner::*> {
  using type = T;
};
}  // namespace detail

/// The array type of a field, from its pointer to member.
template <class MemberPointer>
using FieldType = typename detail::FieldOf<MemberPointer>::type;

/// The kind of a field's array type.
template <class Array>
constexpr FieldKind field_kind() {
  if constexpr (std::is_same_v<Array, Vector3Array>) {
    return FieldKind::kVector3;
  } else if constexpr (std::is_same_v<Array, Eigen::ArrayXd>) {
    return FieldKind::kScalar;
  } else {
    static_assert(std::is_same_v<Array, Eigen::ArrayXi>,
                  "a field is a Vector3Array, ArrayXd or ArrayXi");
    return FieldKind::kInt;
  }
}

/// Particles, one row per particle. The state is small-displacement: `displacement` and `rotation`
/// are measured from the reference configuration, so the current position is
/// reference_position + displacement (kept apart so that micro-strains keep full precision).
struct Particles {
  Vector3Array reference_position;   ///< [m]
  Vector3Array displacement;         ///< [m]
  Vector3Array velocity;             ///< [m/s]
  Vector3Array rotation;             ///< small rotation vector [rad]
  Vector3Array angular_velocity;     ///< [rad/s]
  Vector3Array force;                ///< resultant force [N]
  Vector3Array torque;               ///< resultant moment [N m]
  Eigen::ArrayXd mass;               ///< [kg]
  Eigen::ArrayXd moment_of_inertia;  ///< [kg m^2], isotropic
  Eigen::ArrayXd radius;             ///< [m]
  Eigen::ArrayXd volume;             ///< the material volume the particle stands for [m^3]
  Eigen::ArrayXi ply;                ///< ply index, 0 = bottom
  Eigen::ArrayXi group;              ///< BoundaryGroup as int

  /// The declaration of the fields above: f(FieldInfo, &Particles::field) for each, in order.
  template <class F>
  static constexpr void for_each_field(F&& f) {
    f(FieldInfo{"reference_position"}, &Particles::reference_position);
    f(FieldInfo{"displacement"}, &Particles::displacement);
    f(FieldInfo{"velocity"}, &Particles::velocity);
    f(FieldInfo{"rotation"}, &Particles::rotation);
    f(FieldInfo{"angular_velocity"}, &Particles::angular_velocity);
    f(FieldInfo{"force"}, &Particles::force);
    f(FieldInfo{"torque"}, &Particles::torque);
    f(FieldInfo{"mass"}, &Particles::mass);
    f(FieldInfo{"moment_of_inertia"}, &Particles::moment_of_inertia);
    f(FieldInfo{"radius"}, &Particles::radius);
    f(FieldInfo{"volume"}, &Particles::volume);
    f(FieldInfo{"ply"}, &Particles::ply);
    f(FieldInfo{"group"}, &Particles::group);
  }

  int size() const { return static_cast<int>(mass.size()); }
  /// Allocates n particles with every field zeroed.
  void resize(int n);
  /// Appends `other`'s particles after this one's (particle i of other becomes size() + i).
  void append(const Particles& other);
  /// The particles rows[0], rows[1], ... (in that order, repeats allowed). Throws plydem::Error
  /// for an index out of range.
  Particles select(const std::vector<int>& rows) const;
  /// Renumbers in place: new particle k is old particle order[k]. Throws plydem::Error unless
  /// `order` is a permutation of 0 .. size()-1. Bonds are not touched (see renumber() in
  /// contacts/particle_ordering.hpp for a whole model).
  void permute(const std::vector<int>& order);
  /// Throws plydem::Error naming the first field whose row count is not size().
  void check_sizes() const;
  Vector3Array position() const { return reference_position + displacement; }
};

/// Bonds, one row per bond: the linear parallel bond of paper Sec. 2.2 between particles
/// `first` and `second`, with its reference geometry. The contact point lies on the branch line at
/// distance `lever_first` from the first centre and `lever_second` from the second
/// (lever_first + lever_second = length).
struct Bonds {
  Eigen::ArrayXi first;
  Eigen::ArrayXi second;
  Eigen::ArrayXd normal_stiffness;    ///< k_n, contact stiffness [N/m]
  Eigen::ArrayXd shear_stiffness;     ///< k_s [N/m]
  Eigen::ArrayXd bending_stiffness;   ///< k_b [N m/rad]
  Eigen::ArrayXd twisting_stiffness;  ///< k_t [N m/rad]
  /// r = k_z / k_s: the shear stiffness along the layer normal over k_s (core/parallel_bond.hpp,
  /// "Out-of-plane shear"); 1 = isotropic shear, what every strategy builds.
  Eigen::ArrayXd out_of_plane_shear_ratio;
  Vector3Array normal;          ///< unit branch vector first -> second, reference
  Eigen::ArrayXd length;        ///< reference centre distance [m]
  Eigen::ArrayXd lever_first;   ///< [m]
  Eigen::ArrayXd lever_second;  ///< [m]
  /// For an in-ply bond, its bond family in the packing (for reports and plots); for an
  /// interface bond, the interface: k for the one above ply k (both >= 0).
  Eigen::ArrayXi family;
  Eigen::ArrayXi kind;  ///< BondKind as int
  // Strength: the parallel-bond failure law of core/bond_failure.hpp. A bond with infinite
  // strengths never breaks (what every builder makes until strengths are assigned).
  Eigen::ArrayXd strength_radius;       ///< R of the bond's cross-section A = pi R^2 [m]
  Eigen::ArrayXd tensile_strength;      ///< sigma_c [Pa]; +inf = unbreakable
  Eigen::ArrayXd cohesion;              ///< c, the shear strength at zero normal stress [Pa]
  Eigen::ArrayXd friction_coefficient;  ///< tan(phi) of the shear strength c - sigma tan(phi)
  /// Linear softening: the ratio of the separation at which the bond carries nothing to that at
  /// its peak (kappa_u >= 1); 1 = brittle. For a mixed-mode bond, kappa_u in pure mode I.
  Eigen::ArrayXd ductility;
  /// The mixed-mode law of core/bond_failure.hpp (interface bonds): the Benzeggagh-Kenane exponent
  /// eta > 0; 0 = PFC's law (tension, then shear), as every in-ply bond has.
  Eigen::ArrayXd mixed_mode_exponent;
  /// Mixed-mode law: GIIc / GIc of the bond's interface (> 0).
  Eigen::ArrayXd fracture_energy_ratio;
  /// Mixed-mode law: r = E_II / E_I, the elastic energy the intact bond holds at onset in pure
  /// mode II over that in pure mode I: (c^2 / k_s) / (sigma_c^2 / k_n) (> 0).
  Eigen::ArrayXd peak_energy_ratio;
  /// The relative displacement u_second - u_first of the contact point at which the bond carries
  /// no force [m]: an eigen-displacement, such as a ply's cure shrinkage (its thermal strain times
  /// the branch vector: strategies/cure_stress.hpp). Zero for every bond a strategy builds.
  Vector3Array free_offset;
  /// 0 intact .. 1 broken: the stiffnesses above are (1 - damage) times the intact ones.
  Eigen::ArrayXd damage;
  Eigen::ArrayXi state;  ///< BondState as int

  /// The declaration of the fields above: f(FieldInfo, &Bonds::field) for each, in order.
  template <class F>
  static constexpr void for_each_field(F&& f) {
    f(FieldInfo{"first", true}, &Bonds::first);
    f(FieldInfo{"second", true}, &Bonds::second);
    f(FieldInfo{"normal_stiffness"}, &Bonds::normal_stiffness);
    f(FieldInfo{"shear_stiffness"}, &Bonds::shear_stiffness);
    f(FieldInfo{"bending_stiffness"}, &Bonds::bending_stiffness);
    f(FieldInfo{"twisting_stiffness"}, &Bonds::twisting_stiffness);
    f(FieldInfo{"out_of_plane_shear_ratio", false, 1.0}, &Bonds::out_of_plane_shear_ratio);
    f(FieldInfo{"normal"}, &Bonds::normal);
    f(FieldInfo{"length"}, &Bonds::length);
    f(FieldInfo{"lever_first"}, &Bonds::lever_first);
    f(FieldInfo{"lever_second"}, &Bonds::lever_second);
    f(FieldInfo{"family"}, &Bonds::family);
    f(FieldInfo{"kind"}, &Bonds::kind);
    constexpr double kUnbreakable = std::numeric_limits<double>::infinity();
    f(FieldInfo{"strength_radius"}, &Bonds::strength_radius);
    f(FieldInfo{"tensile_strength", false, kUnbreakable}, &Bonds::tensile_strength);
    f(FieldInfo{"cohesion", false, kUnbreakable}, &Bonds::cohesion);
    f(FieldInfo{"friction_coefficient"}, &Bonds::friction_coefficient);
    f(FieldInfo{"ductility", false, 1.0}, &Bonds::ductility);
    f(FieldInfo{"mixed_mode_exponent"}, &Bonds::mixed_mode_exponent);
    f(FieldInfo{"fracture_energy_ratio", false, 1.0}, &Bonds::fracture_energy_ratio);
    f(FieldInfo{"peak_energy_ratio", false, 1.0}, &Bonds::peak_energy_ratio);
    f(FieldInfo{"free_offset"}, &Bonds::free_offset);
    f(FieldInfo{"damage"}, &Bonds::damage);
    f(FieldInfo{"state"}, &Bonds::state);
  }

  int size() const { return static_cast<int>(first.size()); }
  /// Allocates n bonds with every field zeroed (in-ply, family 0).
  void resize(int n);
  /// Appends `other`'s bonds after this one's, their ends shifted by `particle_offset` (the
  /// number of particles before other's first one, as Particles::append places them).
  void append(const Bonds& other, int particle_offset = 0);
  /// The bonds rows[0], rows[1], ... (in that order), their ends unchanged. Throws plydem::Error
  /// for an index out of range.
  Bonds select(const std::vector<int>& rows) const;
  /// Reorders in place: new bond k is old bond order[k]. Throws plydem::Error unless `order` is a
  /// permutation of 0 .. size()-1.
  void permute(const std::vector<int>& order);
  /// Renames the ends: particle i becomes new_index[i]. Throws plydem::Error if an end is outside
  /// new_index or is renamed to a negative index (a removed particle).
  void rename_particles(const std::vector<int>& new_index);
  /// Writes the bonds of `from` back to rows rows[0], rows[1], ... (the inverse of select()):
  /// every field of row rows[k] becomes that of bond k of `from`.
  void assign_rows(const std::vector<int>& rows, const Bonds& from);
  /// Throws plydem::Error naming the first field whose row count is not size().
  void check_sizes() const;

  bool is_interface(int b) const { return kind(b) == static_cast<int>(BondKind::kInterface); }
  bool is_broken(int b) const { return state(b) != static_cast<int>(BondState::kIntact); }
  /// Whether any bond has a finite strength (the model can break).
  bool breakable() const;
  /// Whether any bond has a non-zero free offset (cure stresses).
  bool has_free_offsets() const { return (free_offset != 0).any(); }
};

namespace detail {
template <class S>
constexpr std::size_t declared_field_bytes() {
  std::size_t bytes = 0;
  S::for_each_field([&](FieldInfo, auto member) { bytes += sizeof(FieldType<decltype(member)>); });
  return bytes;
}
}  // namespace detail

static_assert(sizeof(Particles) == detail::declared_field_bytes<Particles>(),
              "a member of Particles is missing from Particles::for_each_field");
static_assert(sizeof(Bonds) == detail::declared_field_bytes<Bonds>(),
              "a member of Bonds is missing from Bonds::for_each_field");

/// A built specimen: particles, bonds, and what a report needs to know about them.
struct Model {
  Particles particles;
  Bonds bonds;
  double thickness = 0;  ///< total thickness the layer(s) stand for [m]
  std::string description;

  /// Throws plydem::Error naming the first inconsistency: mismatched array sizes, a bond to a
  /// missing or the same particle, a duplicate bond, a non-finite or negative stiffness, a
  /// non-positive mass, radius or length, a normal that is not a unit vector, a kind that is no
  /// BondKind.
  void check_consistency() const;
};

/// The particles kept[0], kept[1], ... of `model` (in that order, each at most once) and the bonds
/// whose two ends are both kept (in their order), their ends renumbered; thickness and description
/// are copied. Throws plydem::Error for an index out of range or listed twice.
Model select_particles(const Model& model, const std::vector<int>& kept);

/// Fills normal, length and levers of bond b from the particles' reference positions and radii:
/// the contact point sits midway in the gap between the two surfaces.
void set_bond_geometry(const Particles& particles, Bonds& bonds, int b);

/// "particle i at (x, y, z) mm", its reference position, for messages that name a particle.
std::string describe_particle(const Particles& particles, int i);

}  // namespace plydem
