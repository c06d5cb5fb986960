// Cracks as objects (solvers/cracks.hpp) on hand-built cases: bonds broken by hand along lines
// of a square coupon, counted, measured and told apart by ply.
#include <doctest/doctest.h>

#include <Eigen/Sparse>

#include <cmath>
#include <functional>
#include <numbers>
#include <utility>
#include <vector>

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

namespace {

// The minimum of Hashin's complementary-energy functional over C22,
//   integral over (-rho, rho) of (q psi^2 - p psi'^2 + psi''^2) dxi,  psi(±rho) = 1, psi'(±rho) =
//   0,
// by finite differences on `n` intervals (psi'' at the ends from mirrored ghost nodes, which holds
// the slopes there at zero),
// computed here without the closed form's roots: it should equal 2 chi(rho).
double hashin_functional_minimum(double p, double q, double rho, int n) {
  const double h = 2 * rho / n;
  // The energy is psi^T A psi over the nodes 0..n; each term is a weight times (c . psi)^2.
  std::vector<Eigen::Triplet<double>> entries;
  auto add_square = [&](const std::vector<std::pair<int, double>>& c, double weight) {
    for (const auto& [i, ci] : c)
      for (const auto& [j, cj] : c) entries.emplace_back(i, j, weight * ci * cj);
  };
  for (int i = 0; i <= n; ++i) {
    const double w = (i == 0 || i == n) ? h / 2 : h;
    add_square({{i, 1.0}}, w * q);
    // psi'' at node i; the ghost node beyond each end mirrors its neighbour (psi' = 0 there).
    const int left = i == 0 ? 1 : i - 1, right = i == n ? n - 1 : i + 1;
    add_square({{left, 1 / (h * h)}, {i, -2 / (h * h)}, {right, 1 / (h * h)}}, w);
  }
  for (int i = 0; i < n; ++i) add_square({{i, -1 / h}, {i + 1, 1 / h}}, -p * h);
  Eigen::SparseMatrix<double> a(n + 1, n + 1);
  a.setFromTriplets(entries.begin(), entries.end());
  // Unknowns: the interior nodes; the ends are 1. Minimum: f^T A_ff f - b^T A_uu^-1 b, b = A_uf f.
  const Eigen::SparseMatrix<double> interior = a.block(1, 1, n - 1, n - 1);
  Eigen::VectorXd coupling = Eigen::VectorXd::Zero(n - 1);
  for (int k = 1; k < n; ++k) coupling(k - 1) = a.coeff(k, 0) + a.coeff(k, n);
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(interior);
  REQUIRE(solver.info() == Eigen::Success);
  const Eigen::VectorXd u = solver.solve(coupling);
  const double ends = a.coeff(0, 0) + a.coeff(n, n) + 2 * a.coeff(0, n);
  return ends - coupling.dot(u);
}

}  // namespace

TEST_CASE("Hashin's variational stiffness of a cracked cross-ply: energy, limits, refusals") {
  const Material m = load_material("eglass-my750");
  const double t = 0.2e-3;
  for (int n : {1, 2, 4}) {
    CAPTURE(n);
    const double b = t, d = n * t;
    const HashinCrossPly h = hashin_cross_ply(m, b, d);
    // The closed form's chi is half the functional's minimum, computed without its roots.
    for (double rho : {0.3, 1.0, 3.0}) {
      CAPTURE(rho);
      // Steps of 0.003: finer ones lose digits to the fourth-difference matrix's conditioning.
      const int steps = static_cast<int>(std::ceil(2 * rho / 0.003));
      CHECK(hashin_functional_minimum(h.p, h.q, rho, steps) ==
            doctest::Approx(2 * h.chi(rho)).epsilon(1e-5));
    }
    // Dense cracks: the 90° layer carries nothing, the ply-discount modulus b E1 / (b + d) over
    // the rule of mixtures (b E1 + d E2) / (b + d).
    const double discount = b * m.E1 / (b * m.E1 + d * m.E2);
    CHECK(hashin_stiffness_ratio(m, b, d, 1e4 / d) == doctest::Approx(discount).epsilon(1e-6));
    CHECK(ply_discount_stiffness_ratio(m, b, d) == doctest::Approx(discount).epsilon(1e-14));
    // No cracks, and cracks far apart: E0; the stiffness falls as the density grows.
    CHECK(hashin_stiffness_ratio(m, b, d, 0) == 1.0);
    CHECK(hashin_stiffness_ratio(m, b, d, 1e-6 / d) == doctest::Approx(1.0).epsilon(1e-5));
    double previous = 1;
    for (double density : {0.1e3, 0.5e3, 1e3, 2e3, 5e3}) {
      const double ratio = hashin_stiffness_ratio(m, b, d, density);
      CHECK(ratio < previous);
      CHECK(ratio > discount);
      previous = ratio;
    }
  }
  CHECK_THROWS_WITH_AS(hashin_stiffness_ratio(m, t, t, -1), doctest::Contains("crack density"),
                       Error);
  // Shear moduli far below the moduli: the perturbation stops oscillating (4q <= p^2), which the
  // closed form does not cover.
  Material soft = m;
  soft.G12 = 1e6;
  CHECK_THROWS_WITH_AS(hashin_cross_ply(soft, t, t), doctest::Contains("4q <= p^2"), Error);
}

namespace {
// E-glass/MY750 with a matrix fracture energy (WWFE-I gives none): a glass/epoxy mode-I value.
Material with_matrix_fracture_energy(double g) {
  Material m = load_material("eglass-my750");
  m.strength.G_matrix = g;
  return m;
}
}  // namespace

