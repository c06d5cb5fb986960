#pragma once
/// \file
/// Contacts between particles that no intact bond joins: what keeps a cracked specimen from
/// interpenetrating, so that closed cracks carry compression (PFC's linear contact model, which a
/// parallel bond leaves behind when it breaks; Potyondy & Cundall 2004). Free functions and plain
/// arrays, like the bond kernels; the explicit integrator runs one pass per cycle.
///
/// Law. With the centres' current branch d = X_j + u_j - (X_i + u_i), n = d / |d| and the overlap
/// delta = D - |d| (D: the distance at which the pair's faces touch), a touching pair (delta > 0)
/// carries
///   - normal repulsion F_n = k_n delta, pushing i along -n and j along +n;
///   - Coulomb friction: a tangential spring s, the elastic part of the contact points' relative
///     tangential displacement, s += (v_rel - (v_rel.n) n) dt every cycle (v_rel the contact
///     points' relative velocity, as the bond law's du: (v_j - v_i) - (l_i w_i + l_j w_j) x n),
///     turned into the current tangent plane (its length kept) before, and scaled back to
///     |k_s s| = mu F_n when it exceeds the slip limit (the energy so lost is the friction
///     dissipation). The force on i is -F_n n + k_s s, on j its opposite, with the moments of
///     both about the centres (levers l_i, l_j along n).
/// A pair that stops touching forgets its spring (what energy it held counts as dissipated).
///
/// Candidates and their parameters (the rule this file documents):
///   - every pair whose bond has broken, for good: D is the bond's reference length (the crack
///     faces meet where the bond's ends met), the levers are the bond's, k_n and k_s its intact
///     stiffnesses (so that a closed crack is as stiff in compression as the bond was, and the
///     time step of the intact bonds stays stable);
///   - every other pair with no bond row, within (1 + skin)(r_i + r_j) at the last search (the
///     shared cell list, find_contact_pairs): D = r_i + r_j, levers r_i and r_j, k_n (k_s) the
///     mean of the two particles' mean intact bond k_n (k_s) (the model's mean for a particle with
///     none). Pairs joined by an intact bond never touch as contacts: the bond carries them.
///   - Skin rule (Verlet): a pair left out at a search was more than skin (r_i + r_j) >= 2 skin
///     r_min apart, so it cannot touch before some particle has moved skin r_min since the
///     search. check() measures the largest displacement D_max since the last search and the
///     largest speed v_max; it searches again when D_max > skin r_min / 2, and asks to be called
///     again after (skin r_min - D_max) / (2 v_max dt) cycles (at most check_interval): enough
///     unless a particle more than doubles its speed in that time (a break, where the integrator
///     checks at the next cycle).

#include <Eigen/Dense>
#include <cstdint>
#include <vector>

#include "core/checkpoint.hpp"
#include "core/model.hpp"

namespace plydem {

struct ContactSettings {
  /// Candidates lie within (1 + skin)(r_i + r_j) at a search (> 0).
  double skin = 0.2;
  /// The most cycles between two checks of the skin rule (>= 1).
  long check_interval = 1000;
  /// Coulomb coefficient mu of every contact (>= 0), PFC's contact friction, which the bond's
  /// own tan(phi) (the friction term of its shear strength) does not set.
  double friction = 0.5;

