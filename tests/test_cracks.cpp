// Cracks as objects (solvers/cracks.hpp) on hand-built cases: bonds broken by hand along lines
// of a square coupon, counted, measured and told apart by ply.
#include <doctest/doctest.h>

#include <cmath>
#include <functional>
#include <numbers>

#include "core/error.hpp"
#include "core/transverse_cracking.hpp"
#include "solvers/cracks.hpp"
#include "strategies/laminate.hpp"
#include "strategies/registry.hpp"
#include "strategies/specimen.hpp"

using namespace plydem;

namespace {

constexpr double kMm = 1e-3;

// A 2 x 1 mm square-strategy coupon of 0.1 mm particles: 20 columns, 10 rows.
Model square_coupon() {
  CouponSpec spec;
  spec.material = load_material("eglass-my750");
  spec.length = 2 * kMm;
  spec.width = 1 * kMm;
  spec.particle_diameter = 0.1 * kMm;
  const std::unique_ptr<Strategy> square = default_registry().create("square");
  return SpecimenBuilder(*square).build(spec).model;
}

// Breaks (in this order, at event `at`) every bond for which `cut` holds.
void break_where(const Model& m, std::vector<BondBreak>& breaks, BondState mode, double at,
                 const std::function<bool(const Eigen::Vector3d&, const Eigen::Vector3d&)>& cut) {
  const Particles& p = m.particles;
  const Bonds& b = m.bonds;
  for (int k = 0; k < b.size(); ++k) {
    const Eigen::Vector3d xi = p.reference_position.row(b.first(k)).transpose();
    const Eigen::Vector3d xj = p.reference_position.row(b.second(k)).transpose();
    if (!cut(xi, xj)) continue;
    BondBreak r;
    r.bond = k;
    r.mode = mode;
    r.at = at;
    r.load = 10 * at;
    r.position = xi + b.lever_first(k) * b.normal.row(k).transpose().matrix();
    breaks.push_back(r);
  }
}

bool straddles(double a, double b, double x) {
  return std::min(a, b) < x && std::max(a, b) > x;
}

}  // namespace

TEST_CASE("cracks cut by hand are counted, measured and told apart") {
  const Model m = square_coupon();
  const double x0 = m.particles.reference_position.col(0).minCoeff() - 0.05 * kMm;
  const double y0 = m.particles.reference_position.col(1).minCoeff() - 0.05 * kMm;
  std::vector<BondBreak> breaks;
  // Half the width at x = 1.5 mm, in shear, first (event 2).
  break_where(m, breaks, BondState::kBrokenShear, 2, [&](auto& a, auto& b) {
    return straddles(a.x(), b.x(), x0 + 1.5 * kMm) && std::max(a.y(), b.y()) < y0 + 0.5 * kMm;
  });
  // Across the whole width at x = 0.5 mm, in tension (event 5).
  break_where(m, breaks, BondState::kBrokenTension, 5,
              [&](auto& a, auto& b) { return straddles(a.x(), b.x(), x0 + 0.5 * kMm); });
  // One horizontal bond of the top row at x = 1 mm (event 9).
  break_where(m, breaks, BondState::kBrokenTension, 9, [&](auto& a, auto& b) {
    return straddles(a.x(), b.x(), x0 + 1.0 * kMm) && std::abs(a.y() - b.y()) < 1e-9 &&
           a.y() > y0 + 0.9 * kMm;
  });
  const std::vector<Crack> cracks = find_cracks(m, breaks);
  REQUIRE(cracks.size() == 3);

  const Crack& half = cracks[0];
  CHECK(half.mode() == "shear");
  CHECK(half.first_at == 2);
  CHECK(half.first_load == 20);
  CHECK(half.bonds == 5 + 2 * 4);  // five rows' horizontal bonds, two diagonals per gap between
  CHECK(half.length == doctest::Approx(0.5 * kMm).epsilon(1e-9));
  CHECK(half.angle == doctest::Approx(std::numbers::pi / 2).epsilon(1e-9));
  CHECK(half.centroid.x() == doctest::Approx(x0 + 1.5 * kMm).epsilon(1e-9));

  const Crack& full = cracks[1];
  CHECK(full.mode() == "tension");
  CHECK(full.bonds == 10 + 2 * 9);
  CHECK(full.length == doctest::Approx(1.0 * kMm).epsilon(1e-9));  // the coupon's width
  CHECK(full.start.y() == doctest::Approx(y0 + 0.05 * kMm).epsilon(1e-9));
  CHECK(full.end.y() == doctest::Approx(y0 + 0.95 * kMm).epsilon(1e-9));

  const Crack& single = cracks[2];
  CHECK(single.bonds == 1);
  CHECK(single.length == doctest::Approx(0.1 * kMm).epsilon(1e-9));
  CHECK(single.angle == doctest::Approx(std::numbers::pi / 2).epsilon(1e-9));  // across its bond

  CHECK(crack_density(cracks, 0, x0, x0 + 2 * kMm) == doctest::Approx(3 / (2 * kMm)));
  CHECK(crack_density(cracks, 0, x0, x0 + 0.9 * kMm) == doctest::Approx(1 / (0.9 * kMm)));
  CHECK(crack_density(cracks, 1, x0, x0 + 2 * kMm) == 0);
  CHECK_THROWS_WITH_AS(crack_density(cracks, 0, 1, 1), doctest::Contains("is empty"), Error);

  // A link distance longer than the cracks' spacing joins them into one (mixed) crack.
  const std::vector<Crack> joined = find_cracks(m, breaks, 1.1 * kMm);
  REQUIRE(joined.size() == 1);
  CHECK(joined[0].mode() == "mixed");
  CHECK(joined[0].first_at == 2);

  const std::string csv = cracks_csv(cracks);
  CHECK(csv.rfind("id,kind,ply,x_mm,y_mm,z_mm,length_mm,angle_deg,bonds,tension,shear,mode,", 0) ==
        0);
  CHECK(csv.find("\n0,ply,0,") != std::string::npos);
  CHECK(csv.find(",shear,2,20\n") != std::string::npos);

  breaks.front().bond = m.bonds.size();
  CHECK_THROWS_WITH_AS(find_cracks(m, breaks), doctest::Contains("names bond"), Error);
  CHECK(find_cracks(m, {}).empty());
}

