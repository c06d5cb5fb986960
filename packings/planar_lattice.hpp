#pragma once
/// \file
/// What the one-particle planar lattices (hexagonal_layer.hpp, square_layer.hpp) share: the sites
/// of a lattice inside a rectangle.
#include <Eigen/Dense>

#include "contacts/cell_list.hpp"

namespace plydem {

/// The sites origin + i a1 + j a2 (origin = (r, r), r = spacing / 2) of the lattice with in-plane
/// vectors a1, a2 whose particles of diameter `spacing` lie inside the rectangle [0, length] x
/// [0, width], sorted by rows of y and along x within a row (neighbours stay close in memory), at
/// z = 0. Throws plydem::Error if the rectangle cannot hold one particle or would need more than
/// 5e8 lattice sites. Reports its progress by lattice rows (core/progress.hpp).
PositionArray fill_rectangle(const Eigen::Vector2d& a1, const Eigen::Vector2d& a2, double spacing,
                             double length, double width);

}  // namespace plydem
