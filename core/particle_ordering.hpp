#pragma once
/// \file
/// Particle numbering for memory locality. A bond kernel reads its particles' neighbours; when
/// particles close in space are also close in memory, those reads hit cache lines that were just
/// loaded. A space-filling (Hilbert) curve through the reference positions gives such a numbering
/// for any packing, regular or not (the same idea as LAMMPS's `atom_modify sort` and HOOMD-blue's
/// `SFCPackTuner`, which use a Hilbert curve over bins).

#include <vector>

#include "core/model.hpp"

namespace plydem {

/// The particles in the order a Hilbert curve visits their reference positions:
/// order[k] = index of the k-th particle along the curve. The curve is two-dimensional when the
/// positions lie in a plane normal to a coordinate axis (a layer), otherwise three-dimensional.
/// Ties (particles in the same curve cell) keep their current order, so the result is
/// deterministic.
std::vector<int> space_filling_curve_order(const Vector3Array& position);

/// Throws plydem::Error unless `order` is a permutation of 0 .. count-1.
void check_permutation(const std::vector<int>& order, int count);

/// Renumbers the model's particles so that new particle k is old particle order[k]: every particle
/// array is permuted, bond endpoints are renamed, and the bonds are sorted by their lower new
/// endpoint (then the higher one), so that a pass over the bonds walks the particles in order.
/// Groups, plies and every other per-particle property travel with their particle; a bond keeps
/// its orientation (first -> second). Throws plydem::Error if `order` is not a permutation.
void renumber(Model& model, const std::vector<int>& order);

}  // namespace plydem
