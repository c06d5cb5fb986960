// A run gives the same bits on 1, 2 and 4 OpenMP threads: the tension test's explicit paths (the
// fixed-cycle mode, whose local damping carries any difference in the last bit of the model to
// 1e-3 in the moduli, and the staged mode relaxed to quasi-static), its static path, and a breaking
// run. The model is built inside each thread scope, so that its calibration and edge balancing are
// held to the same rule as the kernel.
#include <doctest/doctest.h>

#include <cstring>
#include <vector>

#include "core/material.hpp"
#include "experiments/protocols/tension.hpp"
#include "support/threads.hpp"

using namespace plydem;

namespace {

using plydem::test::Threads;

bool same_bits(double a, double b) {
  return std::memcmp(&a, &b, sizeof a) == 0;
}

bool same_bits(const std::vector<double>& a, const std::vector<double>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i)
    if (!same_bits(a[i], b[i])) return false;
  return true;
}

void check_same_pull(const PullResult& a, const PullResult& b) {
  CHECK(a.cycles == b.cycles);
  CHECK(same_bits(a.time_step, b.time_step));
  CHECK(same_bits(a.strain, b.strain));
  CHECK(same_bits(a.lateral_strain, b.lateral_strain));
  CHECK(same_bits(a.shear_strain, b.shear_strain));
  CHECK(same_bits(a.stress, b.stress));
  CHECK(same_bits(a.modulus, b.modulus));
  CHECK(same_bits(a.poisson, b.poisson));
  CHECK(same_bits(a.final_ratio, b.final_ratio));
}

// The coupon: 2.4 x 0.8 mm of the paper's ply at its 0.05 mm particles, about 700 particles, 88
// blocks of eight, which the kernel splits between threads (it keeps fewer than 64 on one).
TensionSettings small_coupon(TensionSolver solver) {
  TensionSettings s;
  s.coupon.material = load_material("eglass-my750");
  s.coupon.ply_angle = 0.5;  // off-axis: every bond family and the shear coupling are loaded
  s.coupon.length = 2.4e-3;
  s.coupon.width = 0.8e-3;
  s.solver = solver;
  s.measure_specimen_stiffness = false;
  return s;
}

void check_same_on_1_2_4_threads(const TensionSettings& settings) {
  std::vector<TensionResult> runs;
  for (int threads : {1, 2, 4}) {
    Threads scope(threads);
    runs.push_back(TensionTest(settings).run());
  }
  REQUIRE(runs[0].along_x.particles > 512);
  for (int t = 1; t < 3; ++t) {
    CAPTURE(t);
    check_same_pull(runs[0].along_x, runs[t].along_x);
    check_same_pull(runs[0].along_y, runs[t].along_y);
    CHECK(same_bits(runs[0].dem.Ex, runs[t].dem.Ex));
    CHECK(same_bits(runs[0].dem.nu_xy, runs[t].dem.nu_xy));
  }
}

}  // namespace

TEST_CASE("explicit fixed-cycle tension gives the same bits on 1, 2 and 4 threads") {
  TensionSettings s = small_coupon(TensionSolver::kExplicit);
  s.fixed_cycles = 1500;
  check_same_on_1_2_4_threads(s);
}

TEST_CASE("explicit staged tension gives the same bits on 1, 2 and 4 threads") {
  TensionSettings s = small_coupon(TensionSolver::kExplicit);
  s.load_stages = 1;
  check_same_on_1_2_4_threads(s);
}

TEST_CASE("static tension gives the same bits on 1, 2 and 4 threads") {
  check_same_on_1_2_4_threads(small_coupon(TensionSolver::kStatic));
}
