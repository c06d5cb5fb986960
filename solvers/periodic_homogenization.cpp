#include "solvers/periodic_homogenization.hpp"

#include <fmt/format.h>

#include <Eigen/IterativeLinearSolvers>
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <vector>

#include "contacts/bond_kernel.hpp"
#include "core/error.hpp"
#include "core/parallel_bond.hpp"
#include "core/stopwatch.hpp"
#include "core/units.hpp"
#include "solvers/sparse_cholesky.hpp"
#include "solvers/stiffness_assembly.hpp"

namespace plydem {
namespace {

using SparseMatrix = Eigen::SparseMatrix<double>;

// A dof whose own stiffness is below this fraction of the stiffness its bonds could give it has
// none: its diagonal is round-off (e.g. a spin in a network of normal springs, where the bond
// stiffness is k_n n n^T and the lever arm n x theta is normal to n). Such a dof cannot be
// Jacobi-scaled: its round-off couplings would turn into O(1) entries.
constexpr double kUnrestrained = 1e-12;

// Columns of `rhs` solved by preconditioned conjugate gradients on the scaled matrix `a`.
template <typename Preconditioner>
Eigen::MatrixXd solve_cg(const SparseMatrix& a, const Eigen::MatrixXd& rhs,
                         const StaticSettings& settings) {
  Eigen::ConjugateGradient<SparseMatrix, Eigen::Lower, Preconditioner> cg;
  cg.setTolerance(settings.cg_tolerance);
  if (settings.cg_max_iterations > 0) cg.setMaxIterations(settings.cg_max_iterations);
  cg.compute(a);
  require(cg.info() == Eigen::Success,
          "periodic homogenization: the preconditioner of the conjugate gradient could not be "
          "built");
  Eigen::MatrixXd y(rhs.rows(), rhs.cols());
  for (Eigen::Index s = 0; s < rhs.cols(); ++s) {
    y.col(s) = cg.solve(rhs.col(s));
    if (cg.info() != Eigen::Success)
      throw Error(fmt::format(
          "periodic homogenization: the conjugate gradient did not converge for unit strain {} "
          "in {} iterations (relative residual {:.3g}); the fluctuations may form a mechanism "
          "(StaticMethod::kDirect names it)",
          s + 1, cg.iterations(), cg.error()));
  }
  return y;
}

}  // namespace

Eigen::Vector3d PeriodicModel::branch(int b) const {
  const Particles& p = model.particles;
  const int i = model.bonds.first(b), j = model.bonds.second(b);
  const Eigen::Vector3d offset =
      lattice_vectors * bond_image.row(b).matrix().transpose().cast<double>();
  return (p.reference_position.row(j) - p.reference_position.row(i)).matrix().transpose() + offset;
}

void PeriodicModel::check_consistency() const {
  model.check_consistency();
  const Bonds& bonds = model.bonds;
  const int m = bonds.size();
  require(bond_image.rows() == m,
          fmt::format("periodic model: {} bond images for {} bonds", bond_image.rows(), m));
  require(
      std::isfinite(volume) && volume > 0,
      fmt::format("periodic model: the volume of one period must be positive, got {} m^3", volume));
  require(lattice_vectors.allFinite(), "periodic model: a lattice vector is not finite");
  require(periodic[0] || periodic[1] || periodic[2], "periodic model: no direction is periodic");
  // The periodic lattice vectors must span their space: Gram determinant against their lengths.
  Eigen::MatrixXd spanning(3, 0);
  double scale = 1;
  for (int d = 0; d < 3; ++d)
    if (periodic[d]) {
      spanning.conservativeResize(3, spanning.cols() + 1);
      spanning.rightCols<1>() = lattice_vectors.col(d);
      scale *= lattice_vectors.col(d).squaredNorm();
    }
  const double gram = (spanning.transpose() * spanning).determinant();
  require(scale > 0 && gram > 1e-12 * scale,
          "periodic model: the periodic lattice vectors are zero or linearly dependent");
  for (int b = 0; b < m; ++b) {
    const int i = bonds.first(b), j = bonds.second(b);
    for (int d = 0; d < 3; ++d)
      if (!periodic[d] && bond_image(b, d) != 0)
        throw Error(fmt::format(
            "periodic model: bond {} (particles {} and {}) has image offset {} along lattice "
            "vector {}, which is not a periodic direction",
            b, i, j, bond_image(b, d), d + 1));
    const Eigen::Vector3d branch = this->branch(b);
    const double length = branch.norm();
    const Eigen::Vector3d normal = bonds.normal.row(b).matrix().transpose();
    const double tolerance = 1e-9 * length;
    const bool matches =
        length > 0 && std::abs(length - bonds.length(b)) <= tolerance &&
        (normal - branch / length).norm() <= 1e-9 &&
        std::abs(bonds.lever_first(b) + bonds.lever_second(b) - length) <= tolerance;
    if (!matches)
      throw Error(fmt::format(
          "periodic model: bond {} joins particle {} to the image ({}, {}, {}) of particle {}, "
          "{:.6g} m away, but its stored geometry (length {:.6g} m, levers {:.6g} + {:.6g} m, "
          "normal ({:.4g}, {:.4g}, {:.4g})) does not match that branch: wrong image offset or "
          "lattice vectors",
          b, i, bond_image(b, 0), bond_image(b, 1), bond_image(b, 2), j, length, bonds.length(b),
          bonds.lever_first(b), bonds.lever_second(b), normal.x(), normal.y(), normal.z()));
  }
}

namespace {

// The number of particles of the supercell; throws plydem::Error for bad inputs.
long supercell_size(const UnitCell& cell, const std::vector<FamilyStiffness>& families,
                    const std::array<int, 3>& repeats, const std::array<bool, 3>& periodic,
                    double density) {
  const int basis = static_cast<int>(cell.basis.size());
  require(basis > 0 && static_cast<int>(cell.radius.size()) == basis,
          "periodic supercell: the unit cell's basis and radius lists must be non-empty and of "
          "equal size");
  require(std::isfinite(cell.volume) && cell.volume > 0,
          "periodic supercell: the unit cell's volume must be positive");
  require(std::isfinite(density) && density > 0,
          fmt::format("periodic supercell: density must be positive, got {}", density));
  require(static_cast<int>(families.size()) >= cell.family_count,
          fmt::format("periodic supercell: the cell has {} bond families but {} stiffnesses were "
                      "given",
                      cell.family_count, families.size()));
  long count = basis;
  for (int d = 0; d < 3; ++d) {
    require(repeats[d] >= 1, "periodic supercell: repeats must be at least 1");
    require(periodic[d] || repeats[d] == 1,
            fmt::format("periodic supercell: {} repeats along lattice vector {}, which is not "
                        "periodic (use 1)",
                        repeats[d], d + 1));
    count *= repeats[d];
  }
  require(count < 100'000'000, fmt::format("periodic supercell: {} particles is too many", count));
  return count;
}

// The particle of basis site p in cell (c0, c1, c2) of the supercell.
struct SupercellIndex {
  std::array<int, 3> repeats;
  int basis;
  int operator()(const Eigen::Vector3i& c, int p) const {
    return ((c(2) * repeats[1] + c(1)) * repeats[0] + c(0)) * basis + p;
  }
};

void place_particles(const UnitCell& cell, const std::array<int, 3>& repeats, double density,
                     Particles& particles) {
  const int basis = static_cast<int>(cell.basis.size());
  const SupercellIndex index{repeats, basis};
  const double volume = cell.volume / basis;
  for (int c2 = 0; c2 < repeats[2]; ++c2)
    for (int c1 = 0; c1 < repeats[1]; ++c1)
      for (int c0 = 0; c0 < repeats[0]; ++c0)
        for (int p = 0; p < basis; ++p) {
          const Eigen::Vector3i c(c0, c1, c2);
          const int i = index(c, p);
          const Eigen::Vector3d x = cell.basis[p] + cell.lattice_vectors * c.cast<double>();
          particles.reference_position.row(i) = x.transpose().array();
          const double r = cell.radius[p];
          particles.radius(i) = r;
          particles.volume(i) = volume;
          particles.mass(i) = density * volume;
          particles.moment_of_inertia(i) = 0.4 * density * volume * r * r;  // solid sphere
        }
}

// Every unit-cell bond in every cell, wrapped into the supercell (out.model.bonds and
// out.bond_image sized already).
void bond_supercell(const UnitCell& cell, const std::vector<FamilyStiffness>& families,
                    const std::array<int, 3>& repeats, const std::array<bool, 3>& periodic,
                    PeriodicModel& out) {
  const int basis = static_cast<int>(cell.basis.size());
  const SupercellIndex index{repeats, basis};
  const int cell_bonds = static_cast<int>(cell.bonds.size());
  Bonds& bonds = out.model.bonds;
  const Eigen::Array3i size(repeats[0], repeats[1], repeats[2]);
  int b = 0;
  for (int c2 = 0; c2 < repeats[2]; ++c2)
    for (int c1 = 0; c1 < repeats[1]; ++c1)
      for (int c0 = 0; c0 < repeats[0]; ++c0)
        for (int k = 0; k < cell_bonds; ++k, ++b) {
          const UnitCell::Bond& bond = cell.bonds[k];
          if (!(bond.first >= 0 && bond.first < basis && bond.second >= 0 && bond.second < basis &&
                bond.family >= 0 && bond.family < cell.family_count))
            throw Error(fmt::format(
                "periodic supercell: unit-cell bond {} refers to a missing particle or family", k));
          const Eigen::Array3i from(c0, c1, c2);
          const Eigen::Array3i target = from + bond.image.array();
          // Wrap into the supercell; the quotient is the supercell image.
          Eigen::Array3i wrapped, image;
          for (int d = 0; d < 3; ++d) {
            image(d) = static_cast<int>(std::floor(static_cast<double>(target(d)) / size(d)));
            wrapped(d) = target(d) - image(d) * size(d);
            if (!periodic[d] && image(d) != 0)
              throw Error(fmt::format(
                  "periodic supercell: unit-cell bond {} reaches across lattice vector {}, which "
                  "is not periodic",
                  k, d + 1));
          }
          const int i = index(from.matrix(), bond.first);
          const int j = index(wrapped.matrix(), bond.second);
          bonds.first(b) = i;
          bonds.second(b) = j;
          bonds.family(b) = bond.family;
          out.bond_image.row(b) = image.transpose();
          const FamilyStiffness& stiffness = families[bond.family];
          bonds.normal_stiffness(b) = stiffness.normal;
          bonds.shear_stiffness(b) = stiffness.shear;
          bonds.bending_stiffness(b) = stiffness.bending;
          bonds.twisting_stiffness(b) = stiffness.twisting;
          const Eigen::Vector3d branch = cell.branch(k);
          const double length = branch.norm();
          if (!(length > 0))
            throw Error(fmt::format("periodic supercell: unit-cell bond {} has zero length", k));
          // The contact point midway in the gap, as set_bond_geometry places it.
          const double gap = length - cell.radius[bond.first] - cell.radius[bond.second];
          bonds.normal.row(b) = (branch / length).transpose().array();
          bonds.length(b) = length;
          bonds.lever_first(b) = cell.radius[bond.first] + 0.5 * gap;
          bonds.lever_second(b) = cell.radius[bond.second] + 0.5 * gap;
        }
}

// A Model holds one bond per pair of particles; with too few repeats a bond would join a
// particle to its own image or a pair twice.
void check_one_bond_per_pair(const Bonds& bonds, long count, const std::array<int, 3>& repeats,
                             int cell_bonds) {
  std::vector<std::vector<int>> partners(count);
  for (int k = 0; k < bonds.size(); ++k) {
    const int i = std::min(bonds.first(k), bonds.second(k));
    const int j = std::max(bonds.first(k), bonds.second(k));
    const bool repeated =
        i == j || std::find(partners[i].begin(), partners[i].end(), j) != partners[i].end();
    if (repeated)
      throw Error(fmt::format(
          "periodic supercell: with {} x {} x {} repeats, unit-cell bond {} joins particle {} "
          "to {} where another bond already does (or to its own image); use more repeats "
          "along the periodic directions",
          repeats[0], repeats[1], repeats[2], k % cell_bonds, bonds.first(k), bonds.second(k)));
    partners[i].push_back(j);
  }
}

}  // namespace

PeriodicModel periodic_supercell(const UnitCell& cell, const std::vector<FamilyStiffness>& families,
                                 const std::array<int, 3>& repeats,
                                 const std::array<bool, 3>& periodic, double density) {
  const long count = supercell_size(cell, families, repeats, periodic, density);
  const int basis = static_cast<int>(cell.basis.size());
  PeriodicModel out;
  out.periodic = periodic;
  out.lattice_vectors = cell.lattice_vectors;
  for (int d = 0; d < 3; ++d) out.lattice_vectors.col(d) *= repeats[d];
  out.volume = cell.volume * repeats[0] * repeats[1] * repeats[2];
  Model& model = out.model;
  const Eigen::Vector3d a1 = out.lattice_vectors.col(0), a2 = out.lattice_vectors.col(1);
  const double area = a1.cross(a2).norm();
  model.thickness = area > 0 ? out.volume / area : 0;
  model.description = fmt::format("periodic supercell of {} x {} x {} unit cells, {} particles",
                                  repeats[0], repeats[1], repeats[2], count);
  model.particles.resize(static_cast<int>(count));
  place_particles(cell, repeats, density, model.particles);
  const int cell_bonds = static_cast<int>(cell.bonds.size());
  model.bonds.resize(static_cast<int>(count / basis) * cell_bonds);
  out.bond_image.setZero(model.bonds.size(), 3);
  bond_supercell(cell, families, repeats, periodic, out);
  check_one_bond_per_pair(model.bonds, count, repeats, cell_bonds);
  out.check_consistency();
  return out;
}

namespace {

// The stiffness each dof's bonds could give it (particle order): translations sum k_n + k_s,
// rotations also the translational springs through their lever arms. Throws plydem::Error for a
// particle without any.
Eigen::VectorXd reference_stiffness(const Model& model) {
  const Particles& p = model.particles;
  const Bonds& bonds = model.bonds;
  const int n = p.size(), m = bonds.size();
  Eigen::VectorXd reference = Eigen::VectorXd::Zero(6 * n);  // particle order
  for (int b = 0; b < m; ++b) {
    const double k = bonds.normal_stiffness(b) + bonds.shear_stiffness(b);
    const double spin = bonds.bending_stiffness(b) + bonds.twisting_stiffness(b);
    const int ends[2] = {bonds.first(b), bonds.second(b)};
    const double lever[2] = {bonds.lever_first(b), bonds.lever_second(b)};
    for (int e = 0; e < 2; ++e) {
      reference.segment<3>(6 * ends[e]).array() += k;
      reference.segment<3>(6 * ends[e] + 3).array() += k * lever[e] * lever[e] + spin;
    }
  }
  for (int i = 0; i < n; ++i)
    if (!(reference(6 * i) > 0))
      throw Error(fmt::format(
          "periodic homogenization: {} has no bonds (or only bonds without stiffness): it floats "
          "freely in the period; remove it or bond it",
          describe_particle(p, i)));
  return reference;
}

// What the unit macro strains load: H_wE (6 columns, dofs in rank order) and H_EE.
struct StrainLoad {
  Eigen::MatrixXd coupling;
  Matrix6d h_ee = Matrix6d::Zero();
};

// The macro strain E moves the image of `second` by E (x_second + L image) and `first` by
// E x_first; the bond law sees only the difference E * branch (it is invariant under a common
// translation), so the unit strain s loads the bond like a displacement E_s * branch of its
// second particle: H_wE gets K(:, u_second) E_s branch, H_EE gets its energy.
StrainLoad strain_load(const PeriodicModel& periodic, const EliminationOrder& order) {
  const Bonds& bonds = periodic.model.bonds;
  const int n = periodic.model.particles.size(), m = bonds.size();
  StrainLoad out;
  Eigen::MatrixXd& coupling = out.coupling;
  Matrix6d& h_ee = out.h_ee;
  coupling = Eigen::MatrixXd::Zero(6 * n, 6);  // H_wE, rank order
  for (int b = 0; b < m; ++b) {
    const Matrix12d full = parallel_bond_stiffness(bond_parameters(bonds, b));
    const Matrix12d sym = 0.5 * (full + full.transpose());
    const Eigen::Vector3d branch = periodic.branch(b);
    Eigen::Matrix<double, 3, 6> strain_motion;
    for (int s = 0; s < 6; ++s) strain_motion.col(s) = voigt_unit_strain(s) * branch;
    const Eigen::Matrix<double, 12, 6> load = sym.middleCols<3>(6) * strain_motion;
    coupling.middleRows<6>(6 * order.rank[bonds.first(b)]) += load.topRows<6>();
    coupling.middleRows<6>(6 * order.rank[bonds.second(b)]) += load.bottomRows<6>();
    h_ee.noalias() += strain_motion.transpose() * load.middleRows<3>(6);
  }
  h_ee = 0.5 * (h_ee + h_ee.transpose()).eval();
  return out;
}

// The internal dofs in rank order: all but the translations of particle 0 (the fluctuation's
// rigid translations) and the dofs without stiffness of their own.
struct InternalDofs {
  std::vector<int> free_index;  // [rank-ordered dof] its index among the free ones, or -1
  std::vector<int> free_dof;    // [free index] the rank-ordered dof
  Eigen::VectorXd weight;       // reference^-1/2, rank order, for the residual test
  int unrestrained = 0;         // dofs without stiffness of their own
};

InternalDofs internal_dofs(const EliminationOrder& order, const BlockStiffness& k,
                           const Eigen::VectorXd& reference) {
  const int n = static_cast<int>(order.order.size());
  InternalDofs out;
  out.free_index.assign(6 * n, -1);
  out.weight.resize(6 * n);
  for (int r = 0; r < n; ++r) {
    const int i = order.order[r];
    for (int c = 0; c < 6; ++c) {
      const int d = 6 * r + c;
      out.weight(d) = 1 / std::sqrt(reference(6 * i + c));
      if (i == 0 && c < 3) continue;
      if (!(k.diagonal(r, c) > kUnrestrained * reference(6 * i + c))) {
        ++out.unrestrained;
        continue;
      }
      out.free_index[d] = static_cast<int>(out.free_dof.size());
      out.free_dof.push_back(d);
    }
  }
  return out;
}

// The scaled fluctuations y = A^-1 rhs, by the method the settings choose.
struct ScaledSolution {
  Eigen::MatrixXd y;
  int zero_pivots = 0;
  std::string method;
};

ScaledSolution solve_scaled(const SparseMatrix& a, const Eigen::MatrixXd& rhs, bool direct,
                            const StaticSettings& settings) {
  const int nf = static_cast<int>(a.cols());
  ScaledSolution out;
  if (nf == 0) {
    out.y.setZero(0, 6);
    out.method = "none (no internal dofs)";
  } else if (direct) {
    out.method = "supernodal Cholesky (AMD on particles)";
    SupernodalCholesky cholesky;
    cholesky.analyze(a);
    cholesky.factorize(a, settings.pivot_tolerance * std::max(nf, 1000));
    out.zero_pivots = static_cast<int>(cholesky.zero_pivots().size());
    out.y = rhs;
    cholesky.solve_in_place(out.y);
  } else if (settings.preconditioner == StaticPreconditioner::kIncompleteCholesky) {
    out.method = "ConjugateGradient + IncompleteCholesky";
    out.y = solve_cg<Eigen::IncompleteCholesky<double, Eigen::Lower, Eigen::AMDOrdering<int>>>(
        a, rhs, settings);
  } else {
    out.method = "ConjugateGradient + Jacobi";
    out.y = solve_cg<Eigen::DiagonalPreconditioner<double>>(a, rhs, settings);
  }
  return out;
}

// Every dof left out (the fixed translations, dofs without stiffness, zero pivots) must be in
// equilibrium too: a zero-energy mode that the strain loads would show here as a force.
void check_equilibrium(const BlockStiffness& k, const Eigen::MatrixXd& fluctuation,
                       const StrainLoad& strain, const InternalDofs& dofs, int zero_pivots) {
  const Eigen::MatrixXd residual =
      dofs.weight.asDiagonal() * (k.multiply(fluctuation) + strain.coupling);
  const double load = (dofs.weight.asDiagonal() * strain.coupling).norm();
  if (!(residual.norm() <= 1e-6 * load || load == 0)) {
    throw Error(fmt::format(
        "periodic homogenization: the bonds do not restrain some internal dofs that the macro "
        "strain loads (a mechanism: {} dofs without stiffness and {} zero pivots among {} "
        "internal dofs; unbalanced force {:.3g} of the load): stiffen the bonds or check the "
        "packing (or StaticSettings::pivot_tolerance is too large)",
        dofs.unrestrained, zero_pivots, dofs.free_dof.size(), residual.norm() / load));
  }
}

}  // namespace

PeriodicHomogenization homogenize_periodic(const PeriodicModel& periodic,
                                           const StaticSettings& settings,
                                           Eigen::MatrixXd* fluctuations) {
  const Stopwatch clock;
  validate(settings);
  periodic.check_consistency();
  const Model& model = periodic.model;
  const int n = model.particles.size();
  const Eigen::VectorXd reference = reference_stiffness(model);

  PeriodicHomogenization result;
  result.particles = n;
  result.bonds = model.bonds.size();
  const bool direct =
      settings.method == StaticMethod::kDirect ||
      (settings.method == StaticMethod::kAuto && 6 * n - 3 <= settings.direct_max_dofs);
  const EliminationOrder order =
      direct ? EliminationOrder::minimum_degree(model) : EliminationOrder::identity(n);
  const BlockStiffness k = block_stiffness(model, order);
  const StrainLoad strain = strain_load(periodic, order);
  result.affine = strain.h_ee / periodic.volume;

  // H_ww y = -H_wE on the internal dofs, Jacobi-scaled.
  const InternalDofs dofs = internal_dofs(order, k, reference);
  const int nf = static_cast<int>(dofs.free_dof.size());
  result.internal_dofs = nf;
  Eigen::VectorXd scale(nf);
  for (int f = 0; f < nf; ++f)
    scale(f) = 1 / std::sqrt(k.diagonal(dofs.free_dof[f] / 6, dofs.free_dof[f] % 6));
  const SparseMatrix a = compress_lower(k, dofs.free_index, nf, scale);
  Eigen::MatrixXd rhs(nf, 6);
  for (int f = 0; f < nf; ++f) rhs.row(f) = -scale(f) * strain.coupling.row(dofs.free_dof[f]);
  const ScaledSolution solution = solve_scaled(a, rhs, direct, settings);
  result.method = solution.method;
  result.zero_modes = dofs.unrestrained + solution.zero_pivots;
  require(solution.y.allFinite(),
          "periodic homogenization: the fluctuations are not finite (the stiffness is "
          "numerically singular)");
  Eigen::MatrixXd fluctuation = Eigen::MatrixXd::Zero(6 * n, 6);
  for (int f = 0; f < nf; ++f) fluctuation.row(dofs.free_dof[f]) = scale(f) * solution.y.row(f);
  check_equilibrium(k, fluctuation, strain, dofs, solution.zero_pivots);

  const Matrix6d condensed = strain.h_ee + strain.coupling.transpose() * fluctuation;
  if (fluctuations) {
    fluctuations->resize(6 * n, 6);
    for (int r = 0; r < n; ++r) {
      fluctuations->middleRows<6>(6 * order.order[r]) = fluctuation.middleRows<6>(6 * r);
    }
  }
  result.relaxed = 0.5 * (condensed + condensed.transpose()) / periodic.volume;
  result.seconds = clock.seconds();
  return result;
}

}  // namespace plydem
