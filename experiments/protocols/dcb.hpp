#pragma once
/// \file
/// The double cantilever beam (DCB, mode I delamination; ASTM D5528) of a unidirectional laminate,
/// opened at its loading points until the delamination grows (`plydem run experiments/dcb.toml`).
///
/// The model is a side view: the particle layer is the beam's x-thickness plane (x along the
/// fibres, y through the laminate's thickness) and the specimen's width b is the layer's
/// out-of-plane thickness, so the beam is in plane stress with the ply's E1 along x, E3 = E2
/// across, and G13 = G12 (a transversely isotropic ply). The two arms, each half the laminate
/// (h = half the plies times the ply thickness), are built by the strategy as two plies of the
/// ply's calibration (every bond of them unbreakable), one above the other, and joined on the
/// mid-plane by interface bonds (BondKind::kInterface), one per particle column facing the
/// other arm's, standing for its column's share of the interface, b L / n. Over the starter
/// delamination (the first `crack` of the length from the load line) there is none.
///
/// Interface bonds are the laminate's (strategies/strength_calibration.hpp
/// set_interface_bond_strength): a normal and a shear spring per unit area, K_n and K_s, that break
/// at the interface strengths and soften linearly so that each dissipates GIc (mode I) over its
/// share of area. By default K_n = E2 / g and K_s = G12 / g, g the gap between the two facing rows'
/// centres: the intact interface is then as stiff across as the arms' own material over one row
/// spacing, so the uncracked beam is seamless.
///
/// Loading (sequentially linear analysis, solvers/bond_events.hpp): the particles of each arm's
/// end column (at the load line, x = the first column) are moved apart along y, the upper arm by
/// +delta/2 and the lower by -delta/2 (a loading block: the end section translates and may
/// rotate); every particle is held out of plane (u_z = theta_x = theta_y = 0: the plane problem of
/// the side view), and the rigid modes left (x translation, rotation about the load line) are
/// pinned. The load P is the sum of the upper end column's y reactions; the opening is delta.
/// Each critical state is one point of the load-opening curve. The run stops when the crack tip
/// reaches `max_crack` from the load line, or when the events solver stops (event limit, failure).
///
/// Crack length: from the load line to the first interface bond (in x) that has not broken, less
/// half its column spacing (the start of its share of the interface): a bond that has softened
/// but still holds is in the cohesive zone ahead of the tip.
///
/// References (computed here, DAMAGE_NOTES §5; ASTM D5528): simple beam theory, C = 8 a^3 /
/// (E1 b h^3) and propagation at P = (b h / a) sqrt(GIc E1 h / 12); corrected beam theory, the same
/// with a + chi h for the root rotation and the elastic foundation of the uncracked part,
/// chi = sqrt(E11 / (11 G13)) (3 - 2 (Gamma / (1 + Gamma))^2), Gamma = 1.18 sqrt(E11 E22) / G13
/// (Hashemi, Kinloch & Williams, Proc. R. Soc. Lond. A 427 (1990) 173). Both are linear: the
/// model is too (small displacements; large openings of long thin arms stiffen the real test).

#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "core/material.hpp"
#include "core/model.hpp"
#include "solvers/bond_events.hpp"
#include "solvers/linear_solver.hpp"
#include "strategies/laminate.hpp"
#include "strategies/strategy.hpp"
#include "strategies/strength_calibration.hpp"

namespace plydem {

struct DcbSettings {
  std::string strategy = "square";
  std::vector<std::pair<std::string, double>> strategy_options;
  Material material = load_material("eglass-my750");  ///< the paper's ply
  /// Ply angles, bottom to top [rad]: every ply at 0 (a unidirectional laminate), an even number
  /// of them; the delamination is on the mid-plane.
  std::vector<double> layup = std::vector<double>(16, 0.0);
  double ply_thickness = 0.2e-3;      ///< [m]
  double length = 80e-3;              ///< L, along the fibres [m]
  double width = 20e-3;               ///< b [m]
  double crack = 30e-3;               ///< a0, the starter delamination from the load line [m]
  double particle_diameter = 0.2e-3;  ///< [m]
  double max_crack = 50e-3;           ///< stop when the crack reaches this length [m]
  /// Normal and shear stiffness of the interface bonds per unit area [N/m^3]; 0 = E2 / g and
  /// G12 / g (see the file comment). lateral_radius is not used.
  InterfaceStiffness interface;
  /// Interface strengths and fracture energies: normal and GIc are required; shear 0 = the
  /// material's S12 (or, without one, the normal strength).
  InterfaceStrength interface_strength;
  /// The events solver's settings (on_event, on_progress and stop_after are the test's own).
  /// Teeth of softening bonds keep 0.8 of their stiffness, as in the strength test.
  EventSettings events = [] {
    EventSettings e;
    e.tooth_stiffness_ratio = 0.8;
    return e;
  }();
  LinearSolverKind linear_solver = LinearSolverKind::kAuto;
  /// Keep copies of the model at selected critical states (DcbResult::snapshots), for VTU series.
  bool record_snapshots = false;

