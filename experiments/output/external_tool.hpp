#pragma once
/// \file
/// Programs plydem runs but does not link: CalculiX (`ccx`) for the FEM references and gnuplot for
/// the figures. Looking one up never throws; running one that fails throws plydem::Error with its
/// own words.

#include <filesystem>
#include <optional>
#include <string>

namespace plydem {

/// The path of `executable` (looked up on PATH unless it contains a '/'), or nullopt when it is
/// not an executable file.
std::optional<std::string> find_executable(const std::string& executable);

/// `text` quoted for a POSIX shell.
std::string shell_quote(const std::string& text);

/// Whether gnuplot (with the pngcairo terminal) can draw the figures.
struct GnuplotAvailability {
  bool available = false;
  std::string executable;  ///< the resolved path when available
  /// When unavailable, why, in one line ("gnuplot is not installed: ... (Debian: apt-get install
  /// gnuplot-nox)").
  std::string message;
};
GnuplotAvailability gnuplot_availability(const std::string& executable = "gnuplot");

/// Runs a gnuplot script in `directory` (data files are read relative to it); the script is kept
/// there as `script_name` so that a user can edit and rerun it. Throws plydem::Error with
/// gnuplot's messages if it is missing or fails.
void run_gnuplot(const std::string& script, const std::filesystem::path& directory,
                 const std::string& script_name);

}  // namespace plydem
