#include "strategies/cure_stress.hpp"

#include <fmt/format.h>

#include <cmath>

#include "contacts/bond_kernel.hpp"
#include "core/error.hpp"
#include "solvers/static_solver.hpp"

namespace plydem {

Eigen::Matrix3d ply_thermal_strain(const Ply& ply, double delta_T) {
  require(std::isfinite(delta_T),
          fmt::format("cure stress: the temperature change must be finite, got {} K", delta_T));
  require(ply.material.thermal_expansion_given || delta_T == 0,
          fmt::format("cure stress: material '{}' has no thermal expansion (alpha1, alpha2 in its "
                      "material file), which a temperature change of {} K needs",
                      ply.material.name, delta_T));
  const Eigen::Matrix3d rotation = Eigen::AngleAxisd(ply.angle, Eigen::Vector3d::UnitZ()).matrix();
  const Eigen::Vector3d alpha(ply.material.alpha1, ply.material.alpha2, ply.material.alpha2);
  return rotation * (alpha * delta_T).asDiagonal() * rotation.transpose();
}

void set_cure_offsets(Model& model, const std::vector<Ply>& plies, double delta_T) {
  const Particles& p = model.particles;
  Bonds& bonds = model.bonds;
  std::vector<Eigen::Matrix3d> strain;
  for (const Ply& ply : plies) strain.push_back(ply_thermal_strain(ply, delta_T));
  for (int i = 0; i < p.size(); ++i)
    require(p.ply(i) >= 0 && p.ply(i) < static_cast<int>(plies.size()),
            fmt::format("cure stress: particle {} lies in ply {}, but {} plies were given", i,
                        p.ply(i), plies.size()));
  bonds.free_offset.resize(bonds.size(), 3);
  for (int b = 0; b < bonds.size(); ++b) {
    const Eigen::Matrix3d mean =
        0.5 * (strain[p.ply(bonds.first(b))] + strain[p.ply(bonds.second(b))]);
    const Eigen::Vector3d branch = bonds.length(b) * bonds.normal.row(b).transpose().matrix();
    bonds.free_offset.row(b) = (mean * branch).transpose().array();
  }
}

std::vector<Eigen::Vector3d> clt_thermal_ply_stresses(const std::vector<Ply>& plies,
                                                      double delta_T) {
  const Eigen::Matrix3d a = laminate_extensional_stiffness(plies);
  std::vector<Eigen::Matrix3d> qbar;
  std::vector<Eigen::Vector3d> eps_th;
  Eigen::Vector3d n_t = Eigen::Vector3d::Zero();
  for (const Ply& ply : plies) {
    qbar.push_back(rotate_reduced_stiffness(reduced_stiffness(ply.material), ply.angle));
    const Eigen::Matrix3d e = ply_thermal_strain(ply, delta_T);
    eps_th.emplace_back(e(0, 0), e(1, 1), 2 * e(0, 1));  // engineering shear strain
    n_t += qbar.back() * eps_th.back() * ply.thickness;
  }
  const Eigen::Vector3d eps0 = a.ldlt().solve(n_t);
  std::vector<Eigen::Vector3d> stresses;
  for (std::size_t k = 0; k < plies.size(); ++k) stresses.push_back(qbar[k] * (eps0 - eps_th[k]));
  return stresses;
}

namespace {

// The free laminate's cure into `model` (solve_cure, cured_preload).
void solve_free_cure(Model& model, const std::vector<Ply>& plies, double delta_T) {
  set_cure_offsets(model, plies, delta_T);
  StaticSettings settings;
  settings.pin_rigid_modes = true;
  solve_static(model, DofConstraints(model.particles.size()), settings);
}

}  // namespace

DofArray cured_preload(Model& model, const std::vector<Ply>& plies, double delta_T,
                       const DofFlags& held) {
  const Particles& p = model.particles;
  require(held.rows() == p.size() && held.cols() == kDofsPerParticle,
          fmt::format("cured preload: {} x {} held flags for {} particles", held.rows(),
                      held.cols(), p.size()));
  solve_free_cure(model, plies, delta_T);
  DofArray preload = DofArray::Zero(p.size(), kDofsPerParticle);
  for (int i = 0; i < p.size(); ++i)
    for (int c = 0; c < 3; ++c) {
      if (held(i, c)) preload(i, c) = p.displacement(i, c);
      if (held(i, 3 + c)) preload(i, 3 + c) = p.rotation(i, c);
    }
  return preload;
}

std::vector<Eigen::Vector3d> solve_cure(Model& model, const std::vector<Ply>& plies, double delta_T,
                                        double half) {
  solve_free_cure(model, plies, delta_T);
  const Particles& p = model.particles;
  const std::vector<Eigen::Matrix3d> stress = particle_stresses(p, model.bonds);
  const Eigen::Vector3d low = p.reference_position.colwise().minCoeff().transpose().matrix();
  const Eigen::Vector3d high = p.reference_position.colwise().maxCoeff().transpose().matrix();
  const Eigen::Vector3d centre = 0.5 * (low + high);
  std::vector<Eigen::Vector3d> sum(plies.size(), Eigen::Vector3d::Zero());
  std::vector<double> volume(plies.size(), 0.0);
  for (int i = 0; i < p.size(); ++i) {
    if (std::abs(p.reference_position(i, 0) - centre.x()) > half ||
        std::abs(p.reference_position(i, 1) - centre.y()) > half)
      continue;
    const Eigen::Matrix3d& s = stress[static_cast<std::size_t>(i)];
    const auto k = static_cast<std::size_t>(p.ply(i));
    sum[k] += p.volume(i) * Eigen::Vector3d(s(0, 0), s(1, 1), s(0, 1));
    volume[k] += p.volume(i);
  }
  for (std::size_t k = 0; k < plies.size(); ++k) {
    require(volume[k] > 0, fmt::format("cure stress: ply {} has no particle within {} mm of the "
                                       "coupon's centre",
                                       k, half * 1e3));
    sum[k] /= volume[k];
  }
  return sum;
}

}  // namespace plydem
