#pragma once
/// \file
/// What every strategy's coupon is made of, assembled in one place: spheres of one radius, each
/// standing for an equal share of the ply's volume (mass from the density, a solid sphere's moment
/// of inertia), and bonds of a packing's graph with their geometry and, per bond family, the
/// calibrated springs of a parallel bond. And SpecimenBuilder, which calibrates each distinct ply
/// once for every coupon an experiment builds.

#include <map>
#include <string>
#include <utility>
#include <vector>

#include "core/model.hpp"
#include "strategies/calibration.hpp"
#include "strategies/strategy.hpp"

namespace plydem {

/// Bending and twisting of a circular parallel bond of radius R carrying contact stiffnesses
/// k_n = A kbar_n, k_s = A kbar_s (eqs. 1-2): k_b = kbar_n I = k_n R^2/4, k_t = kbar_s J = k_s
/// R^2/2. They resist relative rotation of neighbours (non-uniform fields); a uniform strain of a
/// one-particle lattice never loads them, so they do not enter the calibration.
FamilyStiffnessRule parallel_bond_rule(double bond_radius);

/// The particles and bond graph of a coupon, as a packing gives them.
struct SpecimenLayout {
  Eigen::Array<double, Eigen::Dynamic, 3> position;  ///< particle centres [m]
  double radius = 0;                                 ///< of every particle [m]
  double particle_volume = 0;              ///< each particle's share of the ply's volume [m^3]
  double density = 0;                      ///< [kg/m^3]
  std::vector<std::pair<int, int>> pairs;  ///< bonded particles
  std::vector<int> family;                 ///< per bond (empty: all 0)
  double thickness = 0;                    ///< the model's thickness [m]
  std::string description;
};

/// The one specimen assembler: particles with radius, volume, mass and moment of inertia (solid
/// sphere), bonds with their geometry (core/model.hpp set_bond_geometry) and, when `families` is
/// given, bond b the springs rule(k_n, k_s) of families[family(b)] with the parallel bond of the
/// particle radius; otherwise zero stiffness (the caller sets its own, as lattice does per bond).
/// Throws plydem::Error for fewer than two particles or a family without a calibration.
Model assemble_specimen(const SpecimenLayout& layout,
                        const std::vector<FamilyCalibration>* families = nullptr);

/// Builds coupons with one strategy, calibrating each distinct ply (Strategy::calibration_key)
/// once: an experiment that builds several coupons of the same plies (both pulls of a tension
/// test, a laminate's repeated plies) asks one builder.
class SpecimenBuilder {
 public:
  explicit SpecimenBuilder(const Strategy& strategy) : strategy_(strategy) {}
  const Strategy& strategy() const { return strategy_; }
  /// The calibration of the coupon's ply, computed on first use.
  const Calibration& calibration(const CouponSpec& coupon);
  /// The coupon built with its ply's calibration.
  Specimen build(const CouponSpec& coupon);
  /// The coupon of a laminate's ply, built on first use and kept: the plies of a laminate at the
  /// same angle, and those the laminates of one experiment share (a tension test's pulls along x
  /// and y: [0/45/-45/90]s and [-90/-45/-135/0]s have 6 distinct plies among their 16), are built
  /// (and their free edges balanced) once. A build is a function of the strategy, its options and
  /// the coupon (ply_key), so a kept ply is the ply a new build would give, bit for bit.
  const Specimen& ply(const CouponSpec& coupon);
  /// What this builder did: calibrations computed, coupons built.
  const BuildStatistics& statistics() const { return statistics_; }

 private:
  /// What ply() keys its coupons by: the calibration key and the coupon's size and edges.
  std::string ply_key(const CouponSpec& coupon) const;

  const Strategy& strategy_;
  std::map<std::string, Calibration> calibrations_;
  std::map<std::string, Specimen> plies_;
  BuildStatistics statistics_;
};

}  // namespace plydem
