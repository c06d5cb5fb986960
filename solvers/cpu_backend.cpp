// The host's SIMD backend (solvers/explicit_backend.hpp): the kernel-order state of
// solvers/kernel_order_backend.hpp, each block of eight particles running step_particle
// (solvers/particle_step.hpp) in the lanes of a vector (BlockLayout), the blocks split between
// OpenMP threads (OMP_NUM_THREADS). Each particle sums its own bonds, so its result does not
// depend on the thread count, and a run is bitwise reproducible on any number of threads.
//
// Under mpiexec (BackendSetup::split_between_ranks) each rank steps the blocks it owns (a block
// goes to the rank whose slice, solvers/rank_exchange.hpp slice_owners, holds its first particle)
// and, after every cycle, receives its ghosts' displacements and rotations from their owners
// through the PETSc star forest. A block's step reads only its own slots and its neighbours'
// state, so it gives the one-rank run's bits; the report's block sums, the damage steps and what
// the run loop gathers come from the ranks that step them, summed in the one-rank order: the same
// bits as the cpu backend on one rank.
#include <omp.h>

#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
#include <numeric>

#include "core/error.hpp"
#include "solvers/kernel_order_backend.hpp"
#include "solvers/linear_solver.hpp"
#include "solvers/particle_step.hpp"
#include "solvers/rank_exchange.hpp"

// The step is compiled for three instruction sets and the best one the processor has is picked
// when the program starts (GCC function multi-versioning): one binary runs everywhere and uses
// AVX-512 where it exists. Everything the step calls is inlined into it. The results are the same
// in every clone: the step's multiply-adds are explicit fused ones (core/lane_ops.hpp).
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && \
    !defined(PLYDEM_NO_TARGET_CLONES)
#define PLYDEM_TARGET_CLONES [[gnu::target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")]]
#else
#define PLYDEM_TARGET_CLONES
#endif

namespace plydem {
namespace {

// What the blocks of one thread's cycle share.
struct BlockPass {
  const KernelView* a = nullptr;
  GatherBonds* bonds = nullptr;
  int parity = 0;
  double dt = 0, alpha = 0;
  // Breaking: the contacts' forces (kernel order) and which blocks have any; the thread's pass.
  const lanes::Array* contact_force = nullptr;
  const lanes::Array* contact_torque = nullptr;
  const std::uint8_t* contact_block = nullptr;
  BreakingPass* pass = nullptr;
};

// Block `block` (particles 8 block .. 8 block + 7): the Layout of step_particle for eight
// particles in the lanes of a vector.
class BlockLayout {
 public:
  using Lane = lanes::Doubles;
  using Mask = lanes::Mask;

  [[gnu::always_inline]] BlockLayout(const BlockPass& b, int block)
      : b_(b),
        a_(*b.a),
        block_(block),
        first_(block * lanes::kCount),
        state_{{a_.displacement[b.parity][0], a_.displacement[b.parity][1],
                a_.displacement[b.parity][2]},
               {a_.rotation[b.parity][0], a_.rotation[b.parity][1], a_.rotation[b.parity][2]}} {}

  [[gnu::always_inline]] double dt() const { return b_.dt; }
  [[gnu::always_inline]] double alpha() const { return b_.alpha; }

  [[gnu::always_inline]] void load_state(Lane (&u)[3], Lane (&t)[3]) const {
    for (int c = 0; c < 3; ++c) {
      lanes::load(state_.displacement[c] + first_, u[c]);
      lanes::load(state_.rotation[c] + first_, t[c]);
    }
  }

  [[gnu::always_inline]] BlockSlots slots() const {
    return BlockSlots(*b_.bonds, first_, state_, b_.pass);
  }

  [[gnu::always_inline]] void add_contacts(Lane (&force)[3], Lane (&torque)[3]) const {
    if (!b_.contact_block[block_]) return;
    for (int c = 0; c < 3; ++c) {
      Lane f, m;
      lanes::load(b_.contact_force[c].data() + first_, f);
      lanes::load(b_.contact_torque[c].data() + first_, m);
      force[c] += f;
      torque[c] += m;
    }
  }