  /// interface_strength with the shear strength's default filled in.
  InterfaceStrength resolved_interface_strength() const;
  /// Half the laminate: h [m].
  double arm_thickness() const;
  /// Throws plydem::Error naming the first bad setting: an empty layup, an odd number of plies, a
  /// ply not at 0 deg, a non-positive or non-finite size, a crack not shorter than max_crack or
  /// max_crack not shorter than the length, an arm that is not a whole number (at least two) of
  /// particle diameters thick, a missing interface strength or GIc, bad events settings.
  void validate() const;
};

/// Beam theory of a DCB at one crack length.
struct DcbBeamTheory {
  double crack = 0;       ///< a [m]
  double chi = 0;         ///< corrected beam theory's crack length correction / h
  double compliance = 0;  ///< simple beam theory, delta / P [m/N]
  double corrected_compliance = 0;
  double propagation_load = 0;  ///< P at which G = GIc [N]
  double corrected_propagation_load = 0;
};

/// Simple and corrected beam theory of a DCB with arms of thickness `h`, width `b`, crack `a`
/// (from the load line) of a ply with E1 (bending), E2 and G13 = G12, and fracture energy `GIc`.
DcbBeamTheory dcb_beam_theory(const Material& material, double b, double h, double a, double GIc);

/// A copy of the model at one critical state (before its bond fails), or at the end.
struct DcbSnapshot {
  long event = 0;
  std::string label;
  std::shared_ptr<const Model> model;
};

struct DcbResult {
  std::string strategy;
  Material material;
  std::vector<double> layup;
  double width = 0, arm_thickness = 0, length = 0;  ///< b, h, L [m]
  double initial_crack = 0;  ///< a0 as built (to the first bonded share of interface) [m]
  double particle_diameter = 0;
  InterfaceStiffness interface;          ///< as used (defaults resolved)
  InterfaceStrength interface_strength;  ///< as used
  int particles = 0, bonds = 0, interface_bonds = 0;
  double interface_ductility = 1;  ///< kappa_u of the interface bonds

  /// The load-opening curve: the unloaded origin, then one point per critical state, with the
  /// crack length at that state.
  std::vector<double> opening, load, crack;
  double initial_compliance = 0;  ///< opening / load of the intact interface [m/N]
  double propagation_load = 0;    ///< the peak load [N]
  double opening_at_peak = 0;     ///< [m]
  double crack_at_peak = 0;       ///< [m]
  /// The cohesive zone at the peak: the interface bonds ahead of the tip that have softened but
  /// still hold, times their column spacing [m].
  double cohesive_zone_at_peak = 0;
  double final_crack = 0;  ///< [m]
  /// Energy released by the interface bonds (EventsResult::dissipated_energy) over the crack area
  /// grown, b (final - initial crack) [J/m^2]: GIc when the cohesive zone at the end holds as
  /// much energy as the one at the start.
  double released_per_area = 0;
  DcbBeamTheory theory;  ///< at the initial crack

  std::vector<BondBreak> breaks;  ///< the interface bonds broken, in order (EventsResult::breaks)
  long events = 0;
  std::string stop;
  int factorizations = 0;
  long solves = 0;
  double dissipated_energy = 0;  ///< [J]
  double wall_seconds = 0;
  std::shared_ptr<const Model> model;  ///< the final state
  std::vector<DcbSnapshot> snapshots;  ///< with DcbSettings::record_snapshots
};

/// Builds and opens the DCB of `settings` (validated first). Throws plydem::Error for bad
/// settings, a strategy that is not registered or whose arms' rows do not face each other
/// column by column, or a run in which no interface bond failed.
DcbResult run_dcb(const DcbSettings& settings,
                  const std::function<void(const EventProgress&)>& progress = {});

/// The DEM curve reduced as ASTM D5528's modified beam theory reduces a test: over the critical
/// states after the peak whose crack has grown, the least-squares line C^(1/3) = m (a + Delta)
/// (C = opening / load) gives the crack length correction Delta and the flexural modulus
/// 8 / (b h^3 m^3), and each state G_I = 3 P delta / (2 b (a + |Delta|)), averaged.
struct DcbReduction {
  int points = 0;               ///< propagation states used (fewer than 3: nothing reduced)
  double delta = 0;             ///< [m]
  double flexural_modulus = 0;  ///< [Pa]
  double GIc = 0;               ///< mean G_I over the points [J/m^2]
};
DcbReduction reduce_dcb_curve(const DcbResult& result);

}  // namespace plydem
