#include "contacts/bond_kernel.hpp"

namespace plydem {
namespace {

Eigen::Vector3d row3(const Vector3Array& a, int i) {
  return {a(i, 0), a(i, 1), a(i, 2)};
}

void add_row3(Vector3Array& a, int i, const Eigen::Vector3d& v) {
  a(i, 0) += v.x();
  a(i, 1) += v.y();
  a(i, 2) += v.z();
}

BondResponse evaluate(const Particles& p, const Bonds& bonds, int b) {
  const int i = bonds.first(b);
  const int j = bonds.second(b);
  return parallel_bond_response(bond_parameters(bonds, b), row3(p.displacement, i),
                                row3(p.rotation, i), row3(p.displacement, j), row3(p.rotation, j));
}

}  // namespace

BondParameters bond_parameters(const Bonds& bonds, int b) {
  BondParameters params;
  params.normal = row3(bonds.normal, b);
  params.lever_first = bonds.lever_first(b);
  params.lever_second = bonds.lever_second(b);
  params.normal_stiffness = bonds.normal_stiffness(b);
  params.shear_stiffness = bonds.shear_stiffness(b);
  params.bending_stiffness = bonds.bending_stiffness(b);
  params.twisting_stiffness = bonds.twisting_stiffness(b);
  return params;
}

BondPass compute_bond_forces(Particles& particles, const Bonds& bonds) {
  particles.force.setZero();
  particles.torque.setZero();
  BondPass pass;
  for (int b = 0; b < bonds.size(); ++b) {
    const BondResponse r = evaluate(particles, bonds, b);
    const int i = bonds.first(b);
    const int j = bonds.second(b);
    add_row3(particles.force, i, r.force_on_first);
    add_row3(particles.force, j, -r.force_on_first);
    add_row3(particles.torque, i, r.torque_on_first);
    add_row3(particles.torque, j, r.torque_on_second);
    pass.strain_energy += r.energy;
    pass.sum_force_norm += r.force_on_first.norm();
  }
  return pass;
}

double bond_strain_energy(const Particles& particles, const Bonds& bonds) {
  double energy = 0;
  for (int b = 0; b < bonds.size(); ++b) energy += evaluate(particles, bonds, b).energy;
  return energy;
}

}  // namespace plydem