  // The eight motion classes packed in two words: 0 (all free, the common case) keeps the
  // defaults.
  [[gnu::always_inline]] bool load_motion(LaneMotion<Lane>& m) const {
    std::uint64_t classes[2];
    static_assert(sizeof classes == lanes::kCount * sizeof(MotionIndex));
    std::memcpy(classes, a_.motion + first_, sizeof classes);
    m.counts_free = Mask{} - 1;
    if ((classes[0] | classes[1]) == 0) return false;
    for (int l = 0; l < lanes::kCount; ++l) {
      const MotionClass& motion = a_.classes[a_.motion[first_ + l]];
      for (int c = 0; c < 3; ++c) {
        m.fix_velocity[c][l] = motion.fix_velocity[c];
        m.fix_angular_velocity[c][l] = motion.fix_angular_velocity[c];
        m.velocity[c][l] = motion.velocity[c];
        m.angular_velocity[c][l] = motion.angular_velocity[c];
      }
      m.counts_free[l] = motion.free;
    }
    return true;
  }

  [[gnu::always_inline]] void load_dynamics(Lane& inverse_mass, Lane& inverse_inertia, Lane (&v)[3],
                                            Lane (&omega)[3]) const {
    lanes::load(a_.inverse_mass + first_, inverse_mass);
    lanes::load(a_.inverse_inertia + first_, inverse_inertia);
    for (int c = 0; c < 3; ++c) {
      lanes::load(a_.velocity[c] + first_, v[c]);
      lanes::load(a_.angular_velocity[c] + first_, omega[c]);
    }
  }

  // The other buffer and the velocities, which the state the step reads does not alias.
  [[gnu::always_inline]] void store_state(const Lane (&u)[3], const Lane (&t)[3],
                                          const Lane (&v)[3], const Lane (&omega)[3]) const {
    const int out = 1 - b_.parity;
    for (int c = 0; c < 3; ++c) {
      lanes::store(a_.displacement[out][c] + first_, u[c]);
      lanes::store(a_.rotation[out][c] + first_, t[c]);
      lanes::store(a_.velocity[c] + first_, v[c]);
      lanes::store(a_.angular_velocity[c] + first_, omega[c]);
    }
  }

  [[gnu::always_inline]] void add_account(const StepSums<Lane>& s, bool prescribed) const {
    Lane sum;
    lanes::load(a_.damping_sum + first_, sum);
    sum += s.damping_sum;
    lanes::store(a_.damping_sum + first_, sum);
    if (prescribed) {
      lanes::load(a_.work_sum + first_, sum);
      sum += s.work_sum;
      lanes::store(a_.work_sum + first_, sum);
    }
  }

  [[gnu::always_inline]] void report(const ParticleReport<Lane>& r) const {
    for (int c = 0; c < 3; ++c) {
      lanes::store(a_.force[c] + first_, r.force[c]);
      lanes::store(a_.torque[c] + first_, r.torque[c]);
    }
    const std::size_t padded = static_cast<std::size_t>(b_.bonds->padded_count());
    for (int q = 0; q < kParticlePartials; ++q)
      lanes::store(a_.partial + q * padded + first_, r.partial[q]);
  }