  /// Throws plydem::Error naming the first bad field.
  void validate() const;
};

/// One candidate pair and its history.
struct UnbondedContact {
  int first = 0, second = 0;     ///< model particles (the broken bond's first and second, or i < j)
  int bond = -1;                 ///< the broken bond between them, or -1
  double branch[3] = {0, 0, 0};  ///< reference X_second - X_first [m]
  double distance = 0;           ///< D, the centre distance at which they touch [m]
  double lever_first = 0, lever_second = 0;          ///< [m]
  double normal_stiffness = 0, shear_stiffness = 0;  ///< k_n, k_s [N/m]
  double spring[3] = {0, 0, 0};                      ///< s [m]
  double overlap = 0;                                ///< delta at the last pass, 0 if apart [m]
};

/// A particle state in some numbering: component c of particle k at [c][k].
struct ContactState {
  const double* displacement[3] = {nullptr, nullptr, nullptr};
  const double* rotation[3] = {nullptr, nullptr, nullptr};
  const double* velocity[3] = {nullptr, nullptr, nullptr};
  const double* angular_velocity[3] = {nullptr, nullptr, nullptr};
};

/// Where a pass writes: component c of particle k at [c][k].
struct ContactForces {
  double* force[3] = {nullptr, nullptr, nullptr};
  double* torque[3] = {nullptr, nullptr, nullptr};
};

/// The candidate list, its history and its searches. Particles are addressed in the numbering of
/// the arrays the passes read (the model's or a kernel's), the list kept in order of the pairs'
/// model indices, so that results do not depend on that numbering.
class UnbondedContacts {
 public:
  UnbondedContacts() = default;
  /// `index[i]` = array index of model particle i. `intact_normal` and `intact_shear` are the
  /// bonds' intact stiffnesses (0 where unknown: a bond that came broken). Every broken bond of
  /// the model is a candidate from the start; the state `s` (in the arrays' numbering) is the one
  /// of the first search. Throws plydem::Error for bad settings.
  UnbondedContacts(const Model& model, const Eigen::ArrayXd& intact_normal,
                   const Eigen::ArrayXd& intact_shear, std::vector<int> index,
                   const ContactSettings& settings, const ContactState& s);

  /// Bond b (of the model given at construction) has just broken: its pair becomes a candidate.
  void add_broken_bond(int b);

  /// One pass at state `s` (displacements u(n), velocities v(n-1/2)) with time step `dt`: every
  /// candidate's force and moment go into `out`, whose entries written by the previous pass are
  /// zeroed first (the others are left alone).
  void apply(const ContactState& s, double dt, const ContactForces& out);
  /// The array indices the last pass wrote (repeats possible).
  const std::vector<int>& touched() const { return touched_; }

  /// What the contact of bond b, broken at the last cycle, takes over from it at state `s` (the
  /// one after that cycle, with the velocities of the step to it): the energy its first pass will
  /// hold and dissipate plus half the work its force does over that step. A break releases its
  /// bond's energy less this (a compressed bond that breaks into a contact as stiff releases no
  /// normal energy). Does not change the contacts.
  double handover(int b, const ContactState& s, double dt) const;

  /// The skin rule (see the file comment) at state `s`: searches again if it must. Returns the
  /// cycles until the next check.
  long check(const ContactState& s, double dt);

  /// Energy held by the touching contacts' springs at the last pass [J].
  double stored_energy() const;
  /// Energy dissipated by slip (and by springs of pairs that came apart) so far [J].
  double friction_dissipation() const { return friction_dissipation_; }
  const std::vector<UnbondedContact>& contacts() const { return contacts_; }
  long searches() const { return searches_; }
  /// Contacts touching at the last pass.
  int touching() const;

  /// Writes what changes during a run (the candidates and their history, the last pass's touched
  /// indices, the last search's displacements, the dissipation and search count).
  void save(CheckpointWriter& out) const;
  /// Restores what save() wrote into contacts constructed as the saved ones were (the same model
  /// and numbering). Throws plydem::Error for a checkpoint of another model.
  void restore(CheckpointReader& in);

 private:
  void search(const ContactState& s);
  UnbondedContact broken_pair(int b) const;
  std::uint64_t key(int i, int j) const;

  ContactSettings settings_;
  std::vector<int> index_;  // model particle -> array index
  int particles_ = 0;
  Vector3Array reference_position_;  // model order
  Eigen::ArrayXd radius_;            // model order
  double min_radius_ = 0;
  Eigen::ArrayXd particle_normal_, particle_shear_;  // mean intact k_n, k_s per particle
  // The model's bonds, as far as contacts need them.
  Eigen::ArrayXi bond_first_, bond_second_;
  Eigen::ArrayXd bond_length_, bond_lever_first_, bond_lever_second_;
  Eigen::ArrayXd intact_normal_, intact_shear_;
  std::vector<std::uint64_t> bonded_;      // sorted keys of every pair with a bond row
  std::vector<UnbondedContact> contacts_;  // sorted by key
  std::vector<int> touched_;
  Vector3Array searched_at_;  // displacements at the last search, model order
  double friction_dissipation_ = 0;
  long searches_ = 0;
};

}  // namespace plydem
