// The explicit engine's partition between MPI ranks and its exchange (solvers/rank_exchange.hpp):
// the ghosts' state through a PETSc star forest, the run loop's collectives through MPI on
// PETSC_COMM_WORLD. The MPI side is compiled only where PETSc is (PLYDEM_HAVE_PETSC).
#include "solvers/rank_exchange.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <numeric>

#include "core/error.hpp"
#include "solvers/linear_solver.hpp"

#ifdef PLYDEM_HAVE_PETSC
#include <petscsf.h>
#endif

namespace plydem {

std::vector<int> slots_along_longest_extent(const Eigen::Array<double, Eigen::Dynamic, 3>& x) {
  const auto items = static_cast<int>(x.rows());
  if (items == 0) return {};
  const Eigen::RowVector3d extent = x.colwise().maxCoeff() - x.colwise().minCoeff();
  Eigen::Index axis = 0;
  extent.maxCoeff(&axis);
  std::vector<int> by_coordinate(static_cast<std::size_t>(items));
  std::iota(by_coordinate.begin(), by_coordinate.end(), 0);
  std::stable_sort(by_coordinate.begin(), by_coordinate.end(),
                   [&](int a, int b) { return x(a, axis) < x(b, axis); });
  std::vector<int> slot_of(static_cast<std::size_t>(items));
  for (int s = 0; s < items; ++s) slot_of[static_cast<std::size_t>(by_coordinate[s])] = s;
  return slot_of;
}

std::pair<int, int> slots_of_rank(int rank, int size, int items) {
  return {static_cast<int>(static_cast<long>(rank) * items / size),
          static_cast<int>(static_cast<long>(rank + 1) * items / size)};
}

std::string no_contacts_across_ranks(int size) {
  return fmt::format(
      "contacts between unbonded particles do not run across MPI ranks yet ({} ranks here): run "
      "without them (the explicit settings' contacts off; the strength test's material point "
      "turns them off) or on one rank",
      size);
}

std::size_t RankPartition::bytes() const {
  return sizeof(int) * (owner.size() + own.size() + ghosts.size() + local.size() + bonds.size() +
                        border.size() + ghost_source.size()) +
         logs_bond.size();
}

std::vector<int> slice_owners(const Model& model, int size) {
  const int n = model.particles.size();
  require(size >= 1, fmt::format("{} MPI ranks cannot share a model", size));
  require(n >= size, fmt::format("a model of {} particles cannot be shared between {} MPI ranks: "
                                 "run it on at most {} ranks",
                                 n, size, n));
  // The static solve's slices (petsc_solver.cpp numbers its rows by the same slots).
  const std::vector<int> slot_of = slots_along_longest_extent(model.particles.reference_position);
  std::vector<int> owner_of_slot(static_cast<std::size_t>(n));
  for (int r = 0; r < size; ++r) {
    const auto [first, end] = slots_of_rank(r, size, n);
    for (int s = first; s < end; ++s) owner_of_slot[static_cast<std::size_t>(s)] = r;
  }
  std::vector<int> owner(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i)
    owner[static_cast<std::size_t>(i)] =
        owner_of_slot[static_cast<std::size_t>(slot_of[static_cast<std::size_t>(i)])];
  return owner;
}

RankPartition partition_between_ranks(const Model& model, int rank, int size) {
  require(size >= 1 && rank >= 0 && rank < size,
          fmt::format("rank {} of {} ranks does not exist", rank, size));
  return partition_with_owners(model, slice_owners(model, size), rank, size);
}

RankPartition partition_with_owners(const Model& model, std::vector<int> owners, int rank,
                                    int size) {
  const Bonds& bonds = model.bonds;
  const int n = model.particles.size();
  require(size >= 1 && rank >= 0 && rank < size,
          fmt::format("rank {} of {} ranks does not exist", rank, size));
  require(static_cast<int>(owners.size()) == n &&
              std::all_of(owners.begin(), owners.end(), [&](int r) { return r >= 0 && r < size; }),
          fmt::format("the owners of a partition between {} ranks must name a rank for each of "
                      "the {} particles",
                      size, n));
  RankPartition part;
  part.rank = rank;
  part.size = size;
  part.owner = std::move(owners);
  // This rank's bonds and ghosts, and every rank's border from the whole model's bonds (every
  // rank holds them): a particle is on its owner's border where a bond joins it to another rank's
  // particle; its index there, counted in increasing order on its owner, is where the owner sends
  // it from.
  std::vector<char> ghost(static_cast<std::size_t>(n), 0),
      on_border(static_cast<std::size_t>(n), 0);
  auto owner = [&](int i) { return part.owner[static_cast<std::size_t>(i)]; };
  for (int b = 0; b < bonds.size(); ++b) {
    const int i = bonds.first(b), j = bonds.second(b);
    if (owner(i) != owner(j))
      on_border[static_cast<std::size_t>(i)] = on_border[static_cast<std::size_t>(j)] = 1;
    if (owner(i) != rank && owner(j) != rank) continue;
    part.bonds.push_back(b);
    part.logs_bond.push_back(owner(i) == rank ? 1 : 0);
    if (owner(i) != rank) ghost[static_cast<std::size_t>(i)] = 1;
    if (owner(j) != rank) ghost[static_cast<std::size_t>(j)] = 1;
  }
  std::vector<int> border_index(static_cast<std::size_t>(n), -1);
  std::vector<int> next(static_cast<std::size_t>(size), 0);
  for (int i = 0; i < n; ++i)
    if (on_border[static_cast<std::size_t>(i)])
      border_index[static_cast<std::size_t>(i)] = next[static_cast<std::size_t>(owner(i))]++;
  for (int i = 0; i < n; ++i) {
    if (owner(i) == rank && on_border[static_cast<std::size_t>(i)]) part.border.push_back(i);
    if (ghost[static_cast<std::size_t>(i)])
      part.ghost_source.push_back(border_index[static_cast<std::size_t>(i)]);
  }
  for (int i = 0; i < n; ++i) {
    if (owner(i) == rank) part.own.push_back(i);
    if (ghost[static_cast<std::size_t>(i)]) part.ghosts.push_back(i);
    if (owner(i) == rank || ghost[static_cast<std::size_t>(i)]) part.local.push_back(i);
  }
  return part;
}

void unpack_particle_state(Particles& into, int i, const double* row) {
  for (int c = 0; c < 3; ++c) {
    into.displacement(i, c) = row[c];
    into.rotation(i, c) = row[3 + c];
    into.velocity(i, c) = row[6 + c];
    into.angular_velocity(i, c) = row[9 + c];
  }
}

void RankExchange::update_ghosts(Particles& p) {
  update_ghosts(
      [&](int i, double* row) {
        for (int c = 0; c < 3; ++c) {
          row[c] = p.displacement(i, c);
          row[3 + c] = p.rotation(i, c);
        }
      },
      [&](int i, const double* row) {
        for (int c = 0; c < 3; ++c) {
          p.displacement(i, c) = row[c];
          p.rotation(i, c) = row[3 + c];
        }
      });
}

#ifdef PLYDEM_HAVE_PETSC
namespace {

void check_mpi(int code, const char* what) {
  if (code != MPI_SUCCESS) throw Error(fmt::format("MPI failed in {} (error {})", what, code));
}

void check_petsc(PetscErrorCode code, const char* what) {
  if (code != 0) throw Error(fmt::format("PETSc failed in {} (error {})", what, code));
}

// The ghosts' displacement and rotation travel as one unit of kGhostValues doubles per particle:
// the roots are a rank's particles that are some other rank's ghosts (its border), packed in
// increasing order; the leaves its own ghosts, increasing.
constexpr int kGhostWidth = kGhostValues;

// Every rank's `mine` concatenated in rank order on every rank (MPI_Allgatherv), `starts` where
// each rank's values begin.
template <class T>
std::vector<T> gather_from_ranks(std::span<const T> mine, MPI_Datatype type,
                                 std::vector<std::size_t>& starts) {
  int size = 1;
  check_mpi(MPI_Comm_size(PETSC_COMM_WORLD, &size), "MPI_Comm_size");
  std::vector<int> counts(static_cast<std::size_t>(size), 0);
  const int count = static_cast<int>(mine.size());
  check_mpi(MPI_Allgather(&count, 1, MPI_INT, counts.data(), 1, MPI_INT, PETSC_COMM_WORLD),
            "MPI_Allgather");
  std::vector<int> offsets(counts.size(), 0);
  for (std::size_t r = 1; r < counts.size(); ++r) offsets[r] = offsets[r - 1] + counts[r - 1];
  std::vector<T> all(static_cast<std::size_t>(offsets.back() + counts.back()));
  check_mpi(MPI_Allgatherv(mine.data(), count, type, all.data(), counts.data(), offsets.data(),
                           type, PETSC_COMM_WORLD),
            "MPI_Allgatherv");
  starts.assign(offsets.begin(), offsets.end());
  return all;
}

class PetscRankExchange final : public RankExchange {
 public:
  explicit PetscRankExchange(const RankPartition& part) : part_(part) {
    std::vector<PetscSFNode> remote(part.ghosts.size());
    for (std::size_t g = 0; g < part.ghosts.size(); ++g) {
      remote[g].rank = part.owner[static_cast<std::size_t>(part.ghosts[g])];
      remote[g].index = part.ghost_source[g];
    }
    check_petsc(PetscSFCreate(PETSC_COMM_WORLD, &sf_), "PetscSFCreate");
    check_petsc(PetscSFSetGraph(sf_, static_cast<PetscInt>(part.border.size()),
                                static_cast<PetscInt>(part.ghosts.size()), nullptr,
                                PETSC_COPY_VALUES, remote.data(), PETSC_COPY_VALUES),
                "PetscSFSetGraph");
    check_petsc(PetscSFSetUp(sf_), "PetscSFSetUp");
    check_mpi(MPI_Type_contiguous(kGhostWidth, MPI_DOUBLE, &unit_), "MPI_Type_contiguous");
    check_mpi(MPI_Type_commit(&unit_), "MPI_Type_commit");
    root_buffer_.resize(kGhostWidth * part.border.size());
    leaf_buffer_.resize(kGhostWidth * part.ghosts.size());
  }

