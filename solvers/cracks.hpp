#pragma once
/// \file
/// Cracks as objects: the broken bonds of a model grouped into cracks, each with its ply (or the
/// interface it delaminates), position, length, direction, mode and the load step at which it
/// began; and the crack density of each ply.
///
/// Grouping. Two broken bonds belong to the same crack when they lie in the same ply (in-ply
/// bonds of the ply of their first particle) or on the same interface, and their contact points in
/// the reference configuration are within `link_distance` of each other (default 1.5 particle
/// diameters: the neighbouring bonds of a lattice line are one diameter apart, diagonal ones
/// sqrt(2)); the cracks are the connected groups (union-find over a cell grid).
///
/// Geometry. A crack's direction is the principal axis of its bonds' contact points in the x-y
/// plane (the larger eigenvector of their covariance; for a single bond, the direction normal to
/// the bond's branch vector, along which the crack it opens runs); its length is the extent of
/// the contact points along that axis plus one particle diameter (each broken bond stands for one
/// spacing of crack surface: a crack across a coupon of width W, cutting one bond per row,
/// measures W).
///
/// Density. The crack density of a ply is its number of cracks per unit length along x over a
/// stretch [x_begin, x_end] (cracks whose centroid lies in it), the quantity shear-lag models of
/// transverse cracking use (2 s = 1 / density, the mean crack spacing).

#include <string>
#include <vector>

#include "core/bond_failure.hpp"
#include "core/model.hpp"

namespace plydem {

struct Crack {
  int id = 0;              ///< 0, 1, ... in order of their first break
  bool interface = false;  ///< a delamination (interface bonds) rather than an in-ply crack
  int ply = 0;  ///< the ply of an in-ply crack; for a delamination the interface k (above ply k)
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();  ///< mean contact point [m]
  Eigen::Vector3d start = Eigen::Vector3d::Zero();     ///< its ends along `direction` [m]
  Eigen::Vector3d end = Eigen::Vector3d::Zero();
  double angle = 0;       ///< direction of the crack from +x in the x-y plane, in [0, pi) [rad]
  double length = 0;      ///< [m] (see the file comment)
  int bonds = 0;          ///< broken bonds in it
  int tension = 0;        ///< of which broken in tension
  int shear = 0;          ///< and in shear
  double first_at = 0;    ///< BondBreak::at of its first break (event number, or time)
  double first_load = 0;  ///< BondBreak::load of that break
  /// "tension" or "shear" when every bond broke so, else "mixed".
  std::string mode() const;
};

/// The cracks of `breaks` (as solvers log them: bond row, mode, event, load, contact point) in
/// `model` (for the bonds' ply or interface). `link_distance` <= 0: 1.5 times the largest particle
/// diameter. Breaks whose bond row is out of range throw plydem::Error.
std::vector<Crack> find_cracks(const Model& model, const std::vector<BondBreak>& breaks,
                               double link_distance = 0);

/// The cracks of `cracks` in ply `ply` (in-ply cracks only) whose centroid lies in
/// [x_begin, x_end], per unit length [1/m]. Throws plydem::Error if x_end <= x_begin.
double crack_density(const std::vector<Crack>& cracks, int ply, double x_begin, double x_end);

/// Cuts a transverse crack into a laminate model by hand, the way a crack would leave it: every
/// intact bond that crosses the plane x = `x` (its two ends on either side of it in the reference
/// configuration) and joins two particles of the plies first_ply .. last_ply (their in-ply bonds,
/// and the interface bonds between two of them) is broken: state kBrokenTension, damage 1, every
/// stiffness 0. The interface bonds to a ply outside that range stay, so the crack ends at the
/// plies that bound it, as a cross-ply's transverse crack ends at its 0° plies. Returns the breaks
/// as a solver logs them (event 0, load 0), for find_cracks. Throws plydem::Error for plies the
/// model does not have, an x on a particle centre of those plies (the plane must run between
/// particles), or a plane that crosses no bond of them.
std::vector<BondBreak> cut_transverse_crack(Model& model, double x, int first_ply, int last_ply);

/// A transverse crack plane x = position of one ply: the in-ply bonds broken across it.
struct CrackPlane {
  double position = 0;  ///< x of the plane: the mean of its broken bonds' midpoints [m]
  double extent = 0;    ///< extent of their contact points along y, plus one diameter [m]
  int bonds = 0;        ///< broken bonds across it
  int crossing = 0;     ///< in-ply bonds of the ply across it, broken or not
};

/// The transverse crack planes of ply `ply`: its broken in-ply bonds (of `breaks`) that cross a
/// plane x = const (their ends at different x, in the reference configuration) grouped by the
/// band their midpoint lies in (band = round(2 (x_mid - x_0) / d), x_0 the ply's smallest particle
/// x, d the bond's two radii: the gaps between particle columns of a lattice whose rows run along
/// y, a 90° ply's, are the odd bands). Planes whose extent is at least `min_extent` are returned,
/// by position, with the number of the ply's bonds that cross the same band (`crossing`: a crack
/// that transmits nothing has bonds == crossing). Unlike find_cracks, neighbouring cracks one
/// spacing apart stay apart: this is the count a saturated cross-ply needs. Throws plydem::Error
/// for a break out of range.
std::vector<CrackPlane> transverse_crack_planes(const Model& model,
                                                const std::vector<BondBreak>& breaks, int ply,
                                                double min_extent);

/// The cracks as CSV, one row each: id, kind (ply or interface), ply, x_mm, y_mm, z_mm,
/// length_mm, angle_deg, bonds, tension, shear, mode, first_event, first_load.
std::string cracks_csv(const std::vector<Crack>& cracks);

}  // namespace plydem
