#include "solvers/static_solver.hpp"

#include <fmt/format.h>

#include <Eigen/IterativeLinearSolvers>
#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <string>
#include <utility>
#include <vector>

#include "contacts/bond_kernel.hpp"
#include "core/disjoint_sets.hpp"
#include "core/error.hpp"
#include "core/stopwatch.hpp"
#include "core/units.hpp"
#include "solvers/sparse_cholesky.hpp"
#include "solvers/stiffness_assembly.hpp"

namespace plydem {
namespace {

using SparseMatrix = Eigen::SparseMatrix<double>;
Eigen::Vector3d reference_of(const Particles& p, int i) {
  return {p.reference_position(i, 0), p.reference_position(i, 1), p.reference_position(i, 2)};
}

std::string dof_at(const Particles& p, int dof) {
  return fmt::format("{} of {}", dof_name(static_cast<Dof>(dof % kDofsPerParticle)),
                     describe_particle(p, dof / kDofsPerParticle));
}

// Input checks that the linear algebra cannot explain well afterwards.
void check_input(const Model& model, const DofConstraints& constraints) {
  const Particles& p = model.particles;
  const Bonds& b = model.bonds;
  const int n = p.size();
  require(n > 0, "static solve: the model has no particles");
  require(p.reference_position.rows() == n && p.displacement.rows() == n &&
              p.rotation.rows() == n && p.force.rows() == n && p.torque.rows() == n &&
              p.radius.size() == n,
          "static solve: the particle arrays differ in size");
  require(p.reference_position.allFinite(), "static solve: a particle position is not finite");
  require(constraints.fixed.rows() == n && constraints.value.rows() == n,
          fmt::format("static solve: the constraints are for {} particles, the model has {}",
                      constraints.fixed.rows(), n));
  for (int i = 0; i < n; ++i)
    for (int c = 0; c < kDofsPerParticle; ++c)
      if (constraints.fixed(i, c) && !std::isfinite(constraints.value(i, c)))
        throw Error(
            fmt::format("static solve: the prescribed {} is not finite", dof_at(p, 6 * i + c)));

  const int m = b.size();
  require(b.second.size() == m && b.normal_stiffness.size() == m && b.shear_stiffness.size() == m &&
              b.bending_stiffness.size() == m && b.twisting_stiffness.size() == m &&
              b.normal.rows() == m && b.lever_first.size() == m && b.lever_second.size() == m,
          "static solve: the bond arrays differ in size");
  for (int k = 0; k < m; ++k) {
    const int i = b.first(k), j = b.second(k);
    if (i < 0 || i >= n || j < 0 || j >= n || i == j)
      throw Error(
          fmt::format("static solve: bond {} joins particles {} and {}, which is not a pair of "
                      "the model's {} particles",
                      k, i, j, n));
    const std::pair<const char*, double> stiffness[] = {{"normal", b.normal_stiffness(k)},
                                                        {"shear", b.shear_stiffness(k)},
                                                        {"bending", b.bending_stiffness(k)},
                                                        {"twisting", b.twisting_stiffness(k)}};
    for (const auto& [name, value] : stiffness) {
      if (!std::isfinite(value))
        throw Error(
            fmt::format("static solve: bond {} (particles {} and {}) has a non-finite {} "
                        "stiffness",
                        k, i, j, name));
      // A negative spring makes K indefinite: the "equilibrium" would be a saddle that the
      // explicit integrator runs away from, so solving it would hide the real problem.
      if (value < 0)
        throw Error(
            fmt::format("static solve: bond {} (particles {} and {}) has negative {} stiffness "
                        "{:.6g}: unstable calibration (K is indefinite)",
                        k, i, j, name, value));
    }
    if (!(b.normal.row(k).allFinite() && std::isfinite(b.lever_first(k)) &&
          std::isfinite(b.lever_second(k))))
      throw Error(fmt::format("static solve: bond {} has a non-finite normal or lever", k));
  }

  // A particle without bonds has an all-zero row in K: nothing determines its free dofs.
  std::vector<int> bond_count(n, 0);
  for (int k = 0; k < m; ++k) {
    ++bond_count[b.first(k)];
    ++bond_count[b.second(k)];
  }
  for (int i = 0; i < n; ++i) {
    if (bond_count[i] == 0 && !constraints.fixed.row(i).all()) {
      throw Error(
          fmt::format("static solve: {} has no bonds: it floats freely (prescribe all six "
                      "of its dofs or remove it)",
                      describe_particle(p, i)));
    }
  }
}

// Clusters of bond-connected particles (union-find); each has its own six rigid-body modes.
std::vector<std::vector<int>> bonded_clusters(const Model& model) {
  const int n = model.particles.size();
  DisjointSets sets(n);
  for (int k = 0; k < model.bonds.size(); ++k)
    sets.join(model.bonds.first(k), model.bonds.second(k));
  auto root = [&](int i) { return sets.find(i); };
  std::vector<int> index(n, -1);
  std::vector<std::vector<int>> clusters;
  for (int i = 0; i < n; ++i) {
    const int r = root(i);
    if (index[r] < 0) {
      index[r] = static_cast<int>(clusters.size());
      clusters.emplace_back();
    }
    clusters[index[r]].push_back(i);
  }
  return clusters;
}

using RigidRow = Eigen::Matrix<double, 6, 1>;

constexpr const char* kRigidModeNames[6] = {"translation x",    "translation y",
                                            "translation z",    "rotation about x",
                                            "rotation about y", "rotation about z"};

// The rigid modes of one cluster left free by the constraints, and the dofs that remove them.
struct ClusterModes {
  std::vector<int> particles;
  std::vector<std::string> free_modes;  // named where a mode is a pure translation or rotation
  int free_count = 0;
  std::vector<PinnedDof> pins;
};

// Row of dof (i, c) in the matrix of the cluster's six rigid modes: translations e_k, and rotations
// e_k / L about the centroid x_c, u = e_k x (x - x_c) / L. Rotation dofs are measured as L theta so
// that every entry is O(1) and the rank decisions below do not depend on the units.
RigidRow rigid_row(const Eigen::Vector3d& r_over_l, int c) {
  RigidRow row = RigidRow::Zero();
  row(c) = 1;
  if (c < 3)
    for (int k = 0; k < 3; ++k) row(3 + k) = Eigen::Vector3d::Unit(k).cross(r_over_l)(c);
  return row;
}

ClusterModes analyse_cluster(const Particles& p, const DofConstraints& constraints,
                             std::vector<int> cluster) {
  ClusterModes out;
  out.particles = std::move(cluster);
  const std::vector<int>& members = out.particles;
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (int i : members) centroid += reference_of(p, i);
  centroid /= static_cast<double>(members.size());
  double spread = 0, radius = 0;
  for (int i : members) {
    spread += (reference_of(p, i) - centroid).squaredNorm();
    radius = std::max(radius, p.radius(i));
  }
  const double length = std::max(std::sqrt(spread / static_cast<double>(members.size())), radius);
  const double scale = length > 0 ? length : 1.0;

  Eigen::Matrix<double, 6, 6> gram = Eigen::Matrix<double, 6, 6>::Zero();
  for (int i : members) {
    const Eigen::Vector3d r = (reference_of(p, i) - centroid) / scale;
    for (int c = 0; c < kDofsPerParticle; ++c) {
      if (!constraints.fixed(i, c)) continue;
      const RigidRow row = rigid_row(r, c);
      gram += row * row.transpose();
    }
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>> eigen(gram);
  const double largest = eigen.eigenvalues().maxCoeff();
  std::vector<int> null_columns;
  for (int k = 0; k < 6; ++k)
    if (eigen.eigenvalues()(k) <= 1e-10 * std::max(largest, 1.0)) null_columns.push_back(k);
  out.free_count = static_cast<int>(null_columns.size());
  if (out.free_count == 0) return out;
  // At most six free modes: fixed-capacity matrices keep the loops below free of allocations.
  using NullBasis = Eigen::Matrix<double, 6, Eigen::Dynamic, 0, 6, 6>;
  using ModeVector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 6, 1>;
  NullBasis null(6, out.free_count);
  for (int k = 0; k < out.free_count; ++k) null.col(k) = eigen.eigenvectors().col(null_columns[k]);

  int named = 0;
  for (int k = 0; k < 6; ++k) {
    if (null.row(k).norm() > 1 - 1e-8) {  // the canonical mode k lies in the free space
      out.free_modes.emplace_back(kRigidModeNames[k]);
      ++named;
    }
  }
  if (named < out.free_count) {
    out.free_modes.push_back(fmt::format("{} combination{} of rigid motions",
                                         out.free_count - named,
                                         out.free_count - named > 1 ? "s" : ""));
  }

  // Greedy choice of one free dof per free mode: each time the dof whose row (in the free modes'
  // coordinates) has the largest part outside the rows already chosen, i.e. a column-pivoted QR.
  // Ties (a translation is the same at every particle) go to the particle nearest the centroid.
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 6, 6> chosen(out.free_count,
                                                                        out.free_count);
  for (int step = 0; step < out.free_count; ++step) {
    double best = 0, best_distance = 0;
    int best_particle = -1, best_dof = -1;
    ModeVector best_residual;
    for (int i : members) {
      const Eigen::Vector3d r = (reference_of(p, i) - centroid) / scale;
      const double distance = r.norm();
      for (int c = 0; c < kDofsPerParticle; ++c) {
        if (constraints.fixed(i, c)) continue;
        const ModeVector a = null.transpose() * rigid_row(r, c);
        const ModeVector residual =
            a - chosen.leftCols(step) * (chosen.leftCols(step).transpose() * a);
        const double norm = residual.norm();
        const bool clearly_better = norm > best * (1 + 1e-9);
        const bool tie = norm >= best * (1 - 1e-9) && distance < best_distance - 1e-12;
        if (norm > 1e-9 && (best_particle < 0 || clearly_better || tie)) {
          best = norm;
          best_distance = distance;
          best_particle = i;
          best_dof = c;
          best_residual = residual / norm;
        }
      }
    }
    // Cannot happen while modes are free (a free mode is non-zero on some free dof), but a
    // silent partial pin would mislead: say so.
    require(best_particle >= 0, "static solve: no free dof can remove a rigid-body mode");
    out.pins.push_back({best_particle, static_cast<Dof>(best_dof)});
    chosen.col(step) = best_residual;
  }
  return out;
}

std::vector<ClusterModes> free_rigid_modes(const Model& model, const DofConstraints& constraints) {
  std::vector<ClusterModes> out;
  for (std::vector<int>& cluster : bonded_clusters(model)) {
    // A lone particle without bonds is not a rigid body of the lattice: check_input names it.
    if (cluster.size() == 1) continue;
    ClusterModes modes = analyse_cluster(model.particles, constraints, std::move(cluster));
    if (modes.free_count > 0) out.push_back(std::move(modes));
  }
  return out;
}

std::string join(const std::vector<std::string>& items) {
  std::string s;
  for (std::size_t k = 0; k < items.size(); ++k) s += (k ? ", " : "") + items[k];
  return s;
}

[[noreturn]] void refuse_rigid_modes(const Particles& p, const std::vector<ClusterModes>& free) {
  std::vector<std::string> clusters;
  for (const ClusterModes& c : free) {
    std::vector<std::string> pins;
    for (const PinnedDof& pin : c.pins)
      pins.push_back(
          fmt::format("{} of {}", dof_name(pin.dof), describe_particle(p, pin.particle)));
    clusters.push_back(fmt::format(
        "the cluster of {} bonded particles containing particle {} has {} free rigid-body "
        "mode{} ({}); fixing {} would remove them",
        c.particles.size(), c.particles.front(), c.free_count, c.free_count > 1 ? "s" : "",
        join(c.free_modes), join(pins)));
  }
  throw Error(fmt::format(
      "static solve: the constraints leave rigid-body modes free, so the stiffness matrix is "
      "singular: {}. Prescribe those dofs, or set StaticSettings::pin_rigid_modes (or call "
      "pin_rigid_modes) to fix them at zero",
      join(clusters)));
}

// Zero pivots of the factor: the free dofs the bonds do not restrain (a mechanism). `zero` lists
// them by free index; `pivots` are in the same numbering.
[[noreturn]] void refuse_zero_pivots(const Particles& p, const std::vector<int>& free_dofs,
                                     const Eigen::VectorXd& pivots, const std::vector<int>& zero,
                                     double tolerance) {
  bool negative = false;
  for (int f : zero)
    if (pivots(f) < -tolerance) negative = true;
  std::vector<std::string> at;
  for (std::size_t k = 0; k < zero.size() && k < 6; ++k)
    at.push_back(dof_at(p, free_dofs[zero[k]]));
  if (zero.size() > at.size()) at.push_back(fmt::format("and {} more", zero.size() - at.size()));
  throw Error(fmt::format(
      "static solve: the free dofs are not restrained: the LDL^T factor of the stiffness has {} "
      "zero pivot{} (at most {:.3g} of the diagonal) among {} free dofs, at {}. {}"
      "No rigid-body mode of a bonded cluster is free, so the bonds form a mechanism there "
      "(springs with zero shear, bending or twisting stiffness, or a part held only through "
      "one particle): prescribe those dofs or stiffen the bonds",
      zero.size(), zero.size() > 1 ? "s" : "", tolerance, pivots.size(), join(at),
      negative ? "Some pivots are negative: the system is indefinite or numerically singular. "
               : ""));
}

}  // namespace

// Whether the bonds leave each bonded cluster free to move only as a rigid body, so that, with the
// clusters' rigid modes prescribed (free_rigid_modes), the free-free stiffness is positive
// definite and there is no mechanism to look for. A sufficient test, from the bonds alone:
// - a full bond (k_n, k_s, the out-of-plane shear, k_b and k_t all positive) resists every
//   relative motion of its two particles: particles joined by full bonds move as one rigid body;
// - a point bond (k_n and both shears positive, k_b or k_t zero, as the laminates' interface
//   bonds) ties the two particles' material points at its contact (x_first + lever_first n =
//   x_second - lever_second n); two rigid bodies tied at three or more non-collinear contact
//   points move as one, and merging repeats until nothing merges;
// - a broken bond: nothing (its stiffnesses are zero);
// - any other bond, or bodies left apart within one bonded cluster (broken bonds included, as
//   bonded_clusters joins them): false (the probe decides).
bool free_motions_are_rigid(const Model& model) {
  const Bonds& b = model.bonds;
  const auto& x = model.particles.reference_position;
  const int n = model.particles.size();
  DisjointSets bodies(n);
  auto root = [&](int i) { return bodies.find(i); };
  auto join = [&](int i, int j) { return bodies.join(i, j); };
  std::vector<int> point_bonds;
  std::vector<Eigen::Vector3d> contact;
  double extent = 0;
  for (int d = 0; d < 3; ++d)
    if (n > 0) extent = std::max(extent, x.col(d).maxCoeff() - x.col(d).minCoeff());
  for (int k = 0; k < b.size(); ++k) {
    if (b.is_broken(k)) continue;  // no stiffness; its particles must be one body (below)
    if (!(b.normal_stiffness(k) > 0 && b.shear_stiffness(k) > 0 &&
          b.out_of_plane_shear_ratio(k) > 0))
      return false;
    if (b.bending_stiffness(k) > 0 && b.twisting_stiffness(k) > 0) {
      join(b.first(k), b.second(k));
      continue;
    }
    const Eigen::Vector3d normal = b.normal.row(k).transpose().matrix();
    const Eigen::Vector3d on_first =
        x.row(b.first(k)).transpose().matrix() + b.lever_first(k) * normal;
    const Eigen::Vector3d on_second =
        x.row(b.second(k)).transpose().matrix() - b.lever_second(k) * normal;
    if ((on_first - on_second).norm() > 1e-9 * std::max(b.length(k), extent)) return false;
    point_bonds.push_back(k);
    contact.push_back(on_first);
  }
  // Merge bodies tied at three non-collinear points, until none merges.
  const double tolerance = 1e-6 * extent;
  for (bool merged = true; merged;) {
    merged = false;
    std::map<std::pair<int, int>, std::vector<int>> ties;  // body pair -> contacts
    for (std::size_t t = 0; t < point_bonds.size(); ++t) {
      const int a = root(b.first(point_bonds[t])), c = root(b.second(point_bonds[t]));
      if (a != c) ties[{std::min(a, c), std::max(a, c)}].push_back(static_cast<int>(t));
    }
    for (const auto& [pair, points] : ties) {
      if (points.size() < 3) continue;
      const Eigen::Vector3d& p0 = contact[points[0]];
      int far = points[0];
      for (int t : points)
        if ((contact[t] - p0).norm() > (contact[far] - p0).norm()) far = t;
      const Eigen::Vector3d axis = contact[far] - p0;
      if (axis.norm() <= tolerance) continue;
      const Eigen::Vector3d unit = axis.normalized();
      bool spread = false;
      for (int t : points) {
        const Eigen::Vector3d r = contact[t] - p0;
        if ((r - r.dot(unit) * unit).norm() > tolerance) {
          spread = true;
          break;
        }
      }
      if (spread) merged |= join(pair.first, pair.second);
    }
  }
  // Every bond's particles, broken bonds' included: the clusters free_rigid_modes pins are
  // joined by every bond, so a piece that broken bonds alone hold to its cluster is a mechanism.
  for (int k = 0; k < b.size(); ++k)
    if (root(b.first(k)) != root(b.second(k))) return false;
  return true;
}

const char* dof_name(Dof dof) {
  switch (dof) {
    case Dof::kUx:
      return "ux";
    case Dof::kUy:
      return "uy";
    case Dof::kUz:
      return "uz";
    case Dof::kThetaX:
      return "theta_x";
    case Dof::kThetaY:
      return "theta_y";
    case Dof::kThetaZ:
      return "theta_z";
  }
  return "?";
}

DofConstraints::DofConstraints(int particles)
    : fixed(DofFlags::Constant(particles, kDofsPerParticle, false)),
      value(DofArray::Zero(particles, kDofsPerParticle)) {}

void DofConstraints::fix(int particle, Dof dof, double v) {
  if (particle < 0 || particle >= fixed.rows())
    throw Error(fmt::format("constraint on particle {}, which does not exist", particle));
  fixed(particle, static_cast<int>(dof)) = true;
  value(particle, static_cast<int>(dof)) = v;
}

void DofConstraints::fix_particle(int particle, const Eigen::Vector3d& u,
                                  const Eigen::Vector3d& theta) {
  for (int c = 0; c < 3; ++c) {
    fix(particle, static_cast<Dof>(c), u(c));
    fix(particle, static_cast<Dof>(3 + c), theta(c));
  }
}

int DofConstraints::fix_group(const Particles& particles, BoundaryGroup group, Dof dof, double v) {
  require(particles.size() == fixed.rows(),
          fmt::format("the constraints are for {} particles, the model has {}", fixed.rows(),
                      particles.size()));
  int count = 0;
  for (int i = 0; i < particles.size(); ++i) {
    if (particles.group(i) != static_cast<int>(group)) continue;
    fix(i, dof, v);
    ++count;
  }
  return count;
}

int DofConstraints::prescribed_count() const {
  return static_cast<int>(fixed.count());
}

std::vector<PinnedDof> rigid_mode_pins(const Model& model, const DofConstraints& constraints) {
  require(constraints.fixed.rows() == model.particles.size(),
          fmt::format("the constraints are for {} particles, the model has {}",
                      constraints.fixed.rows(), model.particles.size()));
  std::vector<PinnedDof> pins;
  for (const ClusterModes& c : free_rigid_modes(model, constraints))
    pins.insert(pins.end(), c.pins.begin(), c.pins.end());
  return pins;
}

std::vector<PinnedDof> pin_rigid_modes(const Model& model, DofConstraints& constraints) {
  const std::vector<PinnedDof> pins = rigid_mode_pins(model, constraints);
  for (const PinnedDof& pin : pins) constraints.fix(pin.particle, pin.dof, 0.0);
  return pins;
}

namespace {

// A translational and a rotational field of the particles (one row each) as one vector in dof
// order: 6 * particle + component.
Eigen::VectorXd dof_vector(const Vector3Array& translational, const Vector3Array& rotational) {
  const auto n = translational.rows();
  Eigen::VectorXd v(kDofsPerParticle * n);
  for (Eigen::Index i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c) {
      v(kDofsPerParticle * i + c) = translational(i, c);
      v(kDofsPerParticle * i + 3 + c) = rotational(i, c);
    }
  return v;
}

}  // namespace

Eigen::VectorXd particle_state_vector(const Particles& p) {
  return dof_vector(p.displacement, p.rotation);
}

namespace {

// Generalized forces of the bonds, -K q, by the explicit kernel, in dof order.
Eigen::VectorXd bond_generalized_forces(Particles& p, const Bonds& bonds, double* energy) {
  const BondPass pass = compute_bond_forces(p, bonds);
  if (energy) *energy = pass.strain_energy;
  return dof_vector(p.force, p.torque);
}

// The generalized forces the bonds' free offsets put on the particles at zero displacement and
// rotation (the load g0 of K u = g0: each bond pulls its ends towards its free offset).
Eigen::VectorXd free_offset_load(const Model& model) {
  const Bonds& bonds = model.bonds;
  Eigen::VectorXd g = Eigen::VectorXd::Zero(kDofsPerParticle * model.particles.size());
  const Eigen::Vector3d zero = Eigen::Vector3d::Zero();
  for (int b = 0; b < bonds.size(); ++b) {
    if (bonds.is_broken(b) || (bonds.free_offset.row(b) == 0).all()) continue;
    const BondResponse r =
        parallel_bond_response(bond_parameters(bonds, b), zero, zero, zero, zero);
    const int i = kDofsPerParticle * bonds.first(b), j = kDofsPerParticle * bonds.second(b);
    g.segment<3>(i) += r.force_on_first;
    g.segment<3>(j) -= r.force_on_first;
    g.segment<3>(i + 3) += r.torque_on_first;
    g.segment<3>(j + 3) += r.torque_on_second;
  }
  return g;
}

void set_state(Particles& p, const Eigen::VectorXd& u) {
  for (int i = 0; i < p.size(); ++i)
    for (int c = 0; c < 3; ++c) {
      p.displacement(i, c) = u(kDofsPerParticle * i + c);
      p.rotation(i, c) = u(kDofsPerParticle * i + 3 + c);
    }
}

}  // namespace

SparseMatrix assemble_stiffness(const Model& model) {
  const int dofs = kDofsPerParticle * model.particles.size();
  std::vector<int> all(dofs);
  std::iota(all.begin(), all.end(), 0);
  const SparseMatrix lower =
      compress_lower(block_stiffness(model, EliminationOrder::identity(model.particles.size())),
                     all, dofs, Eigen::VectorXd::Ones(dofs));
  const SparseMatrix strictly_lower = lower.triangularView<Eigen::StrictlyLower>();
  return lower + SparseMatrix(strictly_lower.transpose());
}

void validate(const StaticSettings& settings) {
  require(settings.direct_max_dofs >= 0 && settings.cg_max_iterations >= 0 &&
              settings.expected_solves >= 1 && std::isfinite(settings.cg_tolerance) &&
              settings.cg_tolerance > 0 && std::isfinite(settings.pivot_tolerance) &&
              settings.pivot_tolerance > 0 && settings.pivot_tolerance < 1,
          "static solver settings out of range (need direct_max_dofs >= 0, cg_max_iterations >= "
          "0, expected_solves >= 1, cg_tolerance > 0, 0 < pivot_tolerance < 1)");
}

using IncompleteCholeskyCg = Eigen::ConjugateGradient<
    SparseMatrix, Eigen::Lower,
    Eigen::IncompleteCholesky<double, Eigen::Lower, Eigen::AMDOrdering<int>>>;
using JacobiCg =
    Eigen::ConjugateGradient<SparseMatrix, Eigen::Lower, Eigen::DiagonalPreconditioner<double>>;

struct StaticSystem::Impl {
  StaticSettings settings;
  DofConstraints constraints;  // the given ones and the pins (at zero)
  DofFlags given_fixed;        // the dofs whose values solve() reads
  std::vector<PinnedDof> pinned;
  int n = 0, bonds = 0, dofs = 0, nf = 0, prescribed = 0;
  bool direct = true;
  EliminationOrder order;
  std::vector<int> free_index;  // rank-ordered dof -> free index or -1
  std::vector<int> free_dofs;   // free index -> model dof (6 * particle + component)
  Eigen::VectorXd s;            // Jacobi scaling of the free dofs
  BlockStiffness k;             // for the right-hand sides -K_fp u_p
  SparseMatrix a;               // lower triangle of S K_ff S
  // Under mpiexec with PETSc: the particles whose rows this rank assembles (k and a hold only
  // theirs whole; linear_solver.hpp, rank_particles); empty: every row.
  std::vector<char> own;
  Eigen::Index nonzeros = 0;  // of the whole lower triangle, every rank's share summed
  std::unique_ptr<LinearSolver> cholesky;
  std::unique_ptr<IncompleteCholeskyCg> cg_ic;
  std::unique_ptr<JacobiCg> cg_jacobi;
  std::string method_name;
  std::string choice;  // kAuto's, LinearSolver::choice()
  StaticTimings setup;
  int factorizations = 0;
  mutable int solves = 0;

