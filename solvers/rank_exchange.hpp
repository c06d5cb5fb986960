#pragma once
/// \file
/// The explicit engine across MPI ranks (issue 36): under `mpiexec -n N` each rank owns a slice of
/// the particles (the static solve's slices, rank_particles in solvers/linear_solver.hpp: an even
/// share in the order of the reference coordinate along the model's longest extent; the cpu
/// backend gives each of its blocks of eight to the rank whose slice holds its first particle) and
/// runs its backend over its own particles and the bonds that reach them: the reference loops
/// (solvers/reference_backend.cpp) or the cpu backend's blocks (solvers/cpu_backend.cpp). The
/// particles at the other end of those bonds are its ghosts: after every cycle their owners send
/// their displacements and rotations through a PETSc star forest (PetscSF), the only
/// communication of a plain cycle. A bond across a cut is computed, and decided by the failure
/// law, on both of its ranks from the same bits, so they agree as threads do.
///
/// What the run loop reads between cycles (the reports' sums, the gathered state, a particle's
/// state, the damage steps) is collected from the owners in the one-rank order (each particle's,
/// bond's or block's value from its owner, then summed in the one-rank order), so that a run on N
/// ranks gives the bits of the same backend's one-rank run. Every rank holds the whole model still
/// (models built in parts are the next step), and every rank must call these collectives in the
/// same order: the run loop and the experiments are replicated and deterministic (the run loop's
/// clock is agreed, max_over_ranks).
#include <cstddef>
#include <memory>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "core/model.hpp"

namespace plydem {

/// The values a ghost's owner sends it every cycle: its displacement and rotation.
inline constexpr int kGhostValues = 6;

/// How a model's particles and bonds are shared between the ranks (the same on every rank).
struct RankPartition {
  int rank = 0, size = 1;
  std::vector<int> owner;   ///< per particle: the rank that advances it
  std::vector<int> own;     ///< this rank's particles, increasing
  std::vector<int> ghosts;  ///< other ranks' particles a bond reaches from an own one, increasing
  /// own and ghosts merged, increasing: the particles whose forces this rank sums
  std::vector<int> local;
  /// The bonds that reach an own particle, increasing: computed and decided here.
  std::vector<int> bonds;
  /// This rank's particles that are other ranks' ghosts (its border), increasing: what it sends.
  std::vector<int> border;
  /// Per ghost: its index in its owner's border (where the owner sends it from).
  std::vector<int> ghost_source;
  /// The listed bonds whose first particle is own (each bond has exactly one such rank: it logs
  /// the bond's damage steps and adds its energy to the report).
  std::vector<char> logs_bond;
  /// Bytes of the lists.
  std::size_t bytes() const;
  /// Bytes this rank receives per cycle (its ghosts' state).
  std::size_t received_bytes_per_cycle() const {
    return sizeof(double) * kGhostValues * ghosts.size();
  }
};

/// Each item's slot in the order of its coordinate along the longest extent of `x` (stable: ties
/// keep their order): the order in which the ranks' slices are cut, an even share each.
std::vector<int> slots_along_longest_extent(const Eigen::Array<double, Eigen::Dynamic, 3>& x);

/// Rank `rank`'s slots [first, end) of `items`, `size` ranks: an even share in rank order.
std::pair<int, int> slots_of_rank(int rank, int size, int items);

/// Per particle of `model`, the rank of `size` whose slice holds it (rank_particles' slices: an
/// even share along the longest extent, the same on every rank for the same model). Throws
/// plydem::Error for a model with fewer particles than ranks.
std::vector<int> slice_owners(const Model& model, int size);

/// The partition of `model` on this rank of `size` by slice_owners(). Throws plydem::Error for a
/// model with fewer particles than ranks.
RankPartition partition_between_ranks(const Model& model, int rank, int size);

/// The partition of `model` on this rank of `size` with `owner` (per particle, a rank; a rank may
/// own none): its bonds, ghosts and border. Throws plydem::Error for an owner list of the wrong
/// length or naming no rank.
RankPartition partition_with_owners(const Model& model, std::vector<int> owner, int rank, int size);

/// The ghost exchange and the run loop's collectives for one partition.
class RankExchange {
 public:
  virtual ~RankExchange() = default;
  /// The partition it exchanges for.
  virtual const RankPartition& partition() const = 0;
  /// The ghosts' displacement and rotation from their owners, wherever a backend keeps them:
  /// `pack(i, row)` writes border particle i's kGhostValues into `row`, `unpack(i, row)` reads
  /// ghost i's from it (model indices).
  template <class Pack, class Unpack>
  void update_ghosts(Pack pack, Unpack unpack) {
    const RankPartition& part = partition();
    const std::span<double> out = border_rows();
    for (std::size_t k = 0; k < part.border.size(); ++k)
      pack(part.border[k], out.data() + kGhostValues * k);
    send_border();
    const std::span<const double> in = ghost_rows();
    for (std::size_t g = 0; g < part.ghosts.size(); ++g)
      unpack(part.ghosts[g], in.data() + kGhostValues * g);
  }
  /// update_ghosts() into the model's own arrays.
  void update_ghosts(Particles& particles);
  /// Whether `mine` is true on any rank (on every rank).
  virtual bool any_rank(bool mine) const = 0;
  /// Every rank's `mine` (its values in the order of its own items), concatenated in rank order
  /// on every rank; `starts` gets where each rank's values begin.
  virtual std::vector<double> gather_all(std::span<const double> mine,
                                         std::vector<std::size_t>& starts) const = 0;
  /// Every rank's bytes, concatenated in rank order on every rank.
  virtual std::vector<char> gather_bytes(std::span<const char> mine) const = 0;
  /// `value` as rank `root` has it, on every rank.
  virtual double broadcast(double value, int root) const = 0;