TEST_CASE("cracks of a laminate stay in their ply, delaminations on their interface") {
  LaminateSpec spec;
  spec.coupon.material = load_material("eglass-my750");
  spec.coupon.length = 1 * kMm;
  spec.coupon.width = 0.5 * kMm;
  spec.coupon.particle_diameter = 0.1 * kMm;
  spec.ply_angles = parse_layup("[0/0]");
  const std::unique_ptr<Strategy> square = default_registry().create("square");
  const Model m = build_laminate(*square, spec).model;
  const double x0 = m.particles.reference_position.col(0).minCoeff() - 0.05 * kMm;
  std::vector<BondBreak> breaks;
  // The same cut through both plies, and the interface bonds beyond x = 0.8 mm.
  break_where(m, breaks, BondState::kBrokenTension, 1, [&](auto& a, auto& b) {
    return straddles(a.x(), b.x(), x0 + 0.5 * kMm) && std::abs(a.z() - b.z()) < 1e-12;
  });
  break_where(m, breaks, BondState::kBrokenTension, 3, [&](auto& a, auto& b) {
    return std::abs(a.z() - b.z()) > 1e-12 && a.x() > x0 + 0.8 * kMm;
  });
  // Even a link distance that spans the plies keeps them apart.
  const std::vector<Crack> cracks = find_cracks(m, breaks, 1 * kMm);
  REQUIRE(cracks.size() == 3);
  CHECK(!cracks[0].interface);
  CHECK(!cracks[1].interface);
  CHECK(cracks[0].ply + cracks[1].ply == 1);
  CHECK(cracks[2].interface);
  CHECK(cracks[2].ply == 0);
  CHECK(cracks[2].first_at == 3);
  CHECK(crack_density(cracks, 0, x0, x0 + 0.9 * kMm) == doctest::Approx(1 / (0.9 * kMm)));
  CHECK(crack_density(cracks, 1, x0, x0 + 1 * kMm) == doctest::Approx(1 / (1 * kMm)));
}

TEST_CASE("the shear-lag stiffness of a cracked cross-ply and its ply-discount limit") {
  const Material m = load_material("eglass-my750");
  const double b = 0.2e-3, d = 0.4e-3;  // [0/90_2]s of 0.2 mm plies
  // Written out (Garrett & Bailey 1977) at 1 crack per mm: s = 0.5 mm.
  const double G23 = m.E2 / (2 * (1 + m.nu23));
  const double lambda = std::sqrt(G23 * (b * m.E1 + d * m.E2) / (b * d * d * m.E1 * m.E2));
  const double s = 0.5e-3;
  const double by_hand = 1 / (1 + d * m.E2 / (b * m.E1) * std::tanh(lambda * s) / (lambda * s));
  CHECK(shear_lag_stiffness_ratio(m, b, d, 1e3) == doctest::Approx(by_hand).epsilon(1e-12));
  CHECK(shear_lag_stiffness_ratio(m, b, d, 0) == 1);
  // Dense cracks: the 90° layer carries nothing, E = b E1 / (b + d) over E0 = (b E1 + d E2) /
  // (b + d).
  const double discount = b * m.E1 / (b * m.E1 + d * m.E2);
  CHECK(ply_discount_stiffness_ratio(m, b, d) == doctest::Approx(discount).epsilon(1e-14));
  CHECK(shear_lag_stiffness_ratio(m, b, d, 1e9) == doctest::Approx(discount).epsilon(1e-6));
  // More cracks, less stiffness.
  CHECK(shear_lag_stiffness_ratio(m, b, d, 2e3) < shear_lag_stiffness_ratio(m, b, d, 1e3));
  CHECK_THROWS_WITH_AS(shear_lag_stiffness_ratio(m, 0, d, 1e3), doctest::Contains("positive"),
                       Error);
  CHECK_THROWS_WITH_AS(shear_lag_stiffness_ratio(m, b, d, -1), doctest::Contains("density"), Error);
}