  // The blocks (the bonds that reach the particles `own` flags, or all), the Jacobi scaling and
  // the scaled lower triangle, and the whole triangle's entries.
  void assemble(const Model& model) {
    k = block_stiffness(model, order, own.empty() ? nullptr : &own);
    // Jacobi scaling A = S K_ff S with S = diag(K_ff)^-1/2. Rotational and translational
    // stiffnesses differ by the squared particle radius (1e-10 in SI); with a unit diagonal the
    // factorization's pivot test means the same for both, and CG's preconditioners start better
    // conditioned.
    for (int f = 0; f < nf; ++f) {
      const int i = free_dofs[f] / kDofsPerParticle, c = free_dofs[f] % kDofsPerParticle;
      const double diagonal = k.diagonal(order.rank[i], c);
      if (!(diagonal > 0))
        throw Error(
            fmt::format("static solve: nothing resists {}: every bond of the particle has zero "
                        "stiffness in that direction; prescribe it or stiffen the bonds",
                        dof_at(model.particles, free_dofs[f])));
      s(f) = 1 / std::sqrt(diagonal);
    }
    // The lower triangle only: all that the factorizations, IC and CG read, at half the memory.
    a = compress_lower(k, free_index, nf, s);
    nonzeros = a.nonZeros();
    if (!own.empty()) {  // the columns of a rank's own particles are whole, and no other rank's
      double own_columns = 0;
      for (int f = 0; f < nf; ++f)
        if (own[static_cast<std::size_t>(free_dofs[f] / kDofsPerParticle)])
          own_columns += static_cast<double>(a.outerIndexPtr()[f + 1] - a.outerIndexPtr()[f]);
      sum_over_ranks(&own_columns, 1);
      nonzeros = static_cast<Eigen::Index>(own_columns);
    }
  }

