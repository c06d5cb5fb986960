#include "experiments/protocols/plate_hole.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/disjoint_sets.hpp"
#include "core/error.hpp"

namespace plydem {

HoleRemoval remove_hole(Model& model, double centre_x, double centre_y, double diameter) {
  require(std::isfinite(centre_x) && std::isfinite(centre_y), "hole centre is not finite");
  require(std::isfinite(diameter) && diameter > 0,
          fmt::format("hole diameter must be positive, got {} mm", diameter * 1e3));
  const Particles& p = model.particles;
  const Bonds& b = model.bonds;
  const double r2 = 0.25 * diameter * diameter;
  std::vector<int> new_index(static_cast<size_t>(p.size()), -1);
  std::vector<int> kept;
  for (int i = 0; i < p.size(); ++i) {
    const double dx = p.reference_position(i, 0) - centre_x;
    const double dy = p.reference_position(i, 1) - centre_y;
    if (dx * dx + dy * dy >= r2) {
      new_index[i] = static_cast<int>(kept.size());
      kept.push_back(i);
    }
  }
  HoleRemoval removal;
  removal.particles = p.size() - static_cast<int>(kept.size());
  require(removal.particles > 0,
          fmt::format("a {} mm hole at ({}, {}) mm holds no particle centre: nothing to cut",
                      diameter * 1e3, centre_x * 1e3, centre_y * 1e3));
  require(!kept.empty(),
          fmt::format("a {} mm hole removes every particle of the plate", diameter * 1e3));
  std::vector<int> kept_bonds;
  for (int c = 0; c < b.size(); ++c) {
    if (new_index[b.first(c)] >= 0 && new_index[b.second(c)] >= 0) kept_bonds.push_back(c);
  }
  removal.bonds = b.size() - static_cast<int>(kept_bonds.size());

  // Each ply must stay one piece through its own bonds.
  const int n = static_cast<int>(kept.size());
  DisjointSets sets(n);
  std::vector<int> in_ply_bonds(static_cast<size_t>(n), 0);
  for (int c : kept_bonds) {
    if (b.is_interface(c)) continue;
    const int i = new_index[b.first(c)], j = new_index[b.second(c)];
    sets.join(i, j);
    ++in_ply_bonds[i];
    ++in_ply_bonds[j];
  }
  int loose = 0;
  for (int i = 0; i < n; ++i) loose += in_ply_bonds[i] == 0;
  if (loose > 0) {
    throw Error(fmt::format(
        "a {} mm hole at ({}, {}) mm leaves {} loose particle(s) with no bond in their ply: "
        "choose a hole that does not cut the plate's particles apart",
        diameter * 1e3, centre_x * 1e3, centre_y * 1e3, loose));
  }
  std::vector<std::vector<int>> roots_of_ply;
  for (int i = 0; i < n; ++i) {
    const int ply = p.ply(kept[i]);
    if (ply >= static_cast<int>(roots_of_ply.size())) roots_of_ply.resize(ply + 1);
    std::vector<int>& roots = roots_of_ply[ply];
    const int root = sets.find(i);
    if (std::find(roots.begin(), roots.end(), root) == roots.end()) roots.push_back(root);
  }
  for (size_t ply = 0; ply < roots_of_ply.size(); ++ply) {
    if (roots_of_ply[ply].size() > 1) {
      throw Error(fmt::format(
          "a {} mm hole at ({}, {}) mm cuts ply {} of the plate into {} separate pieces: the "
          "hole must be narrower than the plate",
          diameter * 1e3, centre_x * 1e3, centre_y * 1e3, ply + 1, roots_of_ply[ply].size()));
    }
  }

  Model out = select_particles(model, kept);
  out.description = fmt::format("{}, {} mm hole cut ({} particles removed)", model.description,
                                diameter * 1e3, removal.particles);
  out.check_consistency();
  model = std::move(out);
  return removal;
}

BoundaryCompletion hole_boundary_completion(const Strategy& strategy, const std::string& name) {
  const BoundaryCompletion completion = strategy.boundary_completion();
  if (completion.family_count <= 0) {
    throw Error(fmt::format(
        "a plate with a hole completes the boundary cells of a regular layer per ply after "
        "cutting the hole: strategy '{}' completes its edges its own way, which cannot be redone "
        "on the cut plate (use hex2d or square)",
        name));
  }
  return completion;
}

void complete_ply_boundary_cells(Model& model, const BoundaryCompletion& completion) {
  Bonds& bonds = model.bonds;
  std::vector<int> in_ply;
  for (int c = 0; c < bonds.size(); ++c)
    if (!bonds.is_interface(c)) in_ply.push_back(c);
  Bonds layer = bonds.select(in_ply);
  complete_boundary_cells(model.particles, layer, completion.family_count, completion.bulk_bonds);
  bonds.assign_rows(in_ply, layer);
}

}  // namespace plydem
