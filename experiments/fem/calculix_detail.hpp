#pragma once
/// \file
/// What the CalculiX bridge's files share and nothing else uses: the mid-plane interpolation the
/// deck writer (calculix_input.cpp) and the measurement (calculix_results.cpp) both need, and the
/// `.dat` reader the runner (calculix_run.cpp) calls. Not part of plydem's API.

#include <Eigen/Dense>
#include <string>
#include <vector>

#include "experiments/fem/calculix.hpp"

namespace plydem::calculix_detail {

/// The node levels that straddle z = 0, and the weight of the upper one.
struct MidPlane {
  int lower = 0;
  double weight = 0;
};
/// Throws plydem::Error if the levels do not span z = 0.
MidPlane mid_plane(const std::vector<double>& level_z);

/// What ccx's job.dat holds: every node's displacement (and which were seen), the reaction totals
/// of both grips, and with stresses the sum of each element's integration-point stresses.
struct DatResults {
  Vector3Array displacement;
  std::vector<bool> seen;
  Eigen::Vector3d left_force = Eigen::Vector3d::Zero();
  Eigen::Vector3d right_force = Eigen::Vector3d::Zero();
  bool left_seen = false, right_seen = false;
  Eigen::Array<double, Eigen::Dynamic, 6> stress_sum;
  Eigen::ArrayXi stress_points;
};
/// Reads job.dat's text; throws plydem::Error naming the first line it cannot read.
DatResults parse_dat(const std::string& text, int nodes, int elements, bool stresses);

/// Sets the solution's results from the solved `mesh` and its job.dat: the grips' force and the
/// gross stress, the gauge section's strains, the displacement field and (with
/// settings.element_stresses) the element stresses. Throws plydem::Error when job.dat lacks a
/// value or the gauge section holds too few nodes.
void measure_solution(const FemSpecimen& specimen, const FemSettings& settings, const FemMesh& mesh,
                      const DatResults& dat, FemSolution& solution);

}  // namespace plydem::calculix_detail
