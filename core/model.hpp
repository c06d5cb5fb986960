#pragma once
/// \file
/// The model as the engine sees it: particles and bonds as plain arrays (structure of arrays).
/// Strategies fill these; the bond kernel, the integrator and the solvers read and advance them.
/// SI units throughout (m, kg, N, s, rad).

#include <Eigen/Dense>
#include <string>
#include <vector>

namespace plydem {

using Vector3Array = Eigen::Array<double, Eigen::Dynamic, 3>;

/// Boundary groups of particles. A tension test moves kLeftGrip and kRightGrip.
enum class BoundaryGroup : int { kFree = 0, kLeftGrip = 1, kRightGrip = 2 };

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

  int size() const { return static_cast<int>(mass.size()); }
  /// Allocates n particles with every array zeroed.
  void resize(int n);
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
  Vector3Array normal;                ///< unit branch vector first -> second, reference
  Eigen::ArrayXd length;              ///< reference centre distance [m]
  Eigen::ArrayXd lever_first;         ///< [m]
  Eigen::ArrayXd lever_second;        ///< [m]
  Eigen::ArrayXi family;              ///< bond family of the packing (for reports and plots)

  int size() const { return static_cast<int>(first.size()); }
  void resize(int n);
};

/// A built specimen: particles, bonds, and what a report needs to know about them.
struct Model {
  Particles particles;
  Bonds bonds;
  double thickness = 0;  ///< total thickness the layer(s) stand for [m]
  std::string description;

  /// Throws plydem::Error naming the first inconsistency: mismatched array sizes, a bond to a
  /// missing or the same particle, a duplicate bond, a non-finite or negative stiffness, a
  /// non-positive mass, radius or length, a normal that is not a unit vector.
  void check_consistency() const;
};

/// Fills normal, length and levers of bond b from the particles' reference positions and radii:
/// the contact point sits midway in the gap between the two surfaces.
void set_bond_geometry(const Particles& particles, Bonds& bonds, int b);

}  // namespace plydem
