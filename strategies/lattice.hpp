#pragma once
/// \file
/// Lattice, the paper's 3D discrete lattice strategy (Sec. 3.1): a random packing of spheres
/// (packings/random_packing.hpp) filling the ply's box, each sphere bonded to every neighbour
/// within I_R = 1.8 times the sum of the radii (eq. 10), with bond stiffnesses from the microplane
/// model (eqs. 4-15, corrected by ERRATA §2):
///   k_n = E_N(n) 6V / (N L^2),   k_s = E_T(n) 6V / (N L^2)                 (Sec. 3.4)
/// where n is the bond's direction, L its length and V / N the volume per bond. The paper's moduli
/// depend on the angle theta between bond and fibre:
///   E_N(theta) = sin^2 theta E_N^a + cos^2 theta E_N^b                      eq. (13)
///   E_T(theta) = sin^2 theta E_T^a + cos^2 theta E_T^b                      eq. (14), corrected.
/// For bonds spread evenly over all directions this law makes the affine lattice sum, eq. (5), the
/// microplane integral, eq. (11), whose transversely isotropic stiffness is eq. (15).
///
/// Two strategies are registered:
///  - `lattice-paper`: the four moduli from eq. (15) (ERRATA §2 corrections; negative ones set to
///    zero), nothing else. Its Calibration reports the relaxed stiffness the engine really gives,
///    measured on the periodic calibration sample below.
///  - `lattice` (default): the same start, then the automatic correction. The paper's law is
///    rewritten in a richer orientation law (OrientationModuli: a quadratic Bernstein polynomial
///    in the squared direction cosines for E_N, a linear one for E_T, two odd coupling terms),
///    and its coefficients are driven, by Gauss-Newton with the smallest relative change from the
///    paper's, until the relaxed in-plane stiffness of a calibration sample equals the target
///    Q-bar. The sample is the packing periodic in x and y with the ply's thickness in z and free
///    surfaces, as in the coupon, so that the surface softening is included. The coupon's bonds
///    get the calibrated law with the sample's volume per bond.
/// Why more than four moduli: a random network relaxes non-affinely (ERRATA §3), the more so the
/// more anisotropic its springs; for E-glass the paper's law would need a negative E_T (below
/// zero the packing is unstable) and still misses G12. See the lattice tests for the figures.
/// Bending and twisting come from a parallel bond of the particle radius R (as hex2d):
/// k_b = k_n R^2 / 4, k_t = k_s R^2 / 2.

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "packings/random_packing.hpp"
#include "solvers/periodic_homogenization.hpp"
#include "strategies/strategy.hpp"

namespace plydem {

/// The paper's four microplane moduli [Pa] (eqs. 13-14, corrected: ERRATA §2).
struct MicroplaneModuli {
  double normal_transverse = 0;  ///< E_N^a: normal modulus of bonds across the fibre
  double normal_axial = 0;       ///< E_N^b: normal modulus of bonds along the fibre
  double shear_transverse = 0;   ///< E_T^a
  double shear_axial = 0;        ///< E_T^b
};

/// The bond law of both strategies: the moduli [Pa] as functions of the bond's direction n. With
/// the fibre f, the in-plane transverse direction t = z x f, c = n.f, s = n.t, z = n.z, the squared
/// cosines x = (c^2, s^2, z^2) sum to one, and the law is written in Bernstein polynomials of x
/// (non-negative coefficients give non-negative moduli in every direction):
///   E_N(n) = b11 x1^2 + b22 x2^2 + b33 x3^2 + 2 b12 x1 x2 + 2 b13 x1 x3 + 2 b23 x2 x3
///            + 2 c s (g1 + g2 (c^2 - s^2))
///   E_T(n) = t1 x1 + t2 x2 + t3 x3.
/// The paper's law is the special case from_paper(). g1, g2 are odd in s and zero for an ideal
/// isotropic packing: they absorb a realisation's own Q16 and Q26 (fibre frame).
struct OrientationModuli {
  std::array<double, 6> normal{};  ///< b11, b22, b33, b12, b13, b23
  std::array<double, 3> shear{};   ///< t1, t2, t3
  double coupling = 0;             ///< g1
  double coupling_oblique = 0;     ///< g2

