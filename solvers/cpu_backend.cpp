// The host's SIMD backend (solvers/explicit_backend.hpp): the kernel-order state of
// solvers/kernel_order_backend.hpp, each block of eight particles running step_particle
// (solvers/particle_step.hpp) in the lanes of a vector (BlockLayout), the blocks split between
// OpenMP threads (OMP_NUM_THREADS). Each particle sums its own bonds, so its result does not
// depend on the thread count, and a run is bitwise reproducible on any number of threads.
#include <omp.h>

#include <cstdint>
#include <cstring>
#include <limits>

#include "core/error.hpp"
#include "solvers/kernel_order_backend.hpp"
#include "solvers/particle_step.hpp"

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

// Below this many blocks per thread a cycle is too short to share.
constexpr int kMinBlocksPerThread = 32;

class CpuBackend final : public KernelOrderBackend {
 public:
  using KernelOrderBackend::KernelOrderBackend;

  ExplicitBackend kind() const override { return ExplicitBackend::kCpu; }
  bool supports_contacts(std::string*) const override { return true; }
  CycleBatch run_cycles(long cycles, bool report_last, const CycleStep& step) override;

 private:
  // The contacts' pass at the state of buffer `parity`, into the contact arrays.
  void apply_contacts(UnbondedContacts& contacts, int parity, double dt);

  std::vector<std::vector<SlotEvent>> thread_events_;
  std::vector<int> changed_flags_;
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

CycleBatch CpuBackend::run_cycles(long cycles, bool report_last, const CycleStep& step) {
  const KernelView a = view();
  BlockPass args;
  args.a = &a;
  args.bonds = &bonds_;
  args.dt = step.dt;
  args.alpha = step.alpha;
  if (breaking_) {
    args.contact_force = contact_force_;
    args.contact_torque = contact_torque_;
    args.contact_block = contact_block_.data();
  }
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
  parity_ = static_cast<int>((first_parity + ran) & 1);
  CycleBatch batch;
  batch.cycles = ran;
  batch.reported = report_last && ran == cycles;
  if (breaking) {
    for (auto& thread : thread_events_) {
      batch.events.insert(batch.events.end(), thread.begin(), thread.end());
      thread.clear();
    }
  }
  if (batch.reported) store_report(batch, true);
  return batch;
}

}  // namespace

std::unique_ptr<KernelBackend> make_cpu_backend(const BackendSetup& setup) {
  return std::make_unique<CpuBackend>(setup);
}

}  // namespace plydem
