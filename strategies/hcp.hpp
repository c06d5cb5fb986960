#pragma once
/// \file
/// HCP, the paper's 3D hexagonal close packing strategy (Sec. 3.2): a ply is a three-layer HCP
/// lamina (packings/hcp_lamina.hpp) turned with the ply so that an in-plane bond family lies along
/// the fibre. Bonds are grouped as in the paper's eq. (24): the in-plane bonds along the fibre
/// (the paper's bonds 1 and 4) get (k_n^1, k_s^1), all other bonds, in-plane and inclined,
/// (k_n^2, k_s^2).
///
///  - `hcp`: the four springs are solved so that the lamina *as the engine simulates it* (particle
///    spins and the layers' relative shifts relaxed, ERRATA §3; its faces free, so plane stress)
///    has the ply's Q-bar. In the fibre frame the target is the orthotropic Q, four constants for
///    four springs: a least-squares fit of the affine lattice sum starts a Gauss-Newton solve on
///    the relaxed layer cell (strategies/calibration.hpp), exact where non-negative springs exist.
///    Otherwise plydem::Error names the constant out of reach and the nearest stiffness
///    non-negative springs give.
///  - `hcp-eq26`: the springs of the paper's eq. (26), corrected (ERRATA §2: each bond counted
///    once, the k_T2 coefficient of C1212, the true inclined bond length), solved in least squares
///    for the five constants of the ply's 3D stiffness it matches. It reports the relaxed stiffness
///    the lamina really has; it does not reach Q-bar, and E-glass has no non-negative solution.
///    Eq. (26)'s volume 2 sqrt(3) R^2 c per particle is that of a crystal whose layers are c apart;
///    in the lamina the three layers stand for the ply thickness delta, so each particle stands for
///    2 sqrt(3) R^2 delta / 3 (the springs scale with the volume; c still sets the geometry).
///
/// Both take the option `c`, the spacing of the layers in particle radii. Bonds keep the six
/// families of the packing (by direction) for reports; families 2 to 6 share the springs of
/// group 2. At free edges the bonds present carry their missing partners' share
/// (complete_boundary_cells_by_class): per in-plane family (2 bonds per particle in the bulk), and
/// per pair of adjacent layers for the inclined bonds (3 per particle in the bulk), since an
/// inclined bond has no partner of the opposite direction on the same particle.

#include <Eigen/Dense>
#include <vector>

#include "core/model.hpp"
#include "strategies/strategy.hpp"

namespace plydem {

/// Corrected eq. (26): rows C1111, C1122, C2222, C2233, C1212 (fibre along axis 1) of the HCP
/// crystal's affine stiffness, columns the springs k_N1, k_T1 (in-plane bonds along the fibre) and
/// k_N2, k_T2 (all other bonds), for particles of radius `radius` in touching in-plane contact,
/// layers `layer_spacing` apart and a volume `volume_per_particle` (2 sqrt(3) R^2 c for the
/// crystal). Each bond counted once with its true length: in-plane 2R, inclined
/// sqrt(4R^2/3 + c^2); sin(theta) = 2R / sqrt(4R^2 + 3c^2) (eq. 25).
Eigen::Matrix<double, 5, 4> hcp_eq26_matrix(double radius, double layer_spacing,
                                            double volume_per_particle);

/// The ratio C2233 / C1122 that eq. (26) allows at a layer spacing of `layer_spacing_radii`
/// particle radii: both are proportional to k_N2 - k_T2, so the geometry alone fixes it.
double hcp_eq26_ratio(double layer_spacing_radii);

/// The largest C2233 / C1122 that eq. (26) *as printed* (every bond 2R long, theta free) allows
/// over all layer spacings: max over x = sin^2(theta) of 4 x (1 - x) / (1 + x^2).
double hcp_eq26_printed_ratio_bound();

/// Boundary-cell completion by bond class (the idea of strategies/boundary_cells.hpp, where every
/// family has the same bulk count): a bond of class k between i and j is scaled by 1/2
/// (bulk_count[k] / n_i^k) + 1/2 (bulk_count[k] / n_j^k), n_i^k counting i's bonds of class k.
/// Returns the number of bonds whose stiffness changed.
int complete_boundary_cells_by_class(const Particles& particles, Bonds& bonds,
                                     const std::vector<int>& bond_class,
                                     const std::vector<int>& bulk_count);

/// What `hcp` and `hcp-eq26` share: the option `c`, the lamina and the coupon.
class HcpStrategyBase : public Strategy {
 public:
  HcpStrategyBase();
  std::vector<StrategyOption> options() const override;
  void set_option(const std::string& name, double value) override;
  Model assemble(const CouponSpec& coupon, const Calibration& calibration) const override;
  /// The three-particle lamina cell of unit spacing (layer spacing c) turned by
  /// calibration.lattice_angle, with the six families of the coupon.
  std::optional<UnitCell> unit_cell(const Calibration& calibration,
                                    double thickness) const override;

  /// Layer spacing c in particle radii (default the close-packed 2 sqrt(2/3)).
  double layer_spacing_radii() const { return layer_spacing_radii_; }

 protected:
  double layer_spacing_radii_;
};

class HcpStrategy : public HcpStrategyBase {
 public:
  std::string description() const override;
  Calibration calibrate(const Material& material, double ply_angle,
                        double thickness) const override;
};

class HcpEq26Strategy : public HcpStrategyBase {
 public:
  std::string description() const override;
  Calibration calibrate(const Material& material, double ply_angle,
                        double thickness) const override;
};

}  // namespace plydem
