#pragma once
/// \file
/// Effective stiffness of a periodic unit cell of bonded particles.
///  - affine: every particle follows the macroscopic strain and none rotates: eq. (5) with each
///    bond counted once (ERRATA §2);
///  - relaxed: the engine's own kinematics. Particle spins and sublattice shifts are internal
///    degrees of freedom that settle to minimum energy under a macroscopic strain; they are
///    condensed out statically (ERRATA §3). Built from core/parallel_bond.hpp, the same bond
///    law the kernel integrates.
/// Voigt order (11, 22, 33, 23, 13, 12) with engineering shear strains.

#include <Eigen/Dense>
#include <vector>

#include "core/elasticity.hpp"
#include "core/parallel_bond.hpp"

namespace plydem {

/// A periodic cell: basis particles, lattice vectors, bonds to (images of) basis particles.
struct UnitCell {
  /// Columns are the lattice vectors. For a layer the third vector is unused (no periodicity
  /// across the thickness): set it to the thickness direction.
  Eigen::Matrix3d lattice_vectors = Eigen::Matrix3d::Identity();
  std::vector<Eigen::Vector3d> basis;  ///< particle positions in the cell [m]
  std::vector<double> radius;          ///< [m]
  double volume = 0;                   ///< cell volume [m^3] (area x thickness for a layer)
  struct Bond {
    int first = 0;
    int second = 0;
    Eigen::Vector3i image = Eigen::Vector3i::Zero();  ///< cell of `second`, in lattice vectors
    int family = 0;
  };
  std::vector<Bond> bonds;  ///< each bond once
  int family_count = 0;

  /// Branch vector of bond b, first -> second (image included).
  Eigen::Vector3d branch(int b) const;
};

/// Stiffness of one bond family.
struct FamilyStiffness {
  double normal = 0;    ///< k_n [N/m]
  double shear = 0;     ///< k_s [N/m]
  double bending = 0;   ///< k_b [N m/rad]
  double twisting = 0;  ///< k_t [N m/rad]
};

/// The strain tensor of the Voigt unit strain k (order 11, 22, 33, 23, 13, 12) with engineering
/// shear strains: an off-diagonal pair of entries is 1/2 each. A particle at x moves by E x.
Eigen::Matrix3d voigt_unit_strain(int k);

/// Affine stiffness, eq. (5): particles follow the strain, no particle rotates.
Matrix6d affine_stiffness(const UnitCell& cell, const std::vector<FamilyStiffness>& families);
/// Relaxed stiffness: spins and sublattice shifts condensed out at minimum energy.
Matrix6d relaxed_stiffness(const UnitCell& cell, const std::vector<FamilyStiffness>& families);

using Vector6d = Eigen::Matrix<double, 6, 1>;

/// The state of a cell's basis particles under a macroscopic strain with the internal degrees of
/// freedom (spins and sublattice shifts) at minimum energy, as relaxed_stiffness condenses them:
/// the image of particle i in cell `image`, at x = basis[i] + lattice_vectors image, moves by
/// strain x + fluctuation[i] and turns by rotation[i]. The first particle's fluctuation is zero
/// (it fixes the cell's rigid translation); internal zero-energy modes (a layer's out-of-plane
/// motion, which in-plane strains do not load) are left at zero.
struct CellMotion {
  Eigen::Matrix3d strain = Eigen::Matrix3d::Zero();  ///< the symmetric strain tensor E
  std::vector<Eigen::Vector3d> fluctuation;          ///< translation beyond E x, per particle [m]
  std::vector<Eigen::Vector3d> rotation;             ///< per particle [rad]
  /// Displacement of particle `particle`'s image in cell `image` [m].
  Eigen::Vector3d displacement(const UnitCell& cell, int particle,
                               const Eigen::Vector3i& image) const;
};

/// The relaxed motion of `cell` under the macroscopic strain `strain` (Voigt order 11, 22, 33, 23,
/// 13, 12, engineering shear): the same static condensation as relaxed_stiffness, whose stresses
/// are those of this motion.
CellMotion relaxed_motion(const UnitCell& cell, const std::vector<FamilyStiffness>& families,
                          const Vector6d& strain);

/// Bond b of `cell` as the bond law (core/parallel_bond.hpp) sees it, with stiffness `stiffness`
/// (its family's): unit normal first -> second image, contact point midway in the gap.
BondParameters cell_bond(const UnitCell& cell, int b, const FamilyStiffness& stiffness);

/// The in-plane (xx, yy, xy) block of a 6x6 stiffness, for a layer with no bonds across its
/// thickness (whose sigma_zz is zero by construction: plane stress).
Eigen::Matrix3d in_plane_block(const Matrix6d& stiffness);

/// Relative error |A - B|_F / |B|_F.
double relative_difference(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b);

}  // namespace plydem