  template <typename Cg>
  std::unique_ptr<Cg> make_cg() const {
    auto cg = std::make_unique<Cg>();
    cg->setTolerance(settings.cg_tolerance);
    if (settings.cg_max_iterations > 0) cg->setMaxIterations(settings.cg_max_iterations);
    cg->compute(a);
    require(cg->info() == Eigen::Success,
            "static solve: the preconditioner of the conjugate gradient could not be built");
    return cg;
  }

  template <typename Cg>
  void run_cg(const Cg& cg, const Eigen::VectorXd& b, Eigen::VectorXd& y,
              StaticResult& result) const {
    y = cg.solveWithGuess(b, y);
    result.iterations = static_cast<int>(cg.iterations());
    require(cg.info() == Eigen::Success,
            fmt::format("static solve: the conjugate gradient did not converge in {} iterations "
                        "(relative residual {:.3g} > tolerance {:.3g}); the free dofs may form a "
                        "mechanism (try StaticMethod::kDirect, which names it) or the tolerance is "
                        "below round-off",
                        cg.iterations(), cg.error(), settings.cg_tolerance));
  }
};

StaticSystem::StaticSystem(const Model& model, const DofConstraints& given,
                           const StaticSettings& settings)
    : impl_(std::make_unique<Impl>()) {
  validate(settings);
  Impl& m = *impl_;
  m.settings = settings;
  Stopwatch phase;
  check_input(model, given);
  m.constraints = given;
  m.given_fixed = given.fixed;
  const std::vector<ClusterModes> free = free_rigid_modes(model, m.constraints);
  if (!free.empty()) {
    if (!settings.pin_rigid_modes) refuse_rigid_modes(model.particles, free);
    for (const ClusterModes& c : free)
      for (const PinnedDof& pin : c.pins) {
        m.constraints.fix(pin.particle, pin.dof, 0.0);
        m.pinned.push_back(pin);
      }
  }
  m.setup.checks = phase.seconds();

  const Particles& p = model.particles;
  const int n = m.n = p.size();
  m.bonds = model.bonds.size();
  const int dofs = m.dofs = kDofsPerParticle * n;
  m.prescribed = m.constraints.prescribed_count();
  const int nf = m.nf = dofs - m.prescribed;
  // Whether PETSc may solve: asked for, or kAuto for a caller making few solves (kAuto's linear
  // solver then decides after its symbolic analysis).
  const bool few_solves = settings.linear_solver_use == LinearSolverUse::kFewSolves;
  const bool petsc_may_solve =
      petsc_available() && (settings.linear_solver == LinearSolverKind::kPetsc ||
                            (settings.linear_solver == LinearSolverKind::kAuto && few_solves));
  // Above direct_max_dofs kAuto takes an iterative method: PETSc's CG + AMG where it may solve
  // and the caller makes few solves, Eigen's CG otherwise.
  const bool large = settings.method == StaticMethod::kAuto && nf > settings.direct_max_dofs;
  const bool petsc_takes_large = large && petsc_may_solve && few_solves;
  const LinearSolverKind kind =
      petsc_takes_large ? LinearSolverKind::kPetsc : settings.linear_solver;
  m.direct = settings.method == StaticMethod::kDirect ||
             (settings.method == StaticMethod::kAuto && (!large || petsc_takes_large));

  // The hand-written direct solver (and kAuto, which starts with its analysis) factorizes in a
  // fill-reducing order of the particles (counted with the factorization); CHOLMOD orders the
  // dofs itself and CG needs none.
  phase.restart();
  // PETSc numbers the particles itself (slices along the model's longest extent, one per rank).
  m.order =
      m.direct && nf > 0 && kind != LinearSolverKind::kCholmod && kind != LinearSolverKind::kPetsc
          ? EliminationOrder::minimum_degree(model)
          : EliminationOrder::identity(n);
  const double ordering_seconds = phase.seconds();

  phase.restart();
  // Dofs in rank order (dof 6 * rank + component): index among the free dofs, or -1 if
  // prescribed; free_dofs[f] is the model's dof (6 * particle + component) of free index f.
  m.free_index.assign(dofs, -1);
  m.free_dofs.reserve(nf);
  for (int r = 0; r < n; ++r) {
    const int i = m.order.order[r];
    for (int c = 0; c < kDofsPerParticle; ++c) {
      if (m.constraints.fixed(i, c)) continue;
      m.free_index[kDofsPerParticle * r + c] = static_cast<int>(m.free_dofs.size());
      m.free_dofs.push_back(kDofsPerParticle * i + c);
    }
  }

  m.s.resize(nf);
  // Under mpiexec, where PETSc solves (chosen here, not by kAuto's own choice later), each rank
  // assembles the bonds that reach its own particles only: the rows it hands PETSc.
  if (m.direct && nf > 0 && kind == LinearSolverKind::kPetsc)
    m.own = rank_particles(p.reference_position);
  m.assemble(model);
  m.setup.assembly = phase.seconds();

  phase.restart();
  if (nf == 0) {
    m.method_name = "none (every dof prescribed)";
  } else if (m.direct) {
    m.cholesky = make_linear_solver(kind, settings.linear_solver_use, settings.force,
                                    settings.expected_solves);
    // Round-off leaves a zero pivot far above machine epsilon, the more so the larger the
    // system: on hex2d coupons with a free rigid mode we measured up to 4e-10 at 2.3e4 free dofs
    // and 2.4e-8 at 9.1e4, while the smallest genuine pivot stayed above 3e-5. Hence a threshold
    // that grows with the size. The factorization collects every zero pivot in one pass.
    const double threshold = settings.pivot_tolerance * std::max(nf, 1000);
    // Where the unknowns sit, for PETSc's rigid-body near-null space.
    // The rigidity test only where PETSc may solve (it spares PETSc's mechanism probe).
    m.cholesky->set_layout({m.free_dofs, m.s, p.reference_position,
                            petsc_may_solve && free_motions_are_rigid(model), !m.own.empty()});
    m.cholesky->factor(m.a, threshold);
    ++m.factorizations;
    if (!m.cholesky->zero_pivots().empty())
      refuse_zero_pivots(p, m.free_dofs, m.cholesky->pivots(), m.cholesky->zero_pivots(),
                         threshold);
    m.method_name = m.cholesky->name();
    m.choice = m.cholesky->choice();
    m.setup.factorization = ordering_seconds + phase.seconds();
  } else if (settings.preconditioner == StaticPreconditioner::kIncompleteCholesky) {
    m.method_name = "ConjugateGradient + IncompleteCholesky";
    m.cg_ic = m.make_cg<IncompleteCholeskyCg>();
    m.setup.factorization = phase.seconds();
  } else {
    m.method_name = "ConjugateGradient + Jacobi";
    m.cg_jacobi = m.make_cg<JacobiCg>();
    m.setup.factorization = phase.seconds();
  }
}

StaticSystem::~StaticSystem() = default;
StaticSystem::StaticSystem(StaticSystem&&) noexcept = default;
StaticSystem& StaticSystem::operator=(StaticSystem&&) noexcept = default;

int StaticSystem::factorizations() const {
  return impl_->factorizations;
}

int StaticSystem::solves() const {
  return impl_->solves;
}

const DofConstraints& StaticSystem::constraints() const {
  return impl_->constraints;
}

const std::vector<int>& StaticSystem::free_dofs() const {
  return impl_->free_dofs;
}

void StaticSystem::solve_free_in_place(Eigen::MatrixXd& b) const {
  const Impl& m = *impl_;
  require(b.rows() == m.nf,
          fmt::format("static solve: {} rows given for the system's {} free dofs", b.rows(), m.nf));
  if (m.nf == 0) return;
  require(m.direct, "static solve: the iterative method keeps no factor to solve with");
  // K_ff = S^-1 A S^-1, so K_ff^-1 = S A^-1 S (A the Jacobi-scaled matrix that was factored).
  b.array().colwise() *= m.s.array();
  m.cholesky->solve_in_place(b);
  b.array().colwise() *= m.s.array();
}

StaticResult StaticSystem::solve(Model& model, const DofArray& values) const {
  return solve(model, values, true);
}

StaticResult StaticSystem::solve(Model& model, const DofArray& values,
                                 bool with_free_offsets) const {
  const Impl& m = *impl_;
  Particles& p = model.particles;
  require(p.size() == m.n && model.bonds.size() == m.bonds,
          fmt::format("static solve: the system was built for {} particles and {} bonds, the "
                      "model has {} and {}",
                      m.n, m.bonds, p.size(), model.bonds.size()));
  require(values.rows() == m.n,
          fmt::format("static solve: the prescribed values are for {} particles, the model has {}",
                      values.rows(), m.n));
  for (int i = 0; i < m.n; ++i)
    for (int c = 0; c < kDofsPerParticle; ++c)
      if (m.given_fixed(i, c) && !std::isfinite(values(i, c)))
        throw Error(
            fmt::format("static solve: the prescribed {} is not finite", dof_at(p, 6 * i + c)));

  StaticResult result;
  result.method = m.direct ? StaticMethod::kDirect : StaticMethod::kIterative;
  result.method_name = m.method_name;
  result.linear_solver_choice = m.choice;
  result.dofs = m.dofs;
  result.free_dofs = m.nf;
  result.prescribed_dofs = m.prescribed;
  result.stiffness_nonzeros = m.nonzeros;
  result.rank_stiffness_nonzeros = m.a.nonZeros();
  result.pinned = m.pinned;
  result.reused_factorization = m.solves > 0;
  result.factor_entries = m.cholesky ? m.cholesky->factor_entries() : 0.0;
  result.factor_flops = m.cholesky ? m.cholesky->factor_flops() : 0.0;
  if (!result.reused_factorization) result.seconds = m.setup;
  ++m.solves;

  // The prescribed values (pins at zero), in rank order, and the right-hand side -K_fp u_p from
  // the blocks (the prescribed values, free dofs at zero).
  Stopwatch phase;
  const int nf = m.nf;
  auto value_of = [&](int i, int c) { return m.given_fixed(i, c) ? values(i, c) : 0.0; };
  Eigen::VectorXd u_ranked = Eigen::VectorXd::Zero(m.dofs);
  for (int r = 0; r < m.n; ++r) {
    const int i = m.order.order[r];
    for (int c = 0; c < kDofsPerParticle; ++c)
      if (m.constraints.fixed(i, c)) u_ranked(kDofsPerParticle * r + c) = value_of(i, c);
  }
  Eigen::VectorXd b(nf);
  {
    const Eigen::VectorXd k_u = m.k.multiply(u_ranked);
    for (int d = 0; d < m.dofs; ++d)
      if (m.free_index[d] >= 0) b(m.free_index[d]) = -m.s(m.free_index[d]) * k_u(d);
  }
  if (with_free_offsets && model.bonds.has_free_offsets()) {
    const Eigen::VectorXd g0 = free_offset_load(model);
    for (int f = 0; f < nf; ++f) b(f) += m.s(f) * g0(m.free_dofs[f]);
  }
  result.seconds.assembly += phase.seconds();

  phase.restart();
  // The current state, scaled: the first iterate of an iterative solver (successive load stages,
  // or a caller's estimate of the solution, then take fewer iterations); direct factors ignore it.
  Eigen::VectorXd y = Eigen::VectorXd::Zero(nf);
  for (int f = 0; f < nf; ++f) {
    const int i = m.free_dofs[f] / kDofsPerParticle, c = m.free_dofs[f] % kDofsPerParticle;
    y(f) = (c < 3 ? p.displacement(i, c) : p.rotation(i, c - 3)) / m.s(f);
  }
  if (!y.allFinite()) y.setZero();
  if (nf > 0 && m.direct) {
    if (y.isZero(0)) {
      y = b;
      m.cholesky->solve_in_place(y);
    } else {
      m.cholesky->solve_from(y, b);
    }
    result.iterations = m.cholesky->iterations();
  } else if (nf > 0) {
    if (m.cg_ic)
      m.run_cg(*m.cg_ic, b, y, result);
    else
      m.run_cg(*m.cg_jacobi, b, y, result);
  }
  result.seconds.solve = phase.seconds();
  require(y.allFinite(),
          "static solve: the solution is not finite (the stiffness matrix is numerically "
          "singular)");
  const Eigen::VectorXd ay = m.a.selfadjointView<Eigen::Lower>() * y;
  double b_norm = b.norm(), residual = (ay - b).norm();
  if (!m.own.empty()) {  // over the rows each rank holds whole, summed over the ranks
    double squares[2] = {0, 0};
    for (int f = 0; f < nf; ++f)
      if (m.own[static_cast<std::size_t>(m.free_dofs[f] / kDofsPerParticle)]) {
        squares[0] += (ay(f) - b(f)) * (ay(f) - b(f));
        squares[1] += b(f) * b(f);
      }
    sum_over_ranks(squares, 2);
    residual = std::sqrt(squares[0]);
    b_norm = std::sqrt(squares[1]);
  }
  result.relative_residual = b_norm > 0 ? residual / b_norm : residual;

  // The solution, and the kernel's forces at it: ~0 on free dofs, -(K u)_p on prescribed ones.
  Eigen::VectorXd u(m.dofs);
  for (int i = 0; i < m.n; ++i)
    for (int c = 0; c < kDofsPerParticle; ++c)
      u(kDofsPerParticle * i + c) = m.constraints.fixed(i, c) ? value_of(i, c) : 0.0;
  for (int f = 0; f < nf; ++f) u(m.free_dofs[f]) = m.s(f) * y(f);
  set_state(p, u);
  const Eigen::VectorXd force = bond_generalized_forces(p, model.bonds, &result.strain_energy);
  result.reaction = DofArray::Zero(m.n, kDofsPerParticle);
  for (int i = 0; i < m.n; ++i)
    for (int c = 0; c < kDofsPerParticle; ++c)
      if (m.constraints.fixed(i, c)) result.reaction(i, c) = -force(kDofsPerParticle * i + c);
  return result;
}

StaticResult solve_static(Model& model, const DofConstraints& constraints,
                          const StaticSettings& settings) {
  const StaticSystem system(model, constraints, settings);
  return system.solve(model, constraints.value);
}

}  // namespace plydem
