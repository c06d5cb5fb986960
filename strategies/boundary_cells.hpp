#pragma once
/// \file
/// Free edges of regular packings.
///
/// Boundary-cell completion (the count rule). In the bulk of a regular packing every particle has
/// `bulk_count` bonds of each family (two for the hexagonal and square layers: +n and -n), and
/// owns half of each. A particle on a free edge lacks some, so the strip next to the edge is softer
/// than the material its particles' volumes stand for (for a 19-row 0 deg coupon about 1/19 of the
/// diagonal bonds, -3.5% on E2 of the paper's coupon). Completion lets the bonds that are there
/// carry the missing share: a bond of family f between i and j is scaled by
///   1/2 (bulk_count / n_i^f) + 1/2 (bulk_count / n_j^f),
/// which is 1 in the bulk, so the calibrated bulk is untouched. The coupon's summed stiffness is
/// then its volume times the bulk's, but only for edges along lattice lines are the edge particles
/// in equilibrium under the bulk's uniform state: where an edge cuts a turned lattice the edge
/// relaxes, and the paper's 10 x 0.83 mm coupon comes out up to 2.4% soft (hex2d at 75 deg).
///
/// Edge equilibrium (balance_free_edges). A free edge of a continuum ply under a uniform stress
/// that loads it with no traction (sigma_xx along an edge parallel to x) stays uniform, so a single
/// ply's coupon under free grips has exactly CLT's moduli. The discrete coupon does the same when
/// every particle is in force and moment equilibrium under the bulk's relaxed uniform state (the
/// strain, and the particle spin the calibration relaxes: core/homogenizer.hpp relaxed_motion) with
/// the traction-free stress of its nearest edge, and when each edge strip's summed bond stress is
/// its particles' volume times the bulk stress. Both are linear in the weights of the bonds near
/// the edges; balance_free_edges solves them for the weights nearest 1 (least norm, the summed
/// stresses as hard constraints), leaving the bulk untouched.

#include <Eigen/Dense>
#include <vector>

#include "core/homogenizer.hpp"
#include "core/model.hpp"
#include "strategies/strategy.hpp"

namespace plydem {

/// Scales the normal, shear, bending and twisting stiffness of every bond as above. Returns the
/// number of bonds whose stiffness changed.
int complete_boundary_cells(const Particles& particles, Bonds& bonds, int family_count,
                            int bulk_count);

/// How a strategy treats the bonds at its coupon's free edges (CouponSpec::complete_boundary_cells
/// off: neither).
enum class EdgeTreatment : int {
  kCellCompletion = 0,  ///< complete_boundary_cells: exact only for edges along lattice lines
  kEquilibrium = 1,     ///< balance_free_edges
};

/// What balance_free_edges did.
struct EdgeBalance {
  int bonds_changed = 0;        ///< bonds within the edge strips, whose weights were solved
  int equations = 0;            ///< equilibrium equations (3 per particle: force x, y, moment)
  double min_weight = 1;        ///< smallest bond weight
  double max_weight = 1;        ///< largest bond weight
  double max_imbalance = 0;     ///< after: largest unbalanced force or moment / mean bond force
  double imbalance_before = 0;  ///< the same with every weight 1
  /// eps / mean diagonal of A A^T the weights were solved with: 1e-2, or tenfold more for each
  /// retry that a weight below 0.05 needed (boundary_cells.cpp).
  double regularization = 0;
  /// Already in equilibrium (to 1e-9 of a mean bond force) with the strips' stresses exact:
  /// nothing was changed.
  bool balanced = false;
};

/// Weights the in-ply bonds within `depth` [m] of the bounding box of `particles` (a rectangular
/// one-ply coupon, x along its length) so that the relaxed uniform state is in equilibrium with
/// traction-free edges (file comment). `cell` is the strategy's one-particle unit cell in the
/// specimen frame and `families` its calibrated bond families, from which the spin of the relaxed
/// state is taken; `stiffness` is the in-plane stiffness the bulk has (the calibration's relaxed
/// Q-bar) [Pa], from which the traction-free stress states are taken. Bond stiffnesses are scaled
/// by their weights. Throws plydem::Error for a cell of more than one particle, a coupon too small
/// for separate edge strips, or a weight that would not be positive (naming the bond).
EdgeBalance balance_free_edges(const Particles& particles, Bonds& bonds, const UnitCell& cell,
                               const std::vector<FamilyStiffness>& families,
                               const Eigen::Matrix3d& stiffness, double depth);

/// Whether the bonds as they are already meet balance_free_edges's conditions (to 1e-9 of a mean
/// bond force): edges along lattice lines after complete_boundary_cells do.
bool free_edges_balanced(const Particles& particles, const Bonds& bonds, const UnitCell& cell,
                         const std::vector<FamilyStiffness>& families,
                         const Eigen::Matrix3d& stiffness, double depth);

/// The edge strips' depth balance_free_edges gets from treat_free_edges, in particle diameters.
inline constexpr double kEdgeStripDiameters = 2.0;

/// What a one-particle-cell strategy's assemble() does to its built coupon: nothing unless
/// coupon.complete_boundary_cells; then `treatment`, complete_boundary_cells with two bonds per
/// family and particle in the bulk, or balance_free_edges with `cell` (the strategy's unit cell
/// for `calibration`), the calibration's families and the relaxed stiffness of `cell` with them,
/// and strips kEdgeStripDiameters deep. Where complete_boundary_cells already balances the edges
/// (edges along lattice lines: square at 0, 45, 90 deg), its weights are kept.
void treat_free_edges(Model& model, const CouponSpec& coupon, const Calibration& calibration,
                      const UnitCell& cell, int family_count, EdgeTreatment treatment);

/// The strategy option that chooses the treatment: `edge_equilibrium`, 1 (default) or 0 (the count
/// rule, kept to show what it misses). `value` is checked: 0 or 1, else plydem::Error naming the
/// strategy.
StrategyOption edge_treatment_option(EdgeTreatment treatment);
EdgeTreatment parse_edge_treatment(const std::string& strategy, double value);

}  // namespace plydem
