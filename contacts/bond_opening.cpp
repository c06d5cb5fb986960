#include "contacts/bond_opening.hpp"

#include <fmt/format.h>

#include "core/error.hpp"

namespace plydem {

void open_bond(Bonds& bonds, int b, BondState mode) {
  require(mode == BondState::kBrokenTension || mode == BondState::kBrokenShear,
          "a bond opens in tension or in shear");
  require(b >= 0 && b < bonds.size(),
          fmt::format("cannot open bond {}: the model has {} bonds", b, bonds.size()));
  require(!bonds.is_broken(b), fmt::format("bond {} is broken already", b));
  bonds.state(b) = static_cast<int>(mode);
  bonds.damage(b) = 1;
  bonds.normal_stiffness(b) = bonds.shear_stiffness(b) = 0;
  bonds.bending_stiffness(b) = bonds.twisting_stiffness(b) = 0;
}

void open_bonds(Bonds& bonds, std::span<const int> bonds_to_open, BondState mode) {
  for (int b : bonds_to_open) open_bond(bonds, b, mode);
}

}  // namespace plydem