 private:
  const BlockPass& b_;
  const KernelView& a_;
  int block_;
  int first_;
  GatherState state_;
};

template <bool kReport, int kMode>
[[gnu::always_inline]] inline void step_range(const BlockPass& b, int begin_block, int end_block) {
  for (int block = begin_block; block < end_block; ++block) {
    BlockLayout layout(b, block);
    step_particle<kReport, kMode>(layout);
  }
}

// One function per mode and report flag, each compiled for the three instruction sets: the
// register allocator sees one step at a time (in one function holding all ten, GCC 12 spilled more
// of each step's vectors: the elastic layer ran about 5% slower, the breaking coupon 7%).
template <bool kReport, int kMode>
PLYDEM_TARGET_CLONES void step_blocks_in_mode(const BlockPass& b, int begin_block, int end_block) {
  step_range<kReport, kMode>(b, begin_block, end_block);
}

template <int kMode>
void step_mode(const BlockPass& b, bool report, int begin_block, int end_block) {
  if (report) {
    step_blocks_in_mode<true, kMode>(b, begin_block, end_block);
  } else {
    step_blocks_in_mode<false, kMode>(b, begin_block, end_block);
  }
}

void step_blocks(int mode, const BlockPass& b, bool report, int begin_block, int end_block) {
  switch (mode) {
    case kBrittleTypes:
      return step_mode<kBrittleTypes>(b, report, begin_block, end_block);
    case kBrittleSlots:
      return step_mode<kBrittleSlots>(b, report, begin_block, end_block);
    case kSofteningTypes:
      return step_mode<kSofteningTypes>(b, report, begin_block, end_block);
    case kSofteningSlots:
      return step_mode<kSofteningSlots>(b, report, begin_block, end_block);
    default:
      return step_mode<kElasticMode>(b, report, begin_block, end_block);
  }
}

// The blocks blocks[begin .. end) (increasing), stepped run by run of consecutive blocks.
void step_listed_blocks(int mode, const BlockPass& b, bool report, const std::vector<int>& blocks,
                        int begin, int end) {
  int k = begin;
  while (k < end) {
    const int first = blocks[static_cast<std::size_t>(k)];
    int last = first + 1;
    for (++k; k < end && blocks[static_cast<std::size_t>(k)] == last; ++k) ++last;
    step_blocks(mode, b, report, first, last);
  }
}

// Below this many blocks per thread a cycle is too short to share.
constexpr int kMinBlocksPerThread = 32;

// How the blocks are shared between the MPI ranks (file comment): the partition of the model's
// particles (each particle owned by its block's rank), the exchange, and the blocks' owners.
struct BlockSplit {
  RankPartition part;
  std::unique_ptr<RankExchange> exchange;
  std::vector<int> block_owner;  // per block
  std::vector<int> own_blocks;   // increasing
  std::vector<int> all;          // 0 .. particles - 1

  std::size_t bytes() const {
    return part.bytes() + sizeof(int) * (block_owner.size() + own_blocks.size() + all.size());
  }
};

class CpuBackend final : public KernelOrderBackend {
 public:
  explicit CpuBackend(const BackendSetup& setup) : KernelOrderBackend(setup) {
    if (setup.split_between_ranks) split_between_ranks();
  }

  ExplicitBackend kind() const override { return ExplicitBackend::kCpu; }
  bool supports_contacts(std::string* why) const override {
    if (!split_) return true;
    if (why) *why = no_contacts_across_ranks(split_->part.size);
    return false;
  }
  CycleBatch run_cycles(long cycles, bool report_last, const CycleStep& step) override;
  std::size_t bytes() const override {
    return KernelOrderBackend::bytes() + (split_ ? split_->bytes() : 0);
  }

  // On N ranks, what the run loop reads comes from the ranks that step it.
  void store() override;
  void gather(std::span<const int> particles, Particles& into, StateAt at) const override;
  double state(int i, int c, bool rotation) const override;
  std::array<BondEnd, 2> bond_ends(int bond) const override;
  void store_bonds(Bonds& bonds, Eigen::ArrayXd& kappa) const override;
  AccountArrays account() const override;
  const RankPartition* partition() const override { return split_ ? &split_->part : nullptr; }

 private:
  BlockPass block_pass(const KernelView& a, const CycleStep& step);
  // The contacts' pass at the state of buffer `parity`, into the contact arrays.
  void apply_contacts(UnbondedContacts& contacts, int parity, double dt);
  // After a batch that began at buffer `first_parity` and ran `ran` of `cycles` cycles: the
  // current buffer, and the batch with the threads' damage steps (the report not yet stored).
  CycleBatch finish_batch(int first_parity, long cycles, long ran, bool report_last);

