// Cell-list contact detection: the fast path must equal the O(N^2) reference pair for pair, and
// on lattices with known coordination it must find exactly the lattice neighbours.

#include <doctest/doctest.h>

#include <cmath>
#include <limits>
#include <random>
#include <utility>
#include <vector>

#include "contacts/cell_list.hpp"
#include "core/error.hpp"

namespace {

using plydem::find_contact_pairs;
using plydem::find_contact_pairs_brute_force;
using plydem::PositionArray;
using Pairs = std::vector<std::pair<int, int>>;

std::vector<int> contact_count(const Pairs& pairs, int n) {
  std::vector<int> count(static_cast<std::size_t>(n), 0);
  for (const auto& [i, j] : pairs) {
    ++count[static_cast<std::size_t>(i)];
    ++count[static_cast<std::size_t>(j)];
  }
  return count;
}

bool sorted_and_ordered(const Pairs& pairs) {
  for (std::size_t k = 0; k < pairs.size(); ++k) {
    if (pairs[k].first >= pairs[k].second) return false;
    if (k > 0 && !(pairs[k - 1] < pairs[k])) return false;
  }
  return true;
}

/// Checks the fast path against the reference and returns its pairs.
Pairs check_against_brute_force(const PositionArray& position, const Eigen::ArrayXd& radius,
                                double contact_radius) {
  const Pairs fast = find_contact_pairs(position, radius, contact_radius);
  const Pairs reference = find_contact_pairs_brute_force(position, radius, contact_radius);
  CHECK(sorted_and_ordered(reference));
  CHECK(fast.size() == reference.size());
  CHECK(fast == reference);
  return fast;
}

/// Touching spheres of radius `r` on a hexagonal layer in z = 0, `nx` per row, rows offset by r.
PositionArray hexagonal_layer(int nx, int ny, double r) {
  PositionArray position(nx * ny, 3);
  for (int row = 0; row < ny; ++row) {
    for (int col = 0; col < nx; ++col) {
      const int p = row * nx + col;
      position(p, 0) = 2.0 * r * col + (row % 2 == 1 ? r : 0.0);
      position(p, 1) = std::sqrt(3.0) * r * row;
      position(p, 2) = 0.0;
    }
  }
  return position;
}

PositionArray cubic_lattice(int n, double spacing) {
  PositionArray position(n * n * n, 3);
  for (int k = 0; k < n; ++k) {
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i < n; ++i) {
        const int p = (k * n + j) * n + i;
        position.row(p) << spacing * i, spacing * j, spacing * k;
      }
    }
  }
  return position;
}

}  // namespace

TEST_CASE("cell list equals brute force on random 3D points with varying radii") {
  for (const unsigned seed : {1u, 2u, 3u, 4u, 5u}) {
    for (const double contact_radius : {1.0, 1.05, 1.8}) {
      CAPTURE(seed);
      CAPTURE(contact_radius);
      std::mt19937 rng(seed);
      // Negative and positive coordinates, so cells are counted from a non-zero lower corner.
      std::uniform_real_distribution<double> coordinate(-12.0, 15.0);
      std::uniform_real_distribution<double> radius_factor(0.5, 1.5);
      const int n = 1500;
      PositionArray position(n, 3);
      Eigen::ArrayXd radius(n);
      for (int p = 0; p < n; ++p) {
        position.row(p) << coordinate(rng), coordinate(rng), coordinate(rng);
        radius(p) = 0.8 * radius_factor(rng);
      }
      const Pairs pairs = check_against_brute_force(position, radius, contact_radius);
      CHECK(pairs.size() > 100);
    }
  }
}

TEST_CASE("cell list equals brute force on a long thin strip and a flat random layer") {
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const int n = 2000;
  PositionArray strip(n, 3);
  PositionArray layer(n, 3);
  Eigen::ArrayXd radius(n);
  for (int p = 0; p < n; ++p) {
    strip.row(p) << 2000.0 * unit(rng), 1.5 * unit(rng), 1.5 * unit(rng);
    layer.row(p) << 60.0 * unit(rng), 60.0 * unit(rng), 3.25;
    radius(p) = 0.5 + unit(rng);
  }
  CHECK(!check_against_brute_force(strip, radius, 1.05).empty());
  CHECK(!check_against_brute_force(layer, radius, 1.05).empty());
}