  ~PetscRankExchange() override {
    MPI_Type_free(&unit_);
    PetscSFDestroy(&sf_);
  }

  bool any_rank(bool mine) const override {
    int value = mine ? 1 : 0;
    check_mpi(MPI_Allreduce(MPI_IN_PLACE, &value, 1, MPI_INT, MPI_LOR, PETSC_COMM_WORLD),
              "MPI_Allreduce");
    return value != 0;
  }

  std::vector<double> gather_all(std::span<const double> mine,
                                 std::vector<std::size_t>& starts) const override {
    return gather_from_ranks(mine, MPI_DOUBLE, starts);
  }

  std::vector<char> gather_bytes(std::span<const char> mine) const override {
    std::vector<std::size_t> starts;
    return gather_from_ranks(mine, MPI_CHAR, starts);
  }

  double broadcast(double value, int root) const override {
    check_mpi(MPI_Bcast(&value, 1, MPI_DOUBLE, root, PETSC_COMM_WORLD), "MPI_Bcast");
    return value;
  }

  const RankPartition& partition() const override { return part_; }

 protected:
  std::span<double> border_rows() override { return root_buffer_; }
  std::span<const double> ghost_rows() const override { return leaf_buffer_; }

  void send_border() override {
    check_petsc(
        PetscSFBcastBegin(sf_, unit_, root_buffer_.data(), leaf_buffer_.data(), MPI_REPLACE),
        "PetscSFBcastBegin");
    check_petsc(PetscSFBcastEnd(sf_, unit_, root_buffer_.data(), leaf_buffer_.data(), MPI_REPLACE),
                "PetscSFBcastEnd");
  }

 private:
  const RankPartition& part_;
  std::vector<double> root_buffer_, leaf_buffer_;
  PetscSF sf_ = nullptr;
  MPI_Datatype unit_ = MPI_DATATYPE_NULL;
};

}  // namespace

std::unique_ptr<RankExchange> make_rank_exchange(const RankPartition& partition) {
  return std::make_unique<PetscRankExchange>(partition);
}

double max_over_ranks(double value) {
  if (mpi_size() <= 1) return value;
  check_mpi(MPI_Allreduce(MPI_IN_PLACE, &value, 1, MPI_DOUBLE, MPI_MAX, PETSC_COMM_WORLD),
            "MPI_Allreduce");
  return value;
}

#else

std::unique_ptr<RankExchange> make_rank_exchange(const RankPartition& partition) {
  throw Error(
      fmt::format("the explicit engine on {} MPI ranks needs PETSc: this plydem was built "
                  "without it",
                  partition.size));
}

double max_over_ranks(double value) {
  return value;
}

#endif

}  // namespace plydem
