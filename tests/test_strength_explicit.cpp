// The strength test's explicit method at the material point (`plydem strength --method explicit`,
// solvers/explicit_failure.hpp): the same failure model as the events method, run by damped
// dynamics. Its peaks (XT, YT, XC, YC, S12) against the material's strengths and the events
// method's, the one crack of a uniform 90 deg coupon, a notched coupon's crack pattern beside the
// events method's (folded about the hole's centre lines), the same bits on 1 and 2 threads and on
// the device kernel's code (emulation), and its refusals.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "core/error.hpp"
#include "core/material.hpp"
#include "experiments/protocols/strength.hpp"
#include "support/test_support.hpp"
#include "support/threads.hpp"

using namespace plydem;
using namespace plydem::test;

namespace {

// Square, 3 x 1 mm, 0.1 mm particles, Puck (the material point's coupon of
// test_strength_command).
StrengthSettings coupon(const Material& material, double angle_deg, StrengthLoad load,
                        StrengthMethod method) {
  StrengthSettings s;
  s.coupon.material = material;
  s.coupon.ply_angle = angle_deg * kDeg;
  s.coupon.length = 3e-3;
  s.coupon.width = 1e-3;
  s.coupon.particle_diameter = 0.1e-3;
  s.failure_criterion = PlyFailureModel::kPuck;
  s.load = load;
  s.method = method;
  return s;
}

// The sites that cracked, in the order they did.
std::set<int> cracked_sites(const StrengthResult& r) {
  std::set<int> sites;
  for (const EventPoint& p : r.path)
    if (p.site >= 0) sites.insert(p.site);
  return sites;
}

// The material's strength along the load at 0 or 90 deg.
double target_strength(const LaminaStrength& st, double angle_deg, StrengthLoad load) {
  if (load == StrengthLoad::kShear) return st.S12;
  const bool tension = load == StrengthLoad::kTension;
  if (angle_deg == 0) return tension ? st.XT : st.XC;
  return tension ? st.YT : st.YC;
}

// Where `sites` lie folded into one quarter of the coupon about the hole's centre lines (in units
// of 0.1 um): the coupon and its load are symmetric about both, and each ligament may crack on
// either side of the hole, so a crack and its mirror images are the same pattern.
std::set<std::pair<long, long>> folded(const std::set<int>& sites, const Model& model,
                                       const Eigen::Vector2d& centre) {
  const Particles& p = model.particles;
  std::set<std::pair<long, long>> at;
  for (int site : sites)
    at.insert({std::lround(std::abs(p.reference_position(site, 0) - centre(0)) / 1e-7),
               std::lround(std::abs(p.reference_position(site, 1) - centre(1)) / 1e-7)});
  return at;
}

// Each (angle [deg], load) of the five strengths.
using StrengthCases = std::vector<std::pair<double, StrengthLoad>>;
const StrengthCases kFiveStrengths{{0.0, StrengthLoad::kTension},
                                   {90.0, StrengthLoad::kTension},
                                   {0.0, StrengthLoad::kCompression},
                                   {90.0, StrengthLoad::kCompression},
                                   {0.0, StrengthLoad::kShear}};

// The strengths `cases` of `material` by the explicit method: peaks against the targets and the
// events method's.
void check_five_strengths(const Material& material, const StrengthCases& cases = kFiveStrengths) {
  {
    for (const auto& test_case : cases) {
      // Named copies, not structured bindings: Clang 14's lambdas (CAPTURE) cannot see those.
      const double angle = test_case.first;
      const StrengthLoad load = test_case.second;
      CAPTURE(material.name);
      CAPTURE(angle);
      const std::string load_name = strength_load_name(load);
      CAPTURE(load_name);
      const StrengthResult events =
          StrengthTest(coupon(material, angle, load, StrengthMethod::kEvents)).run();
      const StrengthResult dynamics =
          StrengthTest(coupon(material, angle, load, StrengthMethod::kExplicit)).run();
      const double target = target_strength(material.strength, angle, load);
      MESSAGE(material.name << " " << angle << " deg " << load_name << ": explicit peak / target "
                            << (dynamics.strength / target) << ", / events peak "
                            << (dynamics.strength / events.strength) << ", "
                            << dynamics.cracked_sites << " sites (events " << events.cracked_sites
                            << ")");
      // A frame-held coupon in shear keeps a residual load: it ends past the peak.
      CHECK(dynamics.stop == (load == StrengthLoad::kShear ? "past the peak" : "failed"));
      CHECK(dynamics.strength == doctest::Approx(target).epsilon(0.02));
      CHECK(dynamics.strength == doctest::Approx(events.strength).epsilon(0.03));
      REQUIRE(!dynamics.path.empty());
      if (load == StrengthLoad::kShear) {
        // Pure tau12 leaves sigma2 at rounding: Puck's modes A and B both give S12 there.
        for (const StrengthResult* r : {&events, &dynamics}) {
          const PlyFailureMode mode = r->path.front().site_mode;
          CHECK((mode == PlyFailureMode::kMatrixTension ||
                 mode == PlyFailureMode::kMatrixCompression));
        }
      } else {
        CHECK(dynamics.path.front().site_mode == events.path.front().site_mode);
      }
      if (angle == 90 && load == StrengthLoad::kTension) {
        // One crack across the width: every cracked site in one column of particles.
        const Particles& p = dynamics.model->particles;
        double x_min = 1, x_max = -1;
        for (int site : cracked_sites(dynamics)) {
          x_min = std::min(x_min, p.reference_position(site, 0));
          x_max = std::max(x_max, p.reference_position(site, 0));
        }
        CHECK(x_max - x_min < 0.5 * 0.1e-3);
        CHECK(dynamics.cracked_sites >= 10);  // the width's 10 rows
      }
    }
  }
}

}  // namespace