TEST_CASE("hexagonal layer of touching spheres: every interior particle has 6 contacts") {
  const int nx = 40;
  const int ny = 30;
  const double r = 0.37;
  const PositionArray position = hexagonal_layer(nx, ny, r);
  const Eigen::ArrayXd radius = Eigen::ArrayXd::Constant(nx * ny, r);
  const Pairs pairs = check_against_brute_force(position, radius, 1.01);
  const std::vector<int> count = contact_count(pairs, nx * ny);
  for (int row = 1; row < ny - 1; ++row) {
    for (int col = 1; col < nx - 1; ++col) {
      CAPTURE(row);
      CAPTURE(col);
      CHECK(count[static_cast<std::size_t>(row * nx + col)] == 6);
    }
  }
  // 3 bonds per particle less the missing ones on the boundary: nx-1 per row, 2nx-1 between rows.
  CHECK(pairs.size() == static_cast<std::size_t>(ny * (nx - 1) + (ny - 1) * (2 * nx - 1)));
}

TEST_CASE("large hexagonal layer: interior coordination 6 without the reference") {
  const int nx = 300;
  const int ny = 250;
  const PositionArray position = hexagonal_layer(nx, ny, 1.0);
  const Eigen::ArrayXd radius = Eigen::ArrayXd::Constant(nx * ny, 1.0);
  const Pairs pairs = find_contact_pairs(position, radius, 1.01);
  CHECK(sorted_and_ordered(pairs));
  const std::vector<int> count = contact_count(pairs, nx * ny);
  int interior_not_six = 0;
  for (int row = 1; row < ny - 1; ++row) {
    for (int col = 1; col < nx - 1; ++col) {
      if (count[static_cast<std::size_t>(row * nx + col)] != 6) ++interior_not_six;
    }
  }
  CHECK(interior_not_six == 0);
  CHECK(pairs.size() == static_cast<std::size_t>(ny * (nx - 1) + (ny - 1) * (2 * nx - 1)));
}

TEST_CASE("simple cubic lattice: 6 face neighbours, then 18 with the face diagonals") {
  const int n = 9;
  const double r = 0.5;
  const PositionArray position = cubic_lattice(n, 2.0 * r);
  const Eigen::ArrayXd radius = Eigen::ArrayXd::Constant(n * n * n, r);
  // 1.42 * 2r reaches the face diagonal (sqrt(2) * 2r) but not the body diagonal (sqrt(3) * 2r).
  for (const auto& [cutoff, coordination] :
       std::vector<std::pair<double, int>>{{1.01, 6}, {1.42, 18}}) {
    // Copies: doctest's CAPTURE is a lambda, and clang < 16 cannot capture structured bindings.
    const double contact_radius = cutoff;
    const int expected = coordination;
    CAPTURE(contact_radius);
    const Pairs pairs = check_against_brute_force(position, radius, contact_radius);
    const std::vector<int> count = contact_count(pairs, n * n * n);
    for (int k = 1; k < n - 1; ++k) {
      for (int j = 1; j < n - 1; ++j) {
        for (int i = 1; i < n - 1; ++i) {
          CHECK(count[static_cast<std::size_t>((k * n + j) * n + i)] == expected);
        }
      }
    }
  }
}