TEST_CASE(
    "a new crack between two releases the complementary energy the shear-lag stiffness "
    "loses") {
  // Independent route: the laminate's compliance from shear_lag_stiffness_ratio. A length L
  // between two cracks under laminate stress sigma holds the complementary energy (per unit
  // width) sigma^2 h L / (2 E(1/L)); a crack midway leaves two lengths L/2, and the difference
  // over the new crack's area 2d (the whole 90° layer) is G. The 90° layer's stress far from
  // cracks is sigma E2 / E0 in the model's equal-strain laminate.
  const Material m = with_matrix_fracture_energy(200);
  const double b = 0.2e-3, d = 0.2e-3, h = 2 * (b + d);
  const double e0 = (b * m.E1 + d * m.E2) / (b + d);
  const double sigma = 100e6, sigma90 = sigma * m.E2 / e0;
  auto energy = [&](double length) {
    return sigma * sigma * h * length / (2 * e0 * shear_lag_stiffness_ratio(m, b, d, 1 / length));
  };
  for (double length : {0.1e-3, 0.4e-3, 1e-3, 5e-3}) {
    const double g = (2 * energy(length / 2) - energy(length)) / (2 * d);
    CHECK(new_crack_energy_release_rate(m, b, d, sigma90, length) ==
          doctest::Approx(g).epsilon(1e-9));
  }
  // An isolated crack releases the most, and the energy criterion of the first crack meets G_Ic.
  CHECK(new_crack_energy_release_rate(m, b, d, sigma90, 1.0) ==
        doctest::Approx(new_crack_energy_release_rate(m, b, d, sigma90, INFINITY)).epsilon(1e-9));
  const double first = isolated_crack_stress(m, b, d);
  CHECK(new_crack_energy_release_rate(m, b, d, first, INFINITY) ==
        doctest::Approx(m.strength.G_matrix).epsilon(1e-12));
  // Below it no crack forms; above it the interval L* where a new crack releases G_Ic shrinks as
  // the stress grows.
  CHECK(std::isinf(crack_multiplication_interval(m, b, d, 0.99 * first)));
  double previous = INFINITY;
  for (double factor : {1.01, 1.2, 1.5, 2.0, 3.0}) {
    const double interval = crack_multiplication_interval(m, b, d, factor * first);
    CHECK(new_crack_energy_release_rate(m, b, d, factor * first, interval) ==
          doctest::Approx(m.strength.G_matrix).epsilon(1e-9));
    CHECK(interval < previous);
    previous = interval;
  }
  CHECK_THROWS_WITH_AS(isolated_crack_stress(load_material("eglass-my750"), b, d),
                       doctest::Contains("G_matrix"), Error);
  CHECK_THROWS_WITH_AS(new_crack_energy_release_rate(m, b, d, NAN, 1e-3),
                       doctest::Contains("finite"), Error);
}

TEST_CASE("the in-situ transverse strength of a 90° layer (Camanho et al. 2006)") {
  const Material m = with_matrix_fracture_energy(200);
  const double yt = m.strength.YT;
  // A thick embedded layer: 1.12 sqrt(2) YT, whatever its thickness.
  const InSituStrength thick = in_situ_transverse_strength(m, 10e-3);
  CHECK(thick.value / (1.12 * std::sqrt(2.0) * yt) == doctest::Approx(1).epsilon(1e-14));
  // Thin: the slit crack through the layer (length t, Dvorak & Laws 1987) releases
  // G = pi t Lambda22 sigma^2 / 8 at its onset: the strength is where that is G_Ic.
  const double lambda22 = 2 * (1 / m.E2 - m.nu21() * m.nu21() / m.E1);
  for (double t : {0.1e-3, 0.2e-3, 0.4e-3}) {
    const InSituStrength s = in_situ_transverse_strength(m, t);
    REQUIRE(t < s.transition_thickness);
    const double released = std::numbers::pi * t * lambda22 * s.value * s.value / 8;
    CHECK(released / m.strength.G_matrix == doctest::Approx(1).epsilon(1e-12));
    CHECK(s.value > thick.value);
  }
  // The two meet at the transition thickness; a thinner layer is stronger as 1 / sqrt(t).
  const InSituStrength at = in_situ_transverse_strength(m, thick.transition_thickness);
  CHECK(at.thin / at.thick == doctest::Approx(1).epsilon(1e-12));
  CHECK(in_situ_transverse_strength(m, 0.1e-3).value /
            in_situ_transverse_strength(m, 0.4e-3).value ==
        doctest::Approx(2).epsilon(1e-12));
  // An outer layer: 1.79 sqrt(G_Ic / (pi t Lambda22)), weaker than an embedded one as thin.
  const InSituStrength outer = in_situ_transverse_strength(m, 0.1e-3, PlyPlacement::kOuter);
  CHECK(outer.thin / std::sqrt(m.strength.G_matrix / (std::numbers::pi * 0.1e-3 * lambda22)) ==
        doctest::Approx(1.79).epsilon(1e-12));
  CHECK(outer.thin < in_situ_transverse_strength(m, 0.1e-3).thin);
  CHECK_THROWS_WITH_AS(in_situ_transverse_strength(load_material("eglass-my750"), 0.2e-3),
                       doctest::Contains("G_matrix"), Error);
  CHECK_THROWS_WITH_AS(in_situ_transverse_strength(m, 0), doctest::Contains("thickness"), Error);
}
