#pragma once
/// \file
/// Boundary-cell completion for regular packings. In the bulk of a regular packing every particle
/// has `bulk_count` bonds of each family (two for the hexagonal and square layers: +n and -n), and
/// owns half of each. A particle on a free edge lacks some, so the strip next to the edge is softer
/// than the material its particles' volumes stand for (for a 19-row 0 deg coupon about 1/19 of the
/// diagonal bonds, -3.5% on E2 of the paper's coupon). Completion lets the bonds that are there
/// carry the missing share: a bond of family f between i and j is scaled by
///   1/2 (bulk_count / n_i^f) + 1/2 (bulk_count / n_j^f),
/// which is 1 in the bulk, so the calibrated bulk is untouched. For edges along lattice lines the
/// strip's affine stiffness then equals the bulk stiffness times the particles' volume exactly.

#include "core/model.hpp"

namespace plydem {

/// Scales the normal, shear, bending and twisting stiffness of every bond as above. Returns the
/// number of bonds whose stiffness changed.
int complete_boundary_cells(const Particles& particles, Bonds& bonds, int family_count,
                            int bulk_count);

}  // namespace plydem