  /// Eqs. (13)-(14) corrected: E_N = (1 - c^2) E_N^a + c^2 E_N^b, E_T likewise.
  static OrientationModuli from_paper(const MicroplaneModuli& moduli);
  /// E_N and E_T of a bond with direction cosines c = n.f, s = n.t and z = n.z.
  double normal_modulus(double c, double s, double z) const;
  double shear_modulus(double c, double s, double z) const;
};

/// Eq. (11) integrated exactly (a product Gauss rule of degree 11; the integrand has degree 8):
/// C = 3/(2 pi) * integral over the whole unit sphere of E_N N(x)N + E_T T^T.T (ERRATA §2: the
/// full sphere, twice Carol's hemisphere), Voigt 6x6 in the specimen frame, for the fibre along
/// the unit vector `fibre` and t = z x fibre (fibre in the x-y plane), or t = y for a fibre along
/// z.
Matrix6d microplane_stiffness(const OrientationModuli& moduli, const Eigen::Vector3d& fibre);

/// Corrected eq. (15) with the dependent C2323 row, in the paper's frame (fibre along 3): rows
/// (C1111, C3333, C2233, C1122, C2323), columns (E_N^a, E_N^b, E_T^a, E_T^b); computed from
/// microplane_stiffness, so that tests can compare it with the printed 1/35 matrix.
Eigen::Matrix<double, 5, 4> microplane_matrix();

/// The four moduli of a ply from its 3D stiffness (Sec. 3.4).
struct MicroplaneFit {
  /// The paper's solve of eq. (15)'s four rows (C1111, C3333, C2233, C1122; C2323 left
  /// dependent): square, so its least-squares solution is exact. May be negative (ERRATA §2:
  /// E_T^a < 0 for E-glass).
  MicroplaneModuli paper;
  /// `paper` with negative moduli set to zero: a negative spring makes the packing unstable.
  /// (Non-negative least squares over all five constants, C2323 included, gives E_T^a = E_T^b = 0
  /// for E-glass: no shear springs, and the spins of all particles together are a mechanism.)
  MicroplaneModuli moduli;
  double paper_axial_shear = 0;  ///< C2323 (target G12) that `paper` implies [Pa]
  /// |eq. (15) with `moduli` - target| / |target| over the five constants, C2323 included.
  double relative_residual = 0;
};
/// Throws plydem::Error unless validate(material) passes.
MicroplaneFit fit_microplane_moduli(const Material& material);

/// k_n, k_s, k_b, k_t of a bond with branch vector `branch` under the law of the file comment:
/// `volume_per_bond` = V / N [m^3], `radius` the parallel bond radius [m].
FamilyStiffness lattice_bond_stiffness(const OrientationModuli& moduli,
                                       const Eigen::Vector3d& fibre, const Eigen::Vector3d& branch,
                                       double volume_per_bond, double radius);

/// Everything the lattice calibration found, beyond plydem::Calibration.
struct LatticeCalibration {
  Calibration calibration;
  MicroplaneFit fit;         ///< the eq. (15) start
  OrientationModuli moduli;  ///< what the bonds get (from_paper(fit.moduli) for lattice-paper)
  Eigen::Matrix3d relaxed_uncorrected = Eigen::Matrix3d::Zero();  ///< with fit.moduli [Pa]
  Eigen::Matrix3d affine_uncorrected = Eigen::Matrix3d::Zero();   ///< with fit.moduli [Pa]
  double volume_per_bond = 0;  ///< V / N of the calibration sample [m^3]
  int sample_particles = 0;
  int sample_bonds = 0;
  int sample_removed = 0;          ///< loose spheres dropped from the sample
  double sample_coordination = 0;  ///< mean bonds per particle, 2 N_bonds / N_particles
  Eigen::Vector3d sample_box = Eigen::Vector3d::Zero();  ///< [m]
  int iterations = 0;                                    ///< Gauss-Newton steps of the correction
  int evaluations = 0;                                   ///< relaxed homogenizations
  double seconds = 0;                                    ///< wall-clock time of the calibration
};

class LatticeStrategy : public Strategy {
 public:
  /// `corrected` = false gives the paper's uncorrected lattice (`lattice-paper`).
  explicit LatticeStrategy(bool corrected = true);

