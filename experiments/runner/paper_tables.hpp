#pragma once
/// \file
/// The paper's Tables 2-5 as experiment kinds (experiments/runner/experiment.hpp), run by
/// `plydem run experiments/table2.toml` ... `table5.toml`, one file each:
///
///   - `lamina-strategies` (Table 2, lamina_strategies_experiment.cpp): one lamina (the 0 deg
///     E-glass/MY750 ply) with every strategy the config lists. Per strategy: E1, E2, nu12, nu21
///     (and G12) from the static tension test; the wall time of the paper's fixed-cycle explicit
///     run (200,000 cycles, one coupon pulled along x; with --quick fewer cycles, extrapolated and
///     labelled so); the time the staged explicit solver takes to reach its quasi-static
///     tolerance; the static test's time; particle and bond counts. A strategy that is not
///     registered, or refuses the ply, gets a row saying so instead of failing the run.
///   - `lamina-angles` (Table 3, lamina_angles_experiment.cpp): laminae at the config's angles
///     with each listed strategy: Ex, Ey, nu_xy, nu_yx, Gxy and the shear coupling
///     gamma_xy/eps_x, beside correct CLT (Q-bar, computed), CalculiX (experiments/fem/
///     calculix.hpp) and the paper's theory, FEM and DEM rows.
///   - `laminate` (Tables 4 and 5, laminate_experiment.cpp): a layup from the config (hex2d plies
///     joined by interface bonds, strategies/laminate.hpp) beside CLT of its A matrix, CalculiX
///     and the paper's rows.
///
/// Every table gives relative errors against correct CLT. The paper's numbers are data: they come
/// from the config (which cites the paper's table), never from code. A paper theory value more
/// than 1% from correct CLT is flagged (ERRATA §1 explains why those rows are wrong).
/// All tension tests use free grips (uniaxial stress: the ends contract and shear freely); the
/// report says so. Each DEM model is written as VTU (particles and bonds, solved state) and drawn
/// as bonds coloured by normal stiffness; each kind draws stress-strain curves.
///
/// This header holds what the three kinds share: their common config keys, the constants tables
/// and the model figures.

#include <chrono>
#include <filesystem>
#include <limits>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/elasticity.hpp"
#include "core/stopwatch.hpp"
#include "core/units.hpp"
#include "experiments/fem/calculix.hpp"
#include "experiments/output/figures.hpp"
#include "experiments/protocols/tension.hpp"
#include "experiments/runner/experiment.hpp"

namespace plydem::paper_tables {

inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
/// A paper theory value further than this from correct CLT is flagged (ERRATA §1).
inline constexpr double kPaperTheoryTolerance = 0.01;

double radians(double degrees);

// ---- configs ---------------------------------------------------------------------------------

/// `extra` and the keys every kind reads (coupon, quick overrides, FEM settings, the paper's
/// data), for ExperimentConfig::require_known_keys.
std::vector<std::string> known_keys(std::vector<std::string> extra);

/// The report's sentence on the grips.
std::string grips_sentence(GripCondition grips);

/// What a paper-table kind's config takes, for ExperimentRegistry::set_settings: the tension
/// command's settings of `selection` with their defaults, and `own` keys beside those every paper
/// kind reads (FEM settings, figures, the paper's data).
KindSettings paper_kind_settings(const SettingsSelection& selection,
                                 std::vector<std::pair<std::string, std::string>> own);

/// fem.element, fem.elements_per_ply, fem.element_size_mm, fem.edge_band_mm (default
/// `default_edge_band` [m]) and coupon.grips. Throws plydem::Error naming the file.
FemSettings fem_settings_from(const ExperimentConfig& c, const ExperimentContext& context,
                              double default_edge_band);

/// figures.window_mm [m]: how much of the coupon the bond figures show.
double figure_window(const ExperimentConfig& c, const CouponSpec& coupon);

// ---- values and tables -----------------------------------------------------------------------

/// One line of a constants table; NaN = not available.
struct Values {
  double Ex = kNaN, Ey = kNaN, nu_xy = kNaN, nu_yx = kNaN, Gxy = kNaN, coupling = kNaN;
};

Values values_of(const InPlaneConstants& k, bool with_gxy = true);

/// The paper's values under `key` (an inline table with E1, E2, nu12, nu21 [GPa]; missing entries
/// are NaN). nullopt when the config has no such key.
std::optional<Values> paper_values(const ExperimentConfig& c, const std::string& key);

bool off_by(double value, double reference, double tolerance);

/// Whether a paper theory row differs from correct CLT by more than kPaperTheoryTolerance in Ex,
/// Ey, nu_xy or nu_yx.
bool paper_theory_off(const Values& paper, const Values& clt);

std::string number_cell(double value, const char* format, double scale);

std::string constants_header();

/// A table line with relative errors against `clt`; `flag` marks paper theory values that differ
/// from correct CLT by more than kPaperTheoryTolerance.
std::string constants_line(const std::string& label, const Values& v, const Values& clt,
                           bool flag = false);

std::string message_line(const std::string& label, const std::string& message);

/// results.csv's rows of `v` (the finite ones).
void add_rows(std::vector<ResultRow>& rows, const std::string& experiment,
              const std::string& case_name, const std::string& source, const Values& v);

std::string paper_theory_note();

// ---- DEM models: solved state, VTU, bond figure ------------------------------------------------

/// Writes vtu/STEM.pvd (+ particles and bonds .vtu) and STEM_bonds.png; returns the report lines.
std::string write_model(const Model& model, const std::filesystem::path& out_dir,
                        const std::string& stem, const std::string& caption, double window,
                        ExperimentOutput& out, const std::vector<std::string>& ply_labels = {});

/// Static stress-strain points of a pull [%, MPa].
Curve pull_curve(const std::string& label, const PullResult& pull);

Curve theory_line(const std::string& label, double modulus, double max_strain);

std::string degrees_label(double degrees);

}  // namespace plydem::paper_tables
