#pragma once
/// \file
/// The coupon as the tests that pull it along x see it (the tension test,
/// experiments/protocols/tension.hpp, and the strength test, strength.hpp): built by a
/// strategy as one ply or a laminate, gripped at both ends, measured on a central gauge section.
///
/// Grips are the particles within `grip_length` of either end (BoundaryGroup kLeftGrip,
/// kRightGrip). Their axial displacement is prescribed; they are held in z and against tilting,
/// and, when clamped, laterally too (y and the in-plane rotation). Stress is the grip reaction
/// over the cross-section of the gauge section; strain is the least-squares fit of the gauge
/// particles' displacements (core/measurements.hpp), away from the grips and from the free edges.

#include <string>
#include <vector>

#include "core/checkpoint.hpp"
#include "core/model.hpp"
#include "solvers/linear_solver.hpp"
#include "solvers/static_solver.hpp"
#include "strategies/laminate.hpp"
#include "strategies/specimen.hpp"

namespace plydem {

enum class GripCondition { kFree, kClamped };

/// The coupon of `coupon` (one ply at `ply_angle`) or, for a non-empty `layup`, the laminate with
/// every ply turned by `ply_angle` - coupon.ply_angle, built by `builder` (which calibrates each
/// distinct ply once).
Specimen build_coupon(SpecimenBuilder& builder, const CouponSpec& coupon,
                      const std::vector<double>& layup, const InterfaceStiffness& interface,
                      double ply_angle);

/// The coupon's extent along x.
struct CouponGrips {
  double x_min = 0, x_max = 0;
  double span = 0;          ///< x_max - x_min [m]
  int left = 0, right = 0;  ///< particles in each grip
};

/// Puts the particles within `grip_length` of either end into the left and right grip groups.
/// Throws plydem::Error if the grips leave no free length or one holds no particle.
CouponGrips assign_grips(Particles& particles, double grip_length);

/// The ends of the free length that assign_grips left between the grips: the reference x of the
/// left grip's innermost particle and of the right grip's [m]. The grips move rigidly along x, so a
/// continuum model of the same coupon has its loaded faces here (the default grips at the material
/// point are deeper than two diameters: strength.cpp, default_grip_length). Throws plydem::Error
/// if a grip holds no particle.
struct GripFaces {
  double left = 0, right = 0;
};
GripFaces grip_faces(const Particles& particles);

/// The grips' static constraints: the left grip's ux at `left_ux`, the right one's at `right_ux`
/// [m], both held in z and against tilting; `clamped` also holds y and the in-plane rotation.
DofConstraints grip_constraints(const Particles& particles, double left_ux, double right_ux,
                                GripCondition grips);

/// Grips held at a uniform in-plane state: each grip particle at the displacement E (x - c) of
/// the strain `strain` (xx, yy, gamma_xy; c the centre of the coupon's extent) and the in-plane
/// rotation ply_spin[its ply], and at zero uz, theta_x, theta_y. Throws plydem::Error if a
/// particle's ply has no spin.
DofConstraints uniform_grip_constraints(const Particles& particles, const Eigen::Vector3d& strain,
                                        const std::vector<double>& ply_spin);
/// The same for the particles flagged in `held` (one flag per particle) instead of the grips.
DofConstraints uniform_grip_constraints(const Particles& particles, const Eigen::Vector3d& strain,
                                        const std::vector<double>& ply_spin,
                                        const std::vector<bool>& held);

/// Settings of the grips' static solves: the rigid modes free grips leave (the y translation) are
/// pinned; `force` is StaticSettings::force (the user's --force).
StaticSettings grip_solve_settings(LinearSolverKind linear_solver, bool force = false);

/// The central gauge section of a gripped coupon.
struct GaugeSection {
  /// Particles whose displacements give the strain: the central `gauge_fraction` of the length,
  /// at least `edge_band_diameters` particle diameters (at most a quarter of the width) from the
  /// free edges, whose discrete boundary layer relaxes differently from the bulk.
  std::vector<int> particles;
  double x_begin = 0, x_end = 0;  ///< [m]
  double cross_section = 0;       ///< mean cross-section area over the section [m^2]
};

/// Throws plydem::Error for a gauge fraction outside (0, 1).
GaugeSection gauge_section(const Particles& particles, const CouponGrips& grips,
                           double gauge_fraction, double edge_band_diameters,
                           double particle_diameter);

/// The grip stress at the current state: the mean of the bonds' pull on the two grips
/// (Particles::force along x, as the kernel or a solver left it) over `cross_section` [Pa].
double grip_stress(const Particles& particles, double cross_section);

/// A laminate coupon narrower than this many laminate thicknesses is dominated by its free-edge
/// zones (each about one laminate thickness wide; Pipes & Pagano 1970), so its moduli differ from
/// CLT's, which hold for an infinitely wide plate, by physics, not by discretization.
inline constexpr double kFreeEdgeWidths = 5.0;

/// Why `width` is too narrow for CLT to describe a coupon of the plies `layup` (each `thickness`
/// thick), in words, or "" when it is not (a single ply, or width >= kFreeEdgeWidths laminate
/// thicknesses).
std::string narrow_laminate_warning(double width, double thickness,
                                    const std::vector<double>& layup);

/// The coupon's part of a checkpoint's settings (core/checkpoint.hpp): the strategy and its
/// options, the material (name, constants and strengths), the ply angle, the coupon's size and
/// edges, the layup and interface stiffness, the grip length and gauge fraction.
void add_coupon_settings(CheckpointHeader& header, const std::string& strategy,
                         const std::vector<std::pair<std::string, double>>& strategy_options,
                         const CouponSpec& coupon, const std::vector<double>& layup,
                         const InterfaceStiffness& interface, double grip_length,
                         double gauge_fraction);

}  // namespace plydem