  std::vector<StrategyOption> options() const override;
  void set_option(const std::string& name, double value) override;
  std::string description() const override;
  /// The calibration for particles of the `particle_diameter` option on the periodic calibration
  /// sample (`plydem calibrate`; a coupon is calibrated on its own packing: calibrate_coupon).
  Calibration calibrate(const Material& material, double ply_angle,
                        double thickness) const override;
  /// The coupon's own packing, periodic in x and y, corrected from the start the small periodic
  /// sample gives: the calibration its bonds get.
  Calibration calibrate_coupon(const CouponSpec& coupon) const override;
  /// Adds the coupon's size and particle diameter: they make its packing.
  std::string calibration_key(const CouponSpec& coupon) const override;
  /// The coupon's sphere count (the packing fraction of its box) and, from a packing of 12 x 12
  /// diameters periodic in x and y (milliseconds), the bonds per sphere less the share that the
  /// coupon's cut periodic faces remove, and the surface spheres.
  std::optional<PackingEstimate> estimate_packing(const CouponSpec& coupon) const override;
  /// Throws plydem::Error unless `calibration` is calibrate_coupon() of this coupon's packing.
  Model assemble(const CouponSpec& coupon, const Calibration& calibration) const override;

  /// The calibration for spheres of `diameter` in a ply of `thickness`.
  /// With `sample_size` (x and y [m]), the sample is a packing of that size (build() passes the
  /// coupon's: the coupon is the sample with its periodic bonds cut); `start_law` starts the
  /// correction there instead of at the paper's law.
  LatticeCalibration calibrate_lattice(const Material& material, double ply_angle, double thickness,
                                       double diameter,
                                       const Eigen::Vector2d* sample_size = nullptr,
                                       const OrientationModuli* start_law = nullptr) const;
  /// The periodic calibration sample (its bonds carry `moduli` at fibre angle `ply_angle`, with
  /// the sample's own V / N), as calibrate_lattice measures it.
  PeriodicModel calibration_sample(const OrientationModuli& moduli, double ply_angle,
                                   double thickness, double diameter, double density) const;
  /// A packing periodic in x and y filling `box` [m], its bonds carrying `moduli` with
  /// `volume_per_bond` [m^3] (0 = the sample's own V / N).
  PeriodicModel periodic_sample(const OrientationModuli& moduli, double ply_angle,
                                const Eigen::Vector3d& box, double diameter, double density,
                                double volume_per_bond) const;
  /// The packing spec build() uses for a coupon (seed and packing fraction from the options).
  RandomPackingSpec coupon_packing(const CouponSpec& coupon) const;

  std::uint64_t seed() const { return seed_; }
  double contact_radius() const { return contact_radius_; }

 private:
  bool corrected_;
  std::uint64_t seed_ = 1;
  double contact_radius_ = 1.8;         ///< I_R of eq. (10)
  double packing_fraction_ = 0.29;      ///< the paper's 8,841 spheres of 0.05 mm in 10 x 1 x 0.2 mm
  double sample_diameters_ = 16;        ///< calibration sample edge in x and y, in diameters
  double particle_diameter_ = 0.05e-3;  ///< for calibrate() only [m]
  double tolerance_ = 1e-9;             ///< relative error at which the correction stops
  double max_error_ = 0.02;             ///< largest accepted error of an engineering constant

  /// Throws UnreachableStiffness (strategies/calibration.hpp) naming the engineering constants
  /// the corrected sample misses by more than max_error_ (nothing for lattice-paper).
  void check_reached(const LatticeCalibration& cal, const Material& material, double ply_angle,
                     double thickness) const;
};

}  // namespace plydem
