#pragma once
/// \file
/// Failure at the material point (issue 32, ../shared/DAMAGE_NOTES.md §7): each particle's site
/// stress (particle_stresses, the virial of its bonds over its volume) is read in the axes of its
/// ply and judged by a lamina criterion (core/failure_criteria.hpp), which gives the load factor
/// at which the site fails, the mode, and the crack plane that mode opens.

#include <Eigen/Dense>
#include <span>
#include <vector>

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

/// Every particle's site failure at the current state: its in-plane stress (sigma_xx, sigma_yy,
/// tau_xy of particle_stresses) in the axes of its ply, whose fibre angle is
/// ply_angles[particles.ply(i)] [rad], judged by `criterion` with one ply material's `strength`.
/// A site that carries no stress gets an infinite load factor. Throws plydem::Error naming the
/// particle whose ply has no angle in `ply_angles`, and as failure_load_factor does for a
/// strength the criterion needs and the material lacks.
std::vector<SiteFailure> site_failures(const Particles& particles, const Bonds& bonds,
                                       std::span<const double> ply_angles,
                                       FailureCriterion criterion, const LaminaStrength& strength);

/// The bonds a crack at particle `site` opens (contacts/bond_opening.hpp opens them), its plane
/// through the site's cell with unit normal `normal` (crack_normal): the site's unbroken bonds
/// whose branch vector from the site has a positive component along the normal (more than 1e-6 of
/// its length), diagonals as much as axial bonds, in increasing bond index. The crack lies on the
/// normal's side of the site, so that the sites of one line of cracks, each opening towards the
/// same side, open every bond that crosses the line once and no other: a crack is traction-free
/// once open. Throws plydem::Error for a site out of range or a normal that is not a unit vector.
std::vector<int> bonds_across_crack(const Particles& particles, const Bonds& bonds, int site,
                                    const Eigen::Vector3d& normal);

/// The site that fails first as the current state is scaled (the smallest load factor; the lowest
/// particle index on a tie), or -1 if none can fail.
int first_failing_site(const std::vector<SiteFailure>& sites);

}  // namespace plydem
