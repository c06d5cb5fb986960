#include "experiments/protocols/stiffness.hpp"

#include <fmt/format.h>

#include <chrono>

#include "contacts/bond_kernel.hpp"
#include "core/error.hpp"
#include "core/measurements.hpp"
#include "solvers/static_solver.hpp"

namespace plydem {
namespace {

// The window's mean virial stress (xx, yy, xy) at the solved state (see the header).
Eigen::Vector3d window_stress(const Model& solved, const std::vector<char>& inside,
                              double window_volume) {
  const Particles& p = solved.particles;
  const Bonds& bonds = solved.bonds;
  std::vector<int> both, one;
  for (int b = 0; b < bonds.size(); ++b) {
    const int ends = inside[bonds.first(b)] + inside[bonds.second(b)];
    if (ends == 2) both.push_back(b);
    if (ends == 1) one.push_back(b);
  }
  Eigen::Matrix2d stress = Eigen::Matrix2d::Zero();
  for (const auto& [rows, weight] : {std::pair{&both, 1.0}, std::pair{&one, 0.5}}) {
    Particles state = p;
    compute_bond_forces(state, bonds.select(*rows));
    for (int i = 0; i < p.size(); ++i) {
      const Eigen::Vector2d f(state.force(i, 0), state.force(i, 1));
      const Eigen::Vector2d x = p.reference_position.row(i).head<2>().matrix().transpose();
      stress -= weight * f * x.transpose();
    }
  }
  stress /= window_volume;
  return {stress(0, 0), stress(1, 1), 0.5 * (stress(0, 1) + stress(1, 0))};
}

// The particles of the interior window `inset` inside the specimen's extent [low, high] (none
// where that leaves less than three particle diameters across).
struct InteriorWindow {
  std::vector<char> inside;  // per particle
  std::vector<int> particles;
  double volume = 0;
};

InteriorWindow interior_window(const Particles& p, const Eigen::Vector3d& low,
                               const Eigen::Vector3d& high, double inset) {
  const bool has_window = high.x() - low.x() - 2 * inset >= 6 * p.radius.maxCoeff() &&
                          high.y() - low.y() - 2 * inset >= 6 * p.radius.maxCoeff();
  InteriorWindow w;
  w.inside.assign(p.size(), 0);
  for (int i = 0; has_window && i < p.size(); ++i) {
    const double x = p.reference_position(i, 0), y = p.reference_position(i, 1);
    if (x >= low.x() + inset && x <= high.x() - inset && y >= low.y() + inset &&
        y <= high.y() - inset) {
      w.inside[i] = 1;
      w.particles.push_back(i);
      w.volume += p.volume(i);
    }
  }
  return w;
}

}  // namespace

SpecimenStiffness measure_specimen_stiffness(const Model& model, double band,
                                             LinearSolverKind linear_solver, double interior_margin,
                                             bool force) {
  const auto start = std::chrono::steady_clock::now();
  const Particles& p = model.particles;
  require(p.size() >= 4, "the specimen stiffness needs at least four particles");
  require(std::isfinite(band) && band >= 0, "the boundary frame width must be >= 0");
  if (band == 0) band = 4.0 * p.radius.maxCoeff();
  const Eigen::Vector3d low = p.reference_position.colwise().minCoeff().transpose();
  const Eigen::Vector3d high = p.reference_position.colwise().maxCoeff().transpose();
  require(high.x() - low.x() > 2 * band && high.y() - low.y() > 2 * band,
          fmt::format("a {:.4g} mm x {:.4g} mm specimen has no interior inside a {:.4g} mm "
                      "boundary frame",
                      (high.x() - low.x()) * 1e3, (high.y() - low.y()) * 1e3, band * 1e3));
  std::vector<int> frame;
  for (int i = 0; i < p.size(); ++i) {
    const double x = p.reference_position(i, 0), y = p.reference_position(i, 1);
    if (x <= low.x() + band || x >= high.x() - band || y <= low.y() + band ||
        y >= high.y() - band) {
      frame.push_back(i);
    }
  }
  // The interior window (see the header): `interior_margin` inside the frame.
  require(std::isfinite(interior_margin) && interior_margin >= 0,
          "the interior window's margin must be >= 0");
  if (interior_margin == 0) interior_margin = band;
  const InteriorWindow interior = interior_window(p, low, high, band + interior_margin);
  const std::vector<char>& inside = interior.inside;
  const std::vector<int>& window = interior.particles;
  const double window_volume = interior.volume;
  Eigen::Matrix3d window_stresses, window_strains;

  SpecimenStiffness result;
  result.volume = p.volume.sum();
  result.frame_particles = static_cast<int>(frame.size());
  require(result.volume > 0, "the specimen's particles have no volume");
  // Strains about the centre, so that the reactions' moments are taken about it.
  const Eigen::Vector3d centre = 0.5 * (low + high);

  // The three strain cases prescribe the same dofs (the frame's ux and uy) and differ only in
  // their values: one factorization serves all three solves.
  DofConstraints constraints(p.size());
  for (int i : frame) {
    constraints.fix(i, Dof::kUx);
    constraints.fix(i, Dof::kUy);
  }
  StaticSettings settings;
  settings.pin_rigid_modes = true;  // out-of-plane motion of a layer is not restrained by the frame
  settings.linear_solver = linear_solver;
  settings.force = force;
  settings.expected_solves = 3;  // the three strain cases
  const StaticSystem system(model, constraints, settings);

  for (int column = 0; column < 3; ++column) {
    Eigen::Matrix2d strain = Eigen::Matrix2d::Zero();  // engineering shear: off-diagonals 1/2
    if (column < 2) {
      strain(column, column) = 1;
    } else {
      strain(0, 1) = strain(1, 0) = 0.5;
    }
    strain *= 1e-3;  // the model is linear; a small strain keeps the numbers physical
    DofArray values = DofArray::Zero(p.size(), kDofsPerParticle);
    Model solved = model;
    // The affine field everywhere: the frame's values, and the first iterate of an iterative
    // solver inside (kPetsc: fewer iterations; a direct factor ignores it).
    for (int i = 0; i < p.size(); ++i) {
      const Eigen::Vector2d x =
          (p.reference_position.row(i).matrix().transpose() - centre).head<2>();
      const Eigen::Vector2d u = strain * x;
      solved.particles.displacement.row(i) << u.x(), u.y(), 0;
      solved.particles.rotation.row(i).setZero();
    }
    for (int i : frame) {
      values(i, static_cast<int>(Dof::kUx)) = solved.particles.displacement(i, 0);
      values(i, static_cast<int>(Dof::kUy)) = solved.particles.displacement(i, 1);
    }
    const StaticResult r = system.solve(solved, values);
    result.linear_solver = r.method_name;
    result.linear_iterations += r.iterations;
    result.linear_solver_choice = r.linear_solver_choice;
    Eigen::Matrix2d stress = Eigen::Matrix2d::Zero();
    for (int i : frame) {
      const Eigen::Vector2d x =
          (p.reference_position.row(i).matrix().transpose() - centre).head<2>();
      const Eigen::Vector2d force(r.reaction(i, 0), r.reaction(i, 1));
      stress += force * x.transpose();
    }
    stress /= result.volume;
    // Symmetric part: the frame's reactions carry no net moment when the particles turn freely.
    const double sxy = 0.5 * (stress(0, 1) + stress(1, 0));
    result.stiffness.col(column) = Eigen::Vector3d(stress(0, 0), stress(1, 1), sxy) / 1e-3;
    if (window.size() >= 3) {
      const GaugeStrain e = fit_gauge_strain(solved.particles, window);
      window_strains.col(column) = Eigen::Vector3d(e.exx, e.eyy, e.gamma_xy);
      window_stresses.col(column) = window_stress(solved, inside, window_volume);
    }
  }
  if (window.size() >= 3) {
    const Eigen::Matrix3d c = window_stresses * window_strains.inverse();
    result.interior_stiffness = 0.5 * (c + c.transpose());
    result.interior_constants = in_plane_constants(result.interior_stiffness);
    result.interior_particles = static_cast<int>(window.size());
    result.interior_margin = interior_margin;
  }
  result.stiffness = 0.5 * (result.stiffness + result.stiffness.transpose()).eval();
  result.constants = in_plane_constants(result.stiffness);
  result.factorizations = system.factorizations();
  result.solves = system.solves();
  result.wall_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace plydem
