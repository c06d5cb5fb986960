#include "core/model.hpp"

#include <fmt/format.h>

#include <cmath>
#include <set>
#include <utility>

#include "core/error.hpp"

namespace plydem {

void Particles::resize(int n) {
  for (Vector3Array* a : {&reference_position, &displacement, &velocity, &rotation,
                          &angular_velocity, &force, &torque}) {
    a->setZero(n, 3);
  }
  for (Eigen::ArrayXd* a : {&mass, &moment_of_inertia, &radius, &volume}) a->setZero(n);
  ply.setZero(n);
  group.setZero(n);
}

void Bonds::resize(int n) {
  first.setZero(n);
  second.setZero(n);
  family.setZero(n);
  for (Eigen::ArrayXd* a : {&normal_stiffness, &shear_stiffness, &bending_stiffness,
                            &twisting_stiffness, &length, &lever_first, &lever_second}) {
    a->setZero(n);
  }
  normal.setZero(n, 3);
}

void set_bond_geometry(const Particles& particles, Bonds& bonds, int b) {
  const int i = bonds.first(b);
  const int j = bonds.second(b);
  const Eigen::Vector3d branch =
      (particles.reference_position.row(j) - particles.reference_position.row(i))
          .matrix()
          .transpose();
  const double length = branch.norm();
  if (!(length > 0)) {
    throw Error(fmt::format("bond {} joins particles {} and {} at the same position", b, i, j));
  }
  bonds.normal.row(b) = (branch / length).transpose().array();
  bonds.length(b) = length;
  const double gap = length - particles.radius(i) - particles.radius(j);
  bonds.lever_first(b) = particles.radius(i) + 0.5 * gap;
  bonds.lever_second(b) = particles.radius(j) + 0.5 * gap;
}

void Model::check_consistency() const {
  const int n = particles.size();
  const auto& p = particles;
  require(n > 0, "the model has no particles");
  for (const Vector3Array* a : {&p.reference_position, &p.displacement, &p.velocity, &p.rotation,
                                &p.angular_velocity, &p.force, &p.torque}) {
    require(a->rows() == n, "particle arrays differ in size");
  }
  require(p.moment_of_inertia.size() == n && p.radius.size() == n && p.volume.size() == n &&
              p.ply.size() == n && p.group.size() == n,
          "particle arrays differ in size");
  for (int i = 0; i < n; ++i) {
    if (!(p.reference_position.row(i).isFinite().all()))
      throw Error(fmt::format("particle {} has a non-finite position", i));
    if (!(std::isfinite(p.mass(i)) && p.mass(i) > 0))
      throw Error(fmt::format("particle {} has a non-positive mass {}", i, p.mass(i)));
    if (!(std::isfinite(p.moment_of_inertia(i)) && p.moment_of_inertia(i) > 0))
      throw Error(fmt::format("particle {} has a non-positive moment of inertia", i));
    if (!(std::isfinite(p.radius(i)) && p.radius(i) > 0))
      throw Error(fmt::format("particle {} has a non-positive radius", i));
  }
  const Bonds& b = bonds;
  const int m = b.size();
  require(b.second.size() == m && b.normal_stiffness.size() == m && b.shear_stiffness.size() == m &&
              b.bending_stiffness.size() == m && b.twisting_stiffness.size() == m &&
              b.normal.rows() == m && b.length.size() == m && b.lever_first.size() == m &&
              b.lever_second.size() == m && b.family.size() == m,
          "bond arrays differ in size");
  std::set<std::pair<int, int>> seen;
  for (int k = 0; k < m; ++k) {
    const int i = b.first(k), j = b.second(k);
    if (!(i >= 0 && i < n && j >= 0 && j < n))
      throw Error(fmt::format("bond {} refers to a missing particle ({}, {})", k, i, j));
    if (!(i != j)) throw Error(fmt::format("bond {} joins particle {} to itself", k, i));
    if (!(seen.insert({std::min(i, j), std::max(i, j)}).second))
      throw Error(
          fmt::format("bond {} duplicates another bond between particles {} and {}", k, i, j));
    for (double s : {b.normal_stiffness(k), b.shear_stiffness(k), b.bending_stiffness(k),
                     b.twisting_stiffness(k)}) {
      if (!(std::isfinite(s) && s >= 0))
        throw Error(
            fmt::format("bond {} has a negative or non-finite stiffness {}: the calibration "
                        "produced an unstable lattice",
                        k, s));
    }
    if (!(std::isfinite(b.length(k)) && b.length(k) > 0))
      throw Error(fmt::format("bond {} has a non-positive length", k));
    if (!(std::abs(b.normal.row(k).matrix().norm() - 1.0) < 1e-12))
      throw Error(fmt::format("bond {} has a normal that is not a unit vector", k));
  }
}

}  // namespace plydem
