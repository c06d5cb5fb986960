#pragma once
/// \file
/// A strategy = a packing + the rule that turns a ply's target stiffness into bond stiffnesses
/// (paper Sec. 3: Lattice, HCP, Hex2D, Square). Strategies are objects; what they build is plain
/// arrays (core/model.hpp).

#include <Eigen/Dense>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/homogenizer.hpp"
#include "core/material.hpp"
#include "core/model.hpp"

namespace plydem {

/// The coupon a strategy is asked to build: one ply, a rectangle in the x-y plane, long along x.
struct CouponSpec {
  Material material;
  double ply_angle = 0;                ///< fibre angle from +x [rad]
  double length = 10e-3;               ///< along x [m]
  double width = 0.83e-3;              ///< along y [m]
  double thickness = 0.2e-3;           ///< the ply thickness the bonds stand for (delta) [m]
  double particle_diameter = 0.05e-3;  ///< [m]
  /// Let bonds at free edges carry the share of their missing partners
  /// (strategies/boundary_cells.hpp).
  bool complete_boundary_cells = true;

  /// Throws plydem::Error naming the first non-finite or non-positive size, or a coupon too small
  /// to hold particles.
  void validate() const;
};

/// One bond family's calibrated stiffness, for reports.
struct FamilyCalibration {
  std::string label;     ///< e.g. "1 (fibre)"
  double direction = 0;  ///< angle of the family from +x in the specimen frame [rad]
  FamilyStiffness stiffness;
};

/// What a strategy needs to build with a calibration beyond its families (lattice: the orientation
/// law and the sample's volume per bond). Strategies derive from it; reports do not read it.
struct CalibrationDetail {
  virtual ~CalibrationDetail() = default;
};

/// The outcome of calibrating a ply: what each bond family gets, and the stiffness the model will
/// have as the engine simulates it beside the target.
struct Calibration {
  std::string method;
  double lattice_angle = 0;  ///< orientation of the packing from +x [rad]
  std::vector<FamilyCalibration> families;
  Eigen::Matrix3d target = Eigen::Matrix3d::Zero();   ///< plane-stress Q-bar [Pa]
  Eigen::Matrix3d affine = Eigen::Matrix3d::Zero();   ///< eq. (5) lattice sum [Pa]
  Eigen::Matrix3d relaxed = Eigen::Matrix3d::Zero();  ///< with spins and shifts relaxed [Pa]
  double relaxed_error = 0;                           ///< |relaxed - target|_F / |target|_F
  std::shared_ptr<const CalibrationDetail> detail;    ///< strategy-specific, may be empty
};

/// What a build made: the model and the calibration each of its plies got (one for a single ply,
/// bottom to top for a laminate), for reports.
struct Specimen {
  Model model;
  std::vector<Calibration> ply_calibrations;
  /// Wall-clock time of the build, the calibrations it computed included (not those it was given
  /// or found already computed) [s].
  double build_seconds = 0;
};

/// How a strategy completes its boundary cells, for an experiment that cuts the coupon after
/// building it (the hole plate): every in-ply bond family has `bulk_bonds` bonds per bulk particle
/// (strategies/boundary_cells.hpp). family_count = 0: the strategy completes its edges its own
/// way, which cannot be redone on a cut coupon.
struct BoundaryCompletion {
  int family_count = 0;
  int bulk_bonds = 0;
};

/// Counts of the work Strategy::build() and SpecimenBuilder did in this process: ply calibrations
/// computed for coupons, and coupons built (each ply of a laminate is one).
struct BuildStatistics {
  long calibrations = 0;
  long builds = 0;
};
BuildStatistics build_statistics();
/// Adds to the process counts (Strategy::build and SpecimenBuilder call it).
void count_build_work(long calibrations, long builds);

/// What a coupon of a strategy will hold, estimated before it is built (from the strategy's unit
/// cell, or a small sample of its packing): for the memory checks of
/// experiments/protocols/resource_estimate.hpp.
struct PackingEstimate {
  double particles = 0;
  double bonds = 0;
  /// Particles within half a diameter of the ply's highest centre (what interface bonds join).
  double top_surface_particles = 0;
  /// Particles within half a diameter of the ply's lowest centre, per unit area [1/m^2].
  double bottom_surface_density = 0;
  int layers = 1;  ///< particle layers through the ply's thickness
};

/// A strategy-specific parameter (hcp's layer spacing, lattice's seed), with its current value.
/// Set from the command line with `--strategy-option NAME=VALUE`.
struct StrategyOption {
  std::string name;
  double value = 0;
  std::string description;  ///< one line, with the unit
};

class Strategy {
 public:
  virtual ~Strategy() = default;
  /// The options this strategy takes, with their current values; none by default.
  virtual std::vector<StrategyOption> options() const { return {}; }
  /// Sets an option. Throws plydem::Error naming an unknown option (and listing the known ones)
  /// or a value out of range. The default knows no options.
  virtual void set_option(const std::string& name, double value);
  /// One line for `plydem strategies`.
  virtual std::string description() const = 0;
  /// Bond stiffnesses for a ply of `material` at `ply_angle` with thickness `thickness`. Throws
  /// plydem::Error if the target cannot be reached with a stable lattice.
  virtual Calibration calibrate(const Material& material, double ply_angle,
                                double thickness) const = 0;
  /// The calibration `coupon`'s bonds get. By default calibrate(material, ply_angle, thickness);
  /// lattice calibrates the coupon's own packing.
  virtual Calibration calibrate_coupon(const CouponSpec& coupon) const;
  /// Two coupons with the same key get the same calibrate_coupon(): by default the material, the
  /// ply angle and thickness (exactly) and the strategy's options. Lattice adds the coupon's size
  /// and particle diameter (its packing).
  virtual std::string calibration_key(const CouponSpec& coupon) const;
  /// Builds the coupon's particles and bonds with `calibration`, what calibrate_coupon(coupon)
  /// returns (perhaps computed for another coupon with the same calibration_key).
  virtual Model assemble(const CouponSpec& coupon, const Calibration& calibration) const = 0;
  /// How the coupon's boundary cells are completed; by default not redoable (see the struct).
  virtual BoundaryCompletion boundary_completion() const { return {}; }
  /// The periodic cell `calibration` (this strategy's calibrate() for a ply of thickness
  /// `thickness`) was solved on, in the specimen frame (x along the coupon), at the particle size
  /// its families' bending and twisting stiffnesses belong to (unit spacing for the built-in
  /// strategies), its bond families numbered as the built coupon's Bonds::family: with
  /// calibration.families as stiffnesses, in_plane_block(relaxed_stiffness(cell)) is
  /// calibration.relaxed. A layer cell (periodic in the plane, volume = area x thickness). The
  /// strength calibration (strategies/strength_calibration.hpp) reads the relaxed bond forces from
  /// it. nullopt (the default) for a strategy that has none whatever the calibration (lattice's
  /// random packing: no uniform bond state).
  virtual std::optional<UnitCell> unit_cell(const Calibration& calibration,
                                            double thickness) const {
    (void)calibration;
    (void)thickness;
    return std::nullopt;
  }

  /// The particles and bonds a build of `coupon` will make, estimated without building it. By
  /// default from unit_cell(Calibration{}, coupon.thickness): the cell's lattice points in the
  /// rectangle the particle centres fill, and for each cell bond the points whose partner lies in
  /// it too (so free edges lose their share); within a few percent of the built counts for
  /// coupons 20 diameters wide. nullopt where the strategy has no unit cell (lattice overrides it).
  virtual std::optional<PackingEstimate> estimate_packing(const CouponSpec& coupon) const;

  /// Calibrates and builds the coupon.
  Specimen build(const CouponSpec& coupon) const;
  /// Builds the coupon with a calibration already computed by calibrate_coupon() for a coupon of
  /// the same calibration_key. Throws plydem::Error if its target is not the coupon's ply Q-bar.
  Specimen build(const CouponSpec& coupon, const Calibration& calibration) const;
};

}  // namespace plydem
