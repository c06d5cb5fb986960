#pragma once
/// \file
/// The cracks of a failure run (solvers/cracks.hpp) for reports: a CSV of every crack, a table
/// per ply and interface (cracks, total length, modes, density along x), and for a run with a
/// strain per event, the crack density of each ply against the applied strain (CSV and PNG).

#include <filesystem>
#include <string>
#include <vector>

#include "core/bond_failure.hpp"
#include "core/model.hpp"
#include "solvers/cracks.hpp"

namespace plydem {

/// One ply's (or interface's) cracks at the end of a run.
struct CrackCount {
  bool interface = false;
  int ply = 0;  ///< ply, or interface k (above ply k)
  int cracks = 0;
  double length = 0;   ///< total [m]
  double density = 0;  ///< cracks per unit length along x over the model's length [1/m]
  int tension = 0, shear = 0, mixed = 0;  ///< cracks by mode
};

/// "ply k" (numbered from 1) or "interface k/k+1": where a crack count belongs, for reports.
std::string crack_place(bool interface, int ply);

struct CrackReport {
  std::vector<Crack> cracks;
  std::vector<CrackCount> counts;            ///< plies with cracks first (by ply), then interfaces
  std::string markdown;                      ///< the section for report.md
  std::vector<std::filesystem::path> files;  ///< written, relative to the output folder
};

/// Finds the cracks of `breaks` in `model` and writes `STEM_cracks.csv` (cracks_csv) into
/// `out_dir`. With `strain` (the applied strain at each event: strain[e] for BondBreak::at = e,
/// strain[0] the unloaded origin), also `STEM_crack_density.csv` (strain, then each cracked ply's
/// density in cracks/mm, at up to 200 events spread over the run) and its figure
/// `STEM_crack_density.png`. `title` heads the section.
CrackReport crack_report(const Model& model, const std::vector<BondBreak>& breaks,
                         const std::vector<double>& strain, const std::filesystem::path& out_dir,
                         const std::string& stem, const std::string& title);

}  // namespace plydem
