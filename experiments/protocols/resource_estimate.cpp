#include "experiments/protocols/resource_estimate.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "core/error.hpp"
#include "core/machine_memory.hpp"
#include "core/model.hpp"
#include "solvers/static_solver.hpp"

namespace plydem {

namespace {

template <class Rows>
double row_bytes() {
  double bytes = 0;
  Rows::for_each_field([&](FieldInfo, auto member) {
    using Array = FieldType<decltype(member)>;
    bytes += static_cast<double>(sizeof(typename Array::Scalar)) *
             (Array::ColsAtCompileTime > 0 ? Array::ColsAtCompileTime : 1);
  });
  return bytes;
}

std::string bytes_text(double bytes) {
  if (!std::isfinite(bytes)) return "more than can be counted";
  if (bytes >= 1e12) return fmt::format("{:.3g} TB", bytes * 1e-12);
  if (bytes >= 1e9) return fmt::format("{:.3g} GB", bytes * 1e-9);
  return fmt::format("{:.3g} MB", bytes * 1e-6);
}

}  // namespace

double particle_row_bytes() {
  return row_bytes<Particles>();
}
double bond_row_bytes() {
  return row_bytes<Bonds>();
}

ResourceEstimate estimate_resources(const Strategy& strategy, const CouponSpec& coupon,
                                    const std::vector<double>& layup,
                                    const InterfaceStiffness& interface, SolverUse solver,
                                    int models_held, int update_rank,
                                    LinearSolverKind linear_solver) {
  ResourceEstimate e;
  const std::optional<PackingEstimate> ply = strategy.estimate_packing(coupon);
  if (!ply) return e;
  e.known = true;
  e.plies = layup.empty() ? 1 : static_cast<int>(layup.size());
  e.particles = ply->particles * e.plies;
  // Interface bonds: each top-surface particle of a ply meets the next ply's bottom surface
  // within the lateral radius (strategies/laminate.hpp), on average its density times that disc.
  const double disc =
      std::numbers::pi * std::pow(interface.lateral_radius * coupon.particle_diameter, 2);
  e.interface_bonds =
      (e.plies - 1) * ply->top_surface_particles * ply->bottom_surface_density * disc;
  e.bonds = ply->bonds * e.plies + e.interface_bonds;
  e.models_held = std::max(1, models_held);

  const double model = e.particles * particle_row_bytes() + e.bonds * bond_row_bytes();
  // The build's packing: positions, the bonded pairs and their families.
  const double build = e.particles * 3 * sizeof(double) + e.bonds * 3 * sizeof(int);
  e.model_bytes = e.models_held * model + build;

  const double unknowns = double{kDofsPerParticle} * e.particles;
  // The assembly's 6 x 6 blocks (one per particle and per bond, solvers/stiffness_assembly.hpp)
  // and their lower triangle in compressed columns (value and row index).
  const double blocks = (e.particles + e.bonds) * (36 * sizeof(double) + sizeof(int));
  const double lower_entries = 21 * e.particles + 36 * e.bonds;
  e.matrix_bytes = blocks + lower_entries * (sizeof(double) + sizeof(int));
  const double layers = static_cast<double>(ply->layers) * e.plies;
  const double columns = std::max(2.0, e.particles / layers);
  const double coordination = e.particles > 0 ? 2 * e.bonds / e.particles : 0.0;
  e.factor_entries =
      std::min(kFactorFillCoefficient * unknowns * coordination * layers * std::log2(columns),
               0.5 * unknowns * (unknowns + 1));
  // The factor and the multifrontal method's fronts and update stack beside it.
  const double factor = direct_factor_bytes(e.factor_entries);
  // PETSc, where a static solve may use it: kPetsc always, kAuto where the factor is larger.
  const bool petsc =
      petsc_available() && solver != SolverUse::kEvents &&
      (linear_solver == LinearSolverKind::kAuto || linear_solver == LinearSolverKind::kPetsc);
  if (petsc) {
    const double aij_entries = 36 * e.particles + 72 * e.bonds;
    e.petsc_bytes = kPetscMemoryFactor * aij_entries * (sizeof(double) + sizeof(int));
  }
  const bool petsc_solves =
      petsc && (linear_solver == LinearSolverKind::kPetsc || e.petsc_bytes < factor);
  const double static_solver = e.matrix_bytes + (petsc_solves ? e.petsc_bytes : factor);
  const std::string static_text =
      petsc_solves
          ? fmt::format("stiffness matrix {}, PETSc's matrix and AMG hierarchy {}{}",
                        bytes_text(e.matrix_bytes), bytes_text(e.petsc_bytes),
                        linear_solver == LinearSolverKind::kAuto
                            ? fmt::format(" (a sparse Cholesky factor would take {}, bound)",
                                          bytes_text(factor))
                            : std::string())
          : fmt::format(
                "stiffness matrix {}, sparse Cholesky factor {} (bound, workspace included)",
                bytes_text(e.matrix_bytes), bytes_text(factor));
  switch (solver) {
    case SolverUse::kStatic:
      e.solver_bytes = static_solver;
      e.solver = static_text;
      break;
    case SolverUse::kExplicit:
      // The integrator's copy, and the static solves of the specimen stiffness after it.
      e.solver_bytes = std::max(model, static_solver);
      e.solver = fmt::format("explicit integrator {}, or {}", bytes_text(model), static_text);
      break;
    case SolverUse::kEvents: {
      const double woodbury = 2 * unknowns * std::max(0, update_rank) * sizeof(double);
      e.solver_bytes = e.matrix_bytes + factor + woodbury;
      e.solver = fmt::format("stiffness matrix {}, sparse Cholesky factor {} (bound), updates {}",
                             bytes_text(e.matrix_bytes), bytes_text(factor), bytes_text(woodbury));
      break;
    }
  }
  e.total_bytes = e.model_bytes + e.solver_bytes;
  return e;
}

std::string format_estimate(const ResourceEstimate& e) {
  if (!e.known) return "no estimate (the strategy has no unit cell to count from)";
  return fmt::format(
      "{:.3g} particles and {:.3g} bonds{}, about {} of memory (models {}{}; {})", e.particles,
      e.bonds,
      e.interface_bonds > 0 ? fmt::format(" ({:.3g} between {} plies)", e.interface_bonds, e.plies)
                            : std::string(),
      bytes_text(e.total_bytes), bytes_text(e.model_bytes),
      e.models_held > 1 ? fmt::format(", {} held at once", e.models_held) : "", e.solver);
}

void check_resources(const ResourceEstimate& e, bool force, const std::string& force_hint) {
  if (!e.known) return;
  constexpr double kMaxIndex = std::numeric_limits<int>::max();
  if (!(e.particles <= kMaxIndex && e.bonds <= kMaxIndex)) {
    throw Error(fmt::format(
        "the coupon would need {}: more particles or bonds than plydem's 32-bit indices hold "
        "({}); make it smaller or the particles larger",
        format_estimate(e), std::numeric_limits<int>::max()));
  }
  const MachineMemory machine = machine_memory();
  if (e.total_bytes <= machine.available) {
    if (e.total_bytes > 1e9) spdlog::info("estimate: {}", format_estimate(e));
    return;
  }
  const std::string message = fmt::format(
      "the coupon would need {}, but this machine has {} available ({}, of {}); make the coupon "
      "smaller or the particles larger, or pass {} to try anyway",
      format_estimate(e), bytes_text(machine.available), machine.source, bytes_text(machine.total),
      force_hint);
  if (!force) throw Error(message);
  spdlog::warn("{} (forced)", message.substr(0, message.find("; make")));
}

}  // namespace plydem
