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

/// Lattice lines, for a regular packing: the particles line by line along one lattice direction (of
/// the bonds and the sums and differences of two bonds, the one with the fewest, longest lines),
/// lines side by side (by layer, then by row), the lattice cut into
/// strips `strip_length` bond lengths long across the lines so that the few lines the kernel works
/// on stay in cache (a scan curve over strips). In this order, for every bond direction, the
/// neighbours of eight consecutive particles of a line are eight consecutive particles of the same
/// or the next line, which the kernel loads as one vector instead of gathering them one by one.
/// Returns an empty vector when the bonds point along more than 16 directions (not a lattice).
std::vector<int> lattice_line_order(const Model& model, int strip_length = 256);

/// How the explicit kernel numbers particles internally (the model keeps its own numbering).
enum class ParticleOrder {
  kAutomatic,  ///< lattice lines where the packing is a lattice, else the Hilbert curve
  kHilbert,    ///< space_filling_curve_order
  kAsBuilt,    ///< the model's own numbering
};

/// The kernel order of `model` for the given choice.
std::vector<int> kernel_order(const Model& model, ParticleOrder choice);

/// Throws plydem::Error unless `order` is a permutation of 0 .. count-1.
void check_permutation(const std::vector<int>& order, int count);

/// Renumbers the model's particles so that new particle k is old particle order[k]: every particle
/// array is permuted, bond endpoints are renamed, and the bonds are sorted by their lower new
/// endpoint (then the higher one), so that a pass over the bonds walks the particles in order.
/// Groups, plies and every other per-particle property travel with their particle; a bond keeps
/// its orientation (first -> second). Throws plydem::Error if `order` is not a permutation.
void renumber(Model& model, const std::vector<int>& order);

}  // namespace plydem
