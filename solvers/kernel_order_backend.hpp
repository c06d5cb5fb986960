#pragma once
/// \file
/// The state of the backends that run in kernel order (the host's SIMD backend, solvers/
/// cpu_backend.cpp, and the device backends it mirrors, MirroredBackend in
/// kernel_order_backend.cpp): the particles renumbered for locality (contacts/
/// particle_ordering.hpp: lattice lines for a regular packing, else a Hilbert curve), the kernel's
/// arrays in that order (solvers/kernel_arrays.hpp) and the bond table in gather form
/// (contacts/bond_kernel.hpp GatherBonds). The model's state is copied in at the start of a run and
/// back at its end; in between, the run loop reads it through gather() and state().
///
/// Breaking: both ends of a bond decide alike (contacts/half_bond.hpp gather_half_bonds), each
/// particle clearing its own slot; store_bonds() writes the bonds back and checks that both ends
/// agree to the bit.

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "contacts/bond_kernel.hpp"
#include "solvers/explicit_backend.hpp"

namespace plydem {

/// How the host keeps a kernel array: doubles in 64-byte aligned arrays of whole lanes (the SIMD
/// kernel loads them as vectors), anything else in a vector.
template <class T>
class HostStore {
 public:
  void resize(std::size_t n) { data_.assign(n, T{}); }
  T* data() { return data_.data(); }
  const T* data() const { return data_.data(); }
  std::size_t size() const { return data_.size(); }
  std::size_t bytes() const { return data_.size() * sizeof(T); }

 private:
  std::vector<T> data_;
};

template <>
class HostStore<double> {
 public:
  void resize(std::size_t n) { data_ = lanes::Array(n); }
  double* data() { return data_.data(); }
  const double* data() const { return data_.data(); }
  std::size_t size() const { return data_.size(); }
  std::size_t bytes() const { return data_.bytes(); }

 private:
  lanes::Array data_;
};

class KernelOrderBackend : public KernelBackend {
 public:
  explicit KernelOrderBackend(const BackendSetup& setup);

  bool kernel_order() const override { return true; }
  std::size_t bytes() const override;
  void set_motions(const MotionTable& table) override;
  void start_breaking(bool softening) override;
  void load() override;
  void store() override;
  void gather(std::span<const int> particles, Particles& into, StateAt at) const override;
  double state(int i, int c, bool rotation) const override;
  ContactState contact_state() const override;
  std::vector<int> contact_index() const override { return position_; }
  void touch_contacts(const std::vector<int>& touched) override;
  void clear_bond(int bond) override;
  std::array<BondEnd, 2> bond_ends(int bond) const override;
  void store_bonds(Bonds& bonds, Eigen::ArrayXd& kappa) const override;
  void restore_bonds(const Bonds& bonds, const Eigen::ArrayXd& kappa) override;
  AccountArrays account() const override;
  void set_account(const AccountArrays& account) override;

 protected:
  /// The state in buffer `parity` as the contacts read it.
  ContactState state_at(int parity) const;
  /// The KernelMode of the bonds as they are.
  int mode() const;
  KernelSizes sizes() const;
  /// The host's arrays and its bond table, as the step (and a device's copies) see them.
  KernelView view();
  /// After a batch that reported: its forces into the model (model order), and the report sums
  /// from the per-particle partials (block partials in lane order, then blocks in order; the same
  /// order a device reduces them in).
  void store_report(CycleBatch& batch, bool reduce);
  /// store_bonds() with each bond's two ends as `ends_of(bond)` gives them (the kernel's own, or
  /// on N ranks each end's from the rank that steps it).
  void write_bonds(Bonds& bonds, Eigen::ArrayXd& kappa,
                   const std::function<std::array<BondEnd, 2>(int)>& ends_of) const;

  Model& model_;
  BondHistory& history_;
  StrengthStorage storage_;
  std::vector<int> order_;     // order_[k] = model index of kernel particle k
  std::vector<int> position_;  // inverse of order_: kernel index of model particle i
  GatherBonds bonds_;
  KernelArrays<HostStore> arrays_;
  int particles_ = 0, padded_ = 0, blocks_ = 0, class_count_ = 1;
  int parity_ = 0;  // the buffer holding the current displacements and rotations
  bool breaking_ = false, softening_ = false, running_ = false;
  // Breaking: the contacts' forces, in kernel order, and which blocks have any.
  lanes::Array contact_force_[3], contact_torque_[3];
  std::vector<std::uint8_t> contact_block_;
};

}  // namespace plydem