 protected:
  /// What this rank sends: kGhostValues per border particle, in the order of partition().border.
  virtual std::span<double> border_rows() = 0;
  /// Every rank's border_rows() to the ranks whose ghosts they are, into ghost_rows().
  virtual void send_border() = 0;
  /// What this rank received: kGhostValues per ghost, in the order of partition().ghosts.
  virtual std::span<const double> ghost_rows() const = 0;
};

/// Every rank's values of its own particles among `particles` (`width` per particle, packed by
/// `pack(i, row)` in the order of `particles`), unpacked by `unpack(i, row)` in that order on every
/// rank: each listed particle's row from its owner.
template <class Pack, class Unpack>
void share_particle_rows(const RankPartition& part, const RankExchange& exchange,
                         std::span<const int> particles, int width, Pack pack, Unpack unpack) {
  std::vector<double> mine;
  for (int i : particles)
    if (part.owner[static_cast<std::size_t>(i)] == part.rank) {
      mine.resize(mine.size() + static_cast<std::size_t>(width));
      pack(i, mine.data() + mine.size() - width);
    }
  std::vector<std::size_t> at;  // each rank's next value
  const std::vector<double> all = exchange.gather_all(mine, at);
  for (int i : particles) {
    std::size_t& next = at[static_cast<std::size_t>(part.owner[static_cast<std::size_t>(i)])];
    unpack(i, all.data() + next);
    next += static_cast<std::size_t>(width);
  }
}

/// The 12 state values share_particle_rows() sends for a particle (displacement, rotation,
/// velocity, angular velocity), from `row` into particle i of `into`.
void unpack_particle_state(Particles& into, int i, const double* row);

/// The exchange of `partition` over PETSC_COMM_WORLD. Throws plydem::Error in a plydem built
/// without PETSc (which has one rank).
std::unique_ptr<RankExchange> make_rank_exchange(const RankPartition& partition);

/// Why contacts between unbonded particles do not run on `size` ranks, and what to do.
std::string no_contacts_across_ranks(int size);

/// The largest of every rank's `value` (itself on one rank): the run loop's agreed clock.
double max_over_ranks(double value);

}  // namespace plydem