// E-glass's five strengths: shear in both builds, the rest in the release build only (label slow;
// the sanitizer build keeps the tension path in the same-bits case below, at 60 deg, which cracks
// in mixed mode, and the inclined compression plane by the events method in
// test_strength_command.cpp).
TEST_CASE("explicit method at the material point: the S12 peak, as the events method") {
  check_five_strengths(eglass(), {{0.0, StrengthLoad::kShear}});
}

TEST_CASE("slow: explicit method at the material point: XT, YT, XC and YC peaks, as events") {
  check_five_strengths(eglass(), {{0.0, StrengthLoad::kTension},
                                  {90.0, StrengthLoad::kTension},
                                  {0.0, StrengthLoad::kCompression},
                                  {90.0, StrengthLoad::kCompression}});
}

// The carbon ply's, in the release build only (label slow): the same code path as E-glass's.
TEST_CASE("slow: explicit method at the material point: a carbon ply's five strengths") {
  check_five_strengths(carbon_ply());
}

// In the release build only (label slow): a 4 x 2 mm coupon twice by each method.
TEST_CASE("slow: explicit method at the material point: a notched coupon cracks where events do") {
  // A 0.6 mm hole in a 4 x 2 mm coupon: the sites that crack by each method, their overlap.
  for (double angle : {90.0, 30.0}) {
    CAPTURE(angle);
    StrengthSettings s = coupon(eglass(), angle, StrengthLoad::kTension, StrengthMethod::kEvents);
    s.coupon.length = 4e-3;
    s.coupon.width = 2e-3;
    s.hole_diameter = 0.6e-3;
    const StrengthResult events = StrengthTest(s).run();
    s.method = StrengthMethod::kExplicit;
    const StrengthResult dynamics = StrengthTest(s).run();
    const auto a = folded(cracked_sites(events), *events.model, events.hole_centre);
    const auto b = folded(cracked_sites(dynamics), *dynamics.model, dynamics.hole_centre);
    std::vector<std::pair<long, long>> both, either;
    std::set_intersection(a.begin(), a.end(), b.begin(), b.end(), std::back_inserter(both));
    std::set_union(a.begin(), a.end(), b.begin(), b.end(), std::back_inserter(either));
    const double overlap = static_cast<double>(both.size()) / static_cast<double>(either.size());
    MESSAGE("notched, " << angle << " deg: explicit peak / events peak "
                        << (dynamics.strength / events.strength) << "; sites "
                        << dynamics.cracked_sites << " (events " << events.cracked_sites << "), "
                        << both.size() << " of " << either.size() << " places in both");
    CHECK(dynamics.strength == doctest::Approx(events.strength).epsilon(0.03));
    CHECK(overlap > 0.6);
  }
}

TEST_CASE(
    "explicit method at the material point: the same bits on 1 and 2 threads and on the device's "
    "code") {
  // The device's kernel (emulation: the CUDA backend's code run on the host) computes the cpu
  // backend's bits; a faster loading keeps the emulation short.
  StrengthSettings s = coupon(eglass(), 60, StrengthLoad::kTension, StrengthMethod::kExplicit);
  s.explicit_loading.cycles_to_failure = 4000;
  StrengthResult one, two, device;
  {
    Threads t(1);
    one = StrengthTest(s).run();
  }
  {
    Threads t(2);
    two = StrengthTest(s).run();
  }
  s.explicit_settings.backend = ExplicitBackend::kDeviceEmulation;
  device = StrengthTest(s).run();
  for (const StrengthResult* r : {&two, &device}) {
    CHECK(one.strength == r->strength);
    CHECK(one.stress == r->stress);
    CHECK(one.strain == r->strain);
    CHECK(cracked_sites(one) == cracked_sites(*r));
  }
  CHECK(one.cracked_sites > 0);
}

TEST_CASE("explicit method: what it does not do is refused by name") {
  auto refusal = [](const StrengthSettings& s) {
    try {
      StrengthTest(s).run();
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  StrengthSettings s = coupon(eglass(), 90, StrengthLoad::kTension, StrengthMethod::kExplicit);
  StrengthSettings bond = s;
  bond.failure_criterion = PlyFailureModel::kBond;
  CHECK(refusal(bond).find("explicit method decides failure at the material point") !=
        std::string::npos);
  StrengthSettings softening = s;
  softening.coupon.material.strength.G_fibre = 50e3;
  softening.coupon.material.strength.G_matrix = 200;
  softening.strength_options.softening = true;
  CHECK(refusal(softening).find("events method only") != std::string::npos);
  StrengthSettings checkpoint = s;
  checkpoint.checkpoint.every = 5;
  checkpoint.checkpoint.file = "never_written.ckpt";
  CHECK(refusal(checkpoint).find("events method only") != std::string::npos);
  StrengthSettings fast = s;
  fast.explicit_loading.cycles_to_failure = 10;
  CHECK(refusal(fast).find("cycles_to_failure is 10") != std::string::npos);
}
