#pragma once
/// \file
/// The one bond-force kernel that advances every model: a loop over the bond arrays applying the
/// parallel bond law (contacts/parallel_bond.hpp). Free functions over arrays, no virtual call per
/// bond, so that it can be made fast without touching strategies or experiments.

#include "contacts/parallel_bond.hpp"
#include "core/model.hpp"

namespace plydem {

/// Bond b's parameters, gathered from the bond arrays.
BondParameters bond_parameters(const Bonds& bonds, int b);

/// Totals of one pass over the bonds.
struct BondPass {
  double strain_energy = 0;   ///< sum of bond energies [J]
  double sum_force_norm = 0;  ///< sum over bonds of |F| [N], the scale of the unbalanced force
};

/// Sets particles.force and particles.torque to the bond forces and moments at the current
/// displacements and rotations (external loads are added by the caller afterwards).
BondPass compute_bond_forces(Particles& particles, const Bonds& bonds);

/// The bonds' strain energy at the current state [J], without touching forces.
double bond_strain_energy(const Particles& particles, const Bonds& bonds);

}  // namespace plydem
