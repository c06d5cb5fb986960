#pragma once
/// \file
/// In-plane shear that follows the ply's measured curve (issue 32; ../shared/DAMAGE_NOTES.md §1,
/// §9): plastic shear strain at the material point, up to the first crack.
///
/// Each site (particle) carries a plastic shear strain gamma_p in the axes of its ply. A bond
/// carries no force at the affine displacement of the mean of its two ends' plastic strains, its
/// free offset d_b = eps_p (x_j - x_i) (eps_p the in-plane tensor of gamma_p turned into the
/// coupon's axes): a uniform plastic strain is stress-free, the bonds' stiffnesses never change,
/// and the ply's elastic constants stay exact, tau12 = G12 (gamma12 - gamma_p) at a site
/// (contacts/site_failure.hpp site_ply_stresses). A site hardens on the Ramberg-Osgood law fitted
/// to the material's shear_curve (core/shear_curve.hpp), gamma12 = (tau12 + alpha tau12^eta) / G12,
/// with isotropic hardening: with kappa the plastic shear strain it has accumulated, its elastic
/// trial |tau| yields when the law at the strain |tau| / G12 + kappa lies below |tau|, and returns
/// onto it at that strain (tau = law(|tau| / G12 + kappa), kappa grows by the difference of the
/// strains), the plastic strain following the sign of tau. A site whose translation is prescribed
/// (a grip or a frame) stays elastic and is not judged.
///
/// The prescribed dofs move in load steps in proportion to their unit values (as the events
/// solver's load factor moves them). At each step the free dofs solve K u = f_p (the bonds' free
/// offsets' load, the stiffness factored once: StaticSystem) and the sites return onto the law,
/// again and again, until no site's plastic strain changes by more than `tolerance` (the initial-
/// stiffness method: each site returns with its own G12, which a uniform state makes exact in one
/// pass). The steps reach the estimate of failure (the elastic first failure's load factor times
/// G12 gamma_f / S12, gamma_f the law's strain at S12) in `steps` steps; the step at which a site
/// first fails by the lamina criterion (its stress, plastic shear taken off) is bisected to
/// `peak_tolerance`, and that site's crack opens (next_opening_site: every bond across its plane)
/// at the critical state. The run ends there: in a shear frame every gauge site carries the same
/// tau12, and the first crack is the peak.
///
/// The path (EventPoint, EventPoint::load_step for the steps): every converged step and the
/// critical state of the crack; reaction = minus the bonds' forces (free offsets included) on the
/// reaction dofs. The model ends at the critical state, the crack's bonds open.

#include <functional>
#include <span>
#include <vector>

#include "solvers/bond_events.hpp"
#include "solvers/static_solver.hpp"

namespace plydem {

struct PlasticShearSettings {
  /// The criterion, the material (with its shear_curve), the ply angles and the strength factors.
  MaterialPointFailure material_point;
  int steps = 100;  ///< load steps to the estimate of failure (>= 2)
  /// A step has converged when no site's plastic shear strain changes by more than this (> 0).
  double tolerance = 1e-9;
  int max_iterations = 2000;     ///< per load step, then refused (>= 1)
  double peak_tolerance = 1e-7;  ///< relative width of the bisection of the crack's load factor
  StaticSettings static_settings;
  /// Every point of the path, the model holding its state and each bond's free offset (the bonds'
  /// forces are those of u_j - u_i - offset: contacts/bond_kernel.hpp particle_stresses).
  std::function<void(const Model&, const EventPoint&, std::span<const Eigen::Vector3d>)> on_point;
  std::function<void(const EventProgress&)> on_progress;
  double progress_seconds = 2.0;
  /// Throws plydem::Error naming the first bad setting (a material without a shear_curve too).
  void validate() const;
};

struct PlasticShearResult {
  /// As run_events reports it: path, breaks, peak, stop ("failed" at the crack, or "no site
  /// failed"), solves (of the free offsets' load), factorizations, and the crack's energy and
  /// area (crack_energy, crack_area, crack_fracture_energy).
  EventsResult events;
  std::vector<double> plastic_shear;  ///< each site's gamma_p at the end (ply axes)
  double plastic_work = 0;            ///< sum of V tau12 d(gamma_p) over the sites and steps [J]
  long iterations = 0;                ///< site returns over all steps
};

/// Runs `model` (intact bonds) in plastic shear to its first crack under the prescribed dofs of
/// `unit` (their values at load factor 1). Throws plydem::Error for bad settings, constraints the
/// static solver refuses, a step that does not converge in max_iterations (naming the step and
/// the largest change), or a coupon whose sites never fail.
PlasticShearResult run_plastic_shear(Model& model, const DofConstraints& unit,
                                     const DofFlags& reaction_dofs,
                                     const PlasticShearSettings& settings);

}  // namespace plydem
