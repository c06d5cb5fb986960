#pragma once
/// \file
/// Failure at the material point (issue 32, ../shared/DAMAGE_NOTES.md §7): each particle's site
/// stress is read in the axes of its ply and judged by a lamina criterion
/// (core/failure_criteria.hpp), which gives the load factor at which the site fails, the mode, and
/// the crack plane that mode opens.
///
/// The site stress is the ply's stiffness times the site's strain (site_strains: the displacement
/// gradient that fits its intact bonds' relative displacements), not the virial of its bonds
/// (particle_stresses): both are the ply's stress at an interior site in a uniform state, but at
/// the free edges and corners, where the bonds are fewer and the edge's own stiffnesses differ,
/// the virial reads up to about 9% above the stress the coupon carries (tests/test_site_stress.cpp
/// measures it), and an edge would crack first under a uniform stress. The fit is exact in any
/// affine displacement field, at edges and corners as inside, and a site beside an open crack
/// reads the strain of the side it is still bonded to.

#include <Eigen/Dense>
#include <span>
#include <vector>

#include "core/bond_state.hpp"
#include "core/failure_criteria.hpp"
#include "core/material.hpp"
#include "core/model.hpp"

namespace plydem {

/// One site's failure: the criterion's verdict on its stress and the unit normal of the crack
/// plane it opens, in the coupon's axes (crack_normal).
struct SiteFailure {
  PlyFailure failure;
  Eigen::Vector3d crack_normal = Eigen::Vector3d::UnitX();
};

/// The crack plane of a failure in a ply whose fibre lies at `ply_angle` [rad] from x: a fibre
/// mode's plane is normal to the fibre, n = (cos a, sin a, 0); a matrix mode's plane holds the
/// fibre and is inclined by the fracture angle phi from the thickness direction,
/// n = cos(phi) e2 + sin(phi) e3 with e2 = (-sin a, cos a, 0) the in-plane transverse direction and
/// e3 = z (phi = 0: the plane through the thickness, along the fibres).
Eigen::Vector3d crack_normal(const PlyFailure& failure, double ply_angle);

/// Every particle's in-plane strain (eps_xx, eps_yy, gamma_xy) at the current state: the symmetric
/// part of the in-plane displacement gradient G that fits u_j - u_i = G (x_j - x_i) best (least
/// squares, in-plane components, reference positions; du less the bond's free offset) over the
/// particle's unbroken bonds that have no damage (a softening crack's bonds open across it: they
/// are not the site's strain). Exact whenever the in-plane displacement is affine in x and y
/// (whatever it does through the thickness). A particle whose intact bonds do not span the plane
/// reads NaN.
std::vector<Eigen::Vector3d> site_strains(const Particles& particles, const Bonds& bonds);

/// Every particle's site stress at the current state in the axes of its ply: Q-bar of its ply
/// (`material` at the fibre angle ply_angles[particles.ply(i)] [rad]) times its site strain,
/// turned into the ply's axes, with tau12 = G12 (gamma12 - gamma_p) where `plastic_shear` (one
/// per particle, or empty: 0) gives the site's plastic shear strain gamma_p (in the ply's axes
/// the reduced stiffness couples no normal strain to shear). A site whose bonds all lie along one
/// line carries the uniaxial stress of its stretch along that line (the ply's modulus in that
/// direction times it), one without bonds zero. Throws plydem::Error naming the particle whose ply
/// has no angle in `ply_angles`, and for plastic strains of another size.
/// The strain is that of the bonds' relative displacements less their free offsets (cure
/// stresses: Bonds::free_offset, the state's own mechanical strain); `subtract_free_offsets` false
/// reads the displacements alone (the events solver's unit load, whose state adds to the
/// preload's).
std::vector<PlyStress> site_ply_stresses(const Particles& particles, const Bonds& bonds,
                                         std::span<const double> ply_angles,
                                         const Material& material,
                                         std::span<const double> plastic_shear = {},
                                         bool subtract_free_offsets = true);

/// Every particle's site failure at the current state: its stress in the axes of its ply
/// (site_ply_stresses) judged by `criterion` with the material's strengths. A site that carries no
/// stress (no bond left) gets an infinite load factor. `strength_factors` (one per particle, or
/// empty: 1) scales each site's strengths XT, XC, YT, YC and S12 (strength scatter). Throws
/// plydem::Error naming the particle whose ply has no angle in `ply_angles`, for factors of
/// another size or not positive, and as failure_load_factor does for a strength the criterion
/// needs and the material lacks. `plastic_shear`: as site_ply_stresses.
std::vector<SiteFailure> site_failures(const Particles& particles, const Bonds& bonds,
                                       std::span<const double> ply_angles,
                                       FailureCriterion criterion, const Material& material,
                                       std::span<const double> strength_factors = {},
                                       std::span<const double> plastic_shear = {});

/// Every site's failure as its stress grows from `preload` along `unit` (each one per particle, in
/// its ply's axes: site_ply_stresses of the cured state and of the unit load): the smallest load
/// factor lambda >= 0 at which preload + lambda unit fails it (core/failure_criteria.hpp
/// preloaded_ply_failure; 0 where the preload alone does), with `strength_factors` and the
/// errors of site_failures.
std::vector<SiteFailure> preloaded_site_failures(
    const Particles& particles, std::span<const PlyStress> preload, std::span<const PlyStress> unit,
    std::span<const double> ply_angles, FailureCriterion criterion, const Material& material,
    std::span<const double> strength_factors = {});

/// The bonds a crack at particle `site` opens (contacts/bond_opening.hpp opens them), its plane
/// through the site's cell with unit normal `normal` (crack_normal), on the normal's side of the
/// site, in increasing bond index, in-ply bonds only (an inclined crack's plane crosses the
/// interface bonds to the next ply, which delaminate by their own law):
///  - the site's unbroken bonds whose branch vector from the site has a positive component along
///    the normal (more than 1e-6 of its length), diagonals as much as axial bonds;
///  - in the site's layer, the other unbroken bonds that cross the plane within the site's segment
///    of it: from the plane's side away from the normal (or from on it) to the normal's side,
///    crossing it at a distance along the plane's in-layer direction t from the site of at most
///    h / 2, h = the lattice cell's area over the spacing of the lattice's lines along the normal
///    (both from the site's bonds): the site spacing along a crack that follows a lattice
///    direction. A lattice turned from the crack (a square one at 45 deg, whose crack runs along
///    its diagonals) has bonds that join the sites on either side of the crack's row and cross it
///    halfway between two of its sites: the first of the two to crack opens it.
/// The sites of one row of cracks, each opening towards the same side, open every bond that
/// crosses the row once and no other: a crack is traction-free once open. Throws plydem::Error
/// for a site out of range or a normal that is not a unit vector.
std::vector<int> bonds_across_crack(const Particles& particles, const Bonds& bonds, int site,
                                    const Eigen::Vector3d& normal);

/// The site that fails first as the current state is scaled (the smallest load factor; the lowest
/// particle index on a tie), or -1 if none can fail.
int first_failing_site(const std::vector<SiteFailure>& sites);

/// How the bonds of a site's crack break in a ply failure `mode`: compression modes in shear,
/// tension modes in tension.
BondState crack_bond_state(PlyFailureMode mode);

/// A site whose crack opens, and the bonds it opens.
struct OpeningSite {
  int particle = -1;  ///< -1: none
  SiteFailure site;   ///< its failure (load factor, mode, fracture angle)
  std::vector<int> bonds;
  Eigen::Vector3d normal = Eigen::Vector3d::UnitX();  ///< the side its bonds lie on
};

/// The site whose crack opens first among `sites` (site_failures at one state; a site whose load
/// factor is infinite is not judged) with the bonds it opens, shared by the events solver and the
/// explicit method. The smallest load factor fails first; factors within a relative
/// `tie_tolerance` of it are a tie, which goes to the lowest particle index. Its bonds are
/// bonds_across_crack on its normal's side or, open there already and failing again, on the other
/// side (its bonds bridge a crack whose other sites did not open them: a crack that zig-zags
/// through the lattice), without bonds that soften in another crack (damage > 0). A site with no
/// bond left to open is passed over (its factor in `sites` set to infinity) and the next one
/// judged. particle -1: no site fails.
OpeningSite next_opening_site(const Particles& particles, const Bonds& bonds,
                              std::vector<SiteFailure>& sites, double tie_tolerance);

/// Site `site`'s share of its crack plane through a lattice of such sites [m^2]: V / a, V the
/// particle's volume and a the spacing of the lattice's lines along the crack's unit normal n (the
/// smallest |l . n| of the site's in-ply bonds, broken or not, that have a component along n, l
/// the branch vector from the site in the reference configuration): the cell's area times the
/// layer's thickness over a, or the segment of bonds_across_crack times the thickness (over
/// cos phi for a plane inclined by phi through the thickness). Throws plydem::Error for a site
/// with no such bond.
double crack_share(const Particles& particles, const Bonds& bonds, int site,
                   const Eigen::Vector3d& normal);

}  // namespace plydem
