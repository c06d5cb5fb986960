#pragma once
/// \file
/// The paper's Tables 2-5 as experiment kinds (experiments/runner/experiment.hpp), run by
/// `plydem run experiments/table2.toml` ... `table5.toml`:
///
///   - `lamina-strategies` (Table 2): one lamina (the 0 deg E-glass/MY750 ply) with every strategy
///     the config lists. Per strategy: E1, E2, nu12, nu21 (and G12) from the static tension test;
///     the wall time of the paper's fixed-cycle explicit run (200,000 cycles, one coupon pulled
///     along x; with --quick fewer cycles, extrapolated and labelled so); the time the staged
///     explicit solver takes to reach its quasi-static tolerance; the static test's time; particle
///     and bond counts. A strategy that is not registered, or refuses the ply, gets a row saying
///     so instead of failing the run.
///   - `lamina-angles` (Table 3): laminae at the config's angles with each listed strategy: Ex,
///     Ey, nu_xy, nu_yx, Gxy and the shear coupling gamma_xy/eps_x, beside correct CLT (Q-bar,
///     computed), CalculiX (experiments/fem/calculix.hpp) and the paper's theory, FEM and DEM rows.
///   - `laminate` (Tables 4 and 5): a layup from the config (hex2d plies joined by interface
///     bonds, strategies/laminate.hpp) beside CLT of its A matrix, CalculiX and the paper's rows.
///
/// Every table gives relative errors against correct CLT. The paper's numbers are data: they come
/// from the config (which cites the paper's table), never from code. A paper theory value more
/// than 1% from correct CLT is flagged (ERRATA §1 explains why those rows are wrong).
/// All tension tests use free grips (uniaxial stress: the ends contract and shear freely); the
/// report says so. Each DEM model is written as VTU (particles and bonds, solved state) and drawn
/// as bonds coloured by normal stiffness; each kind draws stress-strain curves.

#include "experiments/runner/experiment.hpp"

namespace plydem {

/// Registers `lamina-strategies`, `lamina-angles` and `laminate` (CMake list PLYDEM_EXPERIMENTS
/// entry `paper_tables`).
void register_paper_tables_experiment(ExperimentRegistry& registry);

}  // namespace plydem