TEST_CASE("edge cases") {
  SUBCASE("no particles") {
    CHECK(find_contact_pairs(PositionArray(0, 3), Eigen::ArrayXd(0), 1.0).empty());
    CHECK(find_contact_pairs_brute_force(PositionArray(0, 3), Eigen::ArrayXd(0), 1.0).empty());
  }
  SUBCASE("one particle") {
    PositionArray position(1, 3);
    position << 1e300, -1e300, 0.0;
    CHECK(find_contact_pairs(position, Eigen::ArrayXd::Constant(1, 2.0), 1.0).empty());
  }
  SUBCASE("two coincident particles") {
    PositionArray position(2, 3);
    position << 1.0, 2.0, 3.0, 1.0, 2.0, 3.0;
    const Pairs expected{{0, 1}};
    CHECK(check_against_brute_force(position, Eigen::ArrayXd::Constant(2, 0.1), 1.0) == expected);
  }
  SUBCASE("a pair exactly at the cutoff is in contact") {
    PositionArray position(3, 3);
    position << 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 2.0;
    const Pairs expected{{0, 1}};
    CHECK(check_against_brute_force(position, Eigen::ArrayXd::Constant(3, 0.5), 1.0) == expected);
  }
  SUBCASE("points spread over 1e6 radii") {
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> coordinate(-5e5, 5e5);
    std::uniform_real_distribution<double> offset(-1.0, 1.0);
    const int clusters = 400;
    PositionArray position(2 * clusters, 3);
    for (int c = 0; c < clusters; ++c) {
      position.row(2 * c) << coordinate(rng), coordinate(rng), coordinate(rng);
      position.row(2 * c + 1) =
          position.row(2 * c) + Eigen::Array<double, 1, 3>(offset(rng), offset(rng), offset(rng));
    }
    const Pairs pairs =
        check_against_brute_force(position, Eigen::ArrayXd::Constant(2 * clusters, 0.5), 1.2);
    CHECK(pairs.size() > 100);
  }
  SUBCASE("a span beyond 2^20 cells is refused, not allocated") {
    PositionArray position(2, 3);
    position << 0.0, 0.0, 0.0, 0.0, 1e9, 0.0;
    CHECK_THROWS_AS(find_contact_pairs(position, Eigen::ArrayXd::Constant(2, 1.0), 1.0),
                    plydem::Error);
    // The reference has no cells, so it still answers.
    CHECK(find_contact_pairs_brute_force(position, Eigen::ArrayXd::Constant(2, 1.0), 1.0).empty());
  }
}

TEST_CASE("bad input throws plydem::Error naming the particle") {
  PositionArray position(4, 3);
  position << 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 2.0, 0.0, 0.0, 3.0, 0.0, 0.0;
  const Eigen::ArrayXd radius = Eigen::ArrayXd::Constant(4, 0.5);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();

  SUBCASE("non-finite position") {
    PositionArray bad = position;
    bad(2, 1) = nan;
    CHECK_THROWS_WITH_AS(find_contact_pairs(bad, radius, 1.0), doctest::Contains("particle 2"),
                         plydem::Error);
    CHECK_THROWS_WITH_AS(find_contact_pairs_brute_force(bad, radius, 1.0),
                         doctest::Contains("particle 2"), plydem::Error);
    bad(2, 1) = inf;
    CHECK_THROWS_AS(find_contact_pairs(bad, radius, 1.0), plydem::Error);
  }
  SUBCASE("non-positive or non-finite radius") {
    for (const double value : {0.0, -0.5, nan, inf}) {
      CAPTURE(value);
      Eigen::ArrayXd bad = radius;
      bad(3) = value;
      CHECK_THROWS_WITH_AS(find_contact_pairs(position, bad, 1.0), doctest::Contains("particle 3"),
                           plydem::Error);
      CHECK_THROWS_AS(find_contact_pairs_brute_force(position, bad, 1.0), plydem::Error);
    }
  }
  SUBCASE("bad contact radius") {
    for (const double value : {-1.0, 0.0, nan, inf}) {
      CAPTURE(value);
      CHECK_THROWS_AS(find_contact_pairs(position, radius, value), plydem::Error);
      CHECK_THROWS_AS(find_contact_pairs_brute_force(position, radius, value), plydem::Error);
    }
  }
  SUBCASE("sizes differ") {
    CHECK_THROWS_AS(find_contact_pairs(position, Eigen::ArrayXd::Constant(3, 0.5), 1.0),
                    plydem::Error);
  }
}