  // On N ranks:
  void split_between_ranks();
  CycleBatch run_split_cycles(long cycles, bool report_last, const CycleStep& step);
  // The ghosts' displacements and rotations in buffer `buffer` from their owners.
  void exchange_ghosts(int buffer);
  // Every rank's damage steps, on every rank.
  void share_events(std::vector<SlotEvent>& events) const;
  // The model's forces from the owners, and the sums of every block in block order.
  void store_split_report(CycleBatch& batch);
  // The 12 state values of kernel particle j, buffer `buffer` (unpack_particle_state's order).
  void pack_kernel_state(int j, int buffer, double* row) const;

  std::vector<std::vector<SlotEvent>> thread_events_;
  std::vector<int> changed_flags_;
  std::unique_ptr<BlockSplit> split_;
};

void CpuBackend::apply_contacts(UnbondedContacts& contacts, int parity, double dt) {
  ContactForces out;
  for (int c = 0; c < 3; ++c) {
    out.force[c] = contact_force_[c].data();
    out.torque[c] = contact_torque_[c].data();
  }
  for (int i : contacts.touched()) contact_block_[static_cast<std::size_t>(i / lanes::kCount)] = 0;
  contacts.apply(state_at(parity), dt, out);
  for (int i : contacts.touched()) contact_block_[static_cast<std::size_t>(i / lanes::kCount)] = 1;
}

BlockPass CpuBackend::block_pass(const KernelView& a, const CycleStep& step) {
  BlockPass args;
  args.a = &a;
  args.bonds = &bonds_;  // the step clears slots through it
  args.dt = step.dt;
  args.alpha = step.alpha;
  if (breaking_) {
    args.contact_force = contact_force_;
    args.contact_torque = contact_torque_;
    args.contact_block = contact_block_.data();
  }
  return args;
}

CycleBatch CpuBackend::run_cycles(long cycles, bool report_last, const CycleStep& step) {
  if (split_) return run_split_cycles(cycles, report_last, step);
  const KernelView a = view();
  const BlockPass args = block_pass(a, step);
  const int kernel_mode = mode();
  const int blocks = blocks_;
  const int first_parity = parity_;
  const bool breaking = breaking_;
  UnbondedContacts* contacts =
      step.contacts && !step.contacts->contacts().empty() ? step.contacts : nullptr;
  // Each thread raises its flag for the cycle's parity when a slot of its blocks broke or
  // softened; after the cycle's barrier every thread reads all flags alike, so all stop after the
  // same cycle (its steps are resolved against the next state, and the contacts of its breaks
  // added, before the next cycle). A flag of parity q is written again two cycles later, after
  // every thread has passed the barrier that follows its reads.
  constexpr int kFlagStride = 16;  // one cache line per flag
  const int max_threads = omp_get_max_threads();
  if (breaking) {
    thread_events_.resize(static_cast<std::size_t>(max_threads));
    for (auto& e : thread_events_) e.clear();
    changed_flags_.assign(static_cast<std::size_t>(2 * max_threads * kFlagStride), 0);
  }
  long ran = cycles;
#pragma omp parallel if (blocks >= 2 * kMinBlocksPerThread)
  {
    const long threads = omp_get_num_threads();
    const long thread = omp_get_thread_num();
    const int begin = static_cast<int>(blocks * thread / threads);
    const int end = static_cast<int>(blocks * (thread + 1) / threads);
    BlockPass mine = args;
    BreakingPass pass;
    if (breaking) pass.events = &thread_events_[static_cast<std::size_t>(thread)];
    mine.pass = &pass;
    for (long s = 0; s < cycles; ++s) {
      mine.parity = static_cast<int>((first_parity + s) & 1);
      const bool report = report_last && s + 1 == cycles;
      if (contacts) {
#pragma omp single
        apply_contacts(*contacts, mine.parity, step.dt);
      }
      pass.cycle = step.first_cycle + s;
      pass.changed = false;
      step_blocks(kernel_mode, mine, report, begin, end);
      const std::size_t flags = static_cast<std::size_t>(s & 1) * max_threads;
      if (breaking) changed_flags_[(flags + thread) * kFlagStride] = pass.changed ? 1 : 0;
#pragma omp barrier
      if (breaking) {
        bool any = false;
        for (long t = 0; t < threads; ++t) any |= changed_flags_[(flags + t) * kFlagStride] != 0;
        if (any) {
          if (thread == 0) ran = s + 1;
          break;
        }
      }
    }
  }
  CycleBatch batch = finish_batch(first_parity, cycles, ran, report_last);
  if (batch.reported) store_report(batch, true);
  return batch;
}

CycleBatch CpuBackend::finish_batch(int first_parity, long cycles, long ran, bool report_last) {
  parity_ = static_cast<int>((first_parity + ran) & 1);
  CycleBatch batch;
  batch.cycles = ran;
  batch.reported = report_last && ran == cycles;
  if (breaking_) {
    for (auto& thread : thread_events_) {
      batch.events.insert(batch.events.end(), thread.begin(), thread.end());
      thread.clear();
    }
  }
  return batch;
}

void CpuBackend::split_between_ranks() {
  split_ = std::make_unique<BlockSplit>();
  BlockSplit& s = *split_;
  const int size = mpi_size();
  const std::vector<int> slice = slice_owners(model_, size);
  s.block_owner.resize(static_cast<std::size_t>(blocks_));
  for (int b = 0; b < blocks_; ++b)
    s.block_owner[static_cast<std::size_t>(b)] =
        slice[static_cast<std::size_t>(order_[static_cast<std::size_t>(b * lanes::kCount)])];
  std::vector<int> owner(static_cast<std::size_t>(particles_));
  for (int i = 0; i < particles_; ++i)
    owner[static_cast<std::size_t>(i)] = s.block_owner[static_cast<std::size_t>(
        position_[static_cast<std::size_t>(i)] / lanes::kCount)];
  s.part = partition_with_owners(model_, std::move(owner), mpi_rank(), size);
  s.exchange = make_rank_exchange(s.part);
  for (int b = 0; b < blocks_; ++b)
    if (s.block_owner[static_cast<std::size_t>(b)] == s.part.rank) s.own_blocks.push_back(b);
  s.all.resize(static_cast<std::size_t>(particles_));
  std::iota(s.all.begin(), s.all.end(), 0);
}

CycleBatch CpuBackend::run_split_cycles(long cycles, bool report_last, const CycleStep& step) {
  const KernelView a = view();
  const BlockPass args = block_pass(a, step);
  const int kernel_mode = mode();
  const std::vector<int>& own = split_->own_blocks;
  const int count = static_cast<int>(own.size());
  const int first_parity = parity_;
  const bool breaking = breaking_;
  if (breaking) {
    thread_events_.resize(static_cast<std::size_t>(omp_get_max_threads()));
    for (auto& e : thread_events_) e.clear();
  }
  // Each cycle: the own blocks between the threads, then the ghosts from their owners (on this
  // thread: the MPI calls stay on the one that started MPI); a damage step on any rank stops
  // every rank after that cycle, as a thread's does on one rank.
  long ran = cycles;
  bool stopped = false;
  for (long s = 0; s < cycles; ++s) {
    const int parity = static_cast<int>((first_parity + s) & 1);
    const bool report = report_last && s + 1 == cycles;
    bool changed = false;
#pragma omp parallel if (count >= 2 * kMinBlocksPerThread) reduction(|| : changed)
    {
      const long threads = omp_get_num_threads();
      const long thread = omp_get_thread_num();
      BlockPass mine = args;
      mine.parity = parity;
      BreakingPass pass;
      if (breaking) pass.events = &thread_events_[static_cast<std::size_t>(thread)];
      pass.cycle = step.first_cycle + s;
      mine.pass = &pass;
      step_listed_blocks(kernel_mode, mine, report, own, static_cast<int>(count * thread / threads),
                         static_cast<int>(count * (thread + 1) / threads));
      changed = changed || pass.changed;
    }
    exchange_ghosts(1 - parity);
    if (breaking && split_->exchange->any_rank(changed)) {
      ran = s + 1;
      stopped = true;
      break;
    }
  }
  CycleBatch batch = finish_batch(first_parity, cycles, ran, report_last);
  if (stopped) share_events(batch.events);  // no rank has any otherwise
  if (batch.reported) store_split_report(batch);
  return batch;
}

void CpuBackend::exchange_ghosts(int buffer) {
  auto& u = arrays_.displacement[buffer];
  auto& theta = arrays_.rotation[buffer];
  split_->exchange->update_ghosts(
      [&](int i, double* row) {
        const auto j = static_cast<std::size_t>(position_[static_cast<std::size_t>(i)]);
        for (int c = 0; c < 3; ++c) {
          row[c] = u[c].data()[j];
          row[3 + c] = theta[c].data()[j];
        }
      },
      [&](int i, const double* row) {
        const auto j = static_cast<std::size_t>(position_[static_cast<std::size_t>(i)]);
        for (int c = 0; c < 3; ++c) {
          u[c].data()[j] = row[c];
          theta[c].data()[j] = row[3 + c];
        }
      });
}

void CpuBackend::share_events(std::vector<SlotEvent>& events) const {
  const std::vector<char> all = split_->exchange->gather_bytes(std::span<const char>(
      reinterpret_cast<const char*>(events.data()), events.size() * sizeof(SlotEvent)));
  events.resize(all.size() / sizeof(SlotEvent));
  std::memcpy(events.data(), all.data(), all.size());
}

void CpuBackend::store_split_report(CycleBatch& batch) {
  const BlockSplit& s = *split_;
  Particles& p = model_.particles;
  share_particle_rows(
      s.part, *s.exchange, s.all, 6,
      [&](int i, double* row) {
        const auto j = static_cast<std::size_t>(position_[static_cast<std::size_t>(i)]);
        for (int c = 0; c < 3; ++c) {
          row[c] = arrays_.force[c].data()[j];
          row[3 + c] = arrays_.torque[c].data()[j];
        }
      },
      [&](int i, const double* row) {
        for (int c = 0; c < 3; ++c) {
          p.force(i, c) = row[c];
          p.torque(i, c) = row[3 + c];
        }
      });
  // Each block's sums from its rank, then summed block by block as on one rank.
  std::vector<double> mine;
  mine.reserve(kParticlePartials * s.own_blocks.size());
  for (int b : s.own_blocks)
    for (int q = 0; q < kParticlePartials; ++q)
      mine.push_back(block_partial(arrays_.partial.data(), padded_, q, b));
  std::vector<std::size_t> at;
  const std::vector<double> all = s.exchange->gather_all(mine, at);
  double sums[kParticlePartials] = {};
  for (int b = 0; b < blocks_; ++b) {
    std::size_t& next = at[static_cast<std::size_t>(s.block_owner[static_cast<std::size_t>(b)])];
    for (int q = 0; q < kParticlePartials; ++q) sums[q] += all[next + static_cast<std::size_t>(q)];
    next += kParticlePartials;
  }
  std::copy(sums, sums + kParticlePartials, batch.sums);
}

void CpuBackend::pack_kernel_state(int j, int buffer, double* row) const {
  const auto k = static_cast<std::size_t>(j);
  for (int c = 0; c < 3; ++c) {
    row[c] = arrays_.displacement[buffer][c].data()[k];
    row[3 + c] = arrays_.rotation[buffer][c].data()[k];
    row[6 + c] = arrays_.velocity[c].data()[k];
    row[9 + c] = arrays_.angular_velocity[c].data()[k];
  }
}

void CpuBackend::store() {
  if (!split_) return KernelOrderBackend::store();
  gather(split_->all, model_.particles, StateAt::kCurrent);
  running_ = false;
}

void CpuBackend::gather(std::span<const int> particles, Particles& into, StateAt at) const {
  if (!split_) return KernelOrderBackend::gather(particles, into, at);
  const int buffer = at == StateAt::kCurrent ? parity_ : 1 - parity_;
  share_particle_rows(
      split_->part, *split_->exchange, particles, 12,
      [&](int i, double* row) {
        pack_kernel_state(position_[static_cast<std::size_t>(i)], buffer, row);
      },
      [&](int i, const double* row) { unpack_particle_state(into, i, row); });
}

double CpuBackend::state(int i, int c, bool rotation) const {
  const double value = KernelOrderBackend::state(i, c, rotation);
  if (!split_) return value;
  const int owner = split_->part.owner[static_cast<std::size_t>(i)];
  return split_->exchange->broadcast(owner == split_->part.rank ? value : 0.0, owner);
}

std::array<BondEnd, 2> CpuBackend::bond_ends(int bond) const {
  std::array<BondEnd, 2> ends = KernelOrderBackend::bond_ends(bond);
  if (!split_ || !breaking_) return ends;
  // Each end as the rank that steps its particle holds it.
  const int particle[2] = {model_.bonds.first(bond), model_.bonds.second(bond)};
  for (int e = 0; e < 2; ++e) {
    const int owner = split_->part.owner[static_cast<std::size_t>(particle[e])];
    const bool mine = owner == split_->part.rank;
    const RankExchange& x = *split_->exchange;
    ends[e].holds = x.broadcast(mine && ends[e].holds ? 1.0 : 0.0, owner) != 0;
    ends[e].damage = x.broadcast(mine ? ends[e].damage : 0.0, owner);
    ends[e].kappa = x.broadcast(mine ? ends[e].kappa : 0.0, owner);
  }
  return ends;
}

void CpuBackend::store_bonds(Bonds& bonds, Eigen::ArrayXd& kappa) const {
  if (!split_) return KernelOrderBackend::store_bonds(bonds, kappa);
  if (!breaking_) return;
  // Every bond's two ends from the ranks that step them: three values per end, packed bond by
  // bond (first end, then second) where this rank owns the end's particle.
  const BlockSplit& s = *split_;
  const Bonds& model_bonds = model_.bonds;
  auto owner_of_end = [&](int b, int e) {
    return s.part
        .owner[static_cast<std::size_t>(e == 0 ? model_bonds.first(b) : model_bonds.second(b))];
  };
  std::vector<double> mine;
  for (int b = 0; b < model_bonds.size(); ++b) {
    const std::array<BondEnd, 2> ends = KernelOrderBackend::bond_ends(b);
    for (int e = 0; e < 2; ++e)
      if (owner_of_end(b, e) == s.part.rank)
        mine.insert(mine.end(), {ends[e].holds ? 1.0 : 0.0, ends[e].damage, ends[e].kappa});
  }
  std::vector<std::size_t> at;
  const std::vector<double> all = s.exchange->gather_all(mine, at);
  std::vector<std::array<BondEnd, 2>> shared(static_cast<std::size_t>(model_bonds.size()));
  for (int b = 0; b < model_bonds.size(); ++b) {
    for (int e = 0; e < 2; ++e) {
      std::size_t& next = at[static_cast<std::size_t>(owner_of_end(b, e))];
      shared[static_cast<std::size_t>(b)][static_cast<std::size_t>(e)] = {
          all[next] != 0, all[next + 1], all[next + 2]};
      next += 3;
    }
  }
  write_bonds(bonds, kappa, [&](int b) { return shared[static_cast<std::size_t>(b)]; });
}

AccountArrays CpuBackend::account() const {
  AccountArrays a = KernelOrderBackend::account();
  if (!split_ || !breaking_) return a;
  share_particle_rows(
      split_->part, *split_->exchange, split_->all, 2,
      [&](int i, double* row) {
        const auto j = static_cast<std::size_t>(position_[static_cast<std::size_t>(i)]);
        row[0] = arrays_.work_sum.data()[j];
        row[1] = arrays_.damping_sum.data()[j];
      },
      [&](int i, const double* row) {
        a.work(i) = row[0];
        a.damping(i) = row[1];
      });
  return a;
}

}  // namespace

std::unique_ptr<KernelBackend> make_cpu_backend(const BackendSetup& setup) {
  return std::make_unique<CpuBackend>(setup);
}

}  // namespace plydem
