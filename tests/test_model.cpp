// The model's fields, declared once (Particles::for_each_field, Bonds::for_each_field): every
// declared field survives resize, append, select, permute and renumber, and the size check names
// it. The checks iterate over the declaration, so a field added there is covered here unchanged.
#include <doctest/doctest.h>

#include <numeric>
#include <string>

#include "contacts/particle_ordering.hpp"
#include "core/error.hpp"
#include "core/model.hpp"

using namespace plydem;

namespace {

// Every field filled with values that tell field, row and column apart; particle indices (bond
// ends) are valid and distinct indices into `particles` particles.
template <class S>
S filled(int rows, int particles, int seed) {
  S s;
  s.resize(rows);
  int field = 0;
  S::for_each_field([&](FieldInfo info, auto member) {
    auto& a = s.*member;
    ++field;
    for (Eigen::Index r = 0; r < a.rows(); ++r)
      for (Eigen::Index c = 0; c < a.cols(); ++c) {
        if (info.particle_index) {
          a(r, c) = static_cast<int>((r + field) % particles);
        } else {
          a(r, c) = 1000 * seed + 100 * field + 10 * static_cast<int>(r) + static_cast<int>(c);
        }
      }
  });
  return s;
}

template <class S>
int field_count() {
  int count = 0;
  S::for_each_field([&](FieldInfo, auto) { ++count; });
  return count;
}

// Row r of every field of `a` equals row q of `b` (particle indices shifted by `offset`).
template <class S>
bool same_row(const S& a, int r, const S& b, int q, int offset = 0) {
  bool same = true;
  S::for_each_field([&](FieldInfo info, auto member) {
    auto expected = (b.*member).row(q).eval();
    if constexpr (field_kind<FieldType<decltype(member)>>() == FieldKind::kInt) {
      if (info.particle_index) expected += offset;
    }
    same &= ((a.*member).row(r) == expected).all();
  });
  return same;
}

}  // namespace

TEST_CASE_TEMPLATE("every declared field is resized, appended, selected and permuted", S, Particles,
                   Bonds) {
  CHECK(field_count<S>() >= 12);
  const S a = filled<S>(5, 7, 1), b = filled<S>(3, 7, 2);

  S zero = a;
  zero.resize(4);
  S::for_each_field([&](FieldInfo info, auto member) {
    CAPTURE(std::string(info.name));
    CHECK((zero.*member).rows() == 4);
    // Each field starts at its declared fill (0, or +inf for an unbreakable bond's strength).
    using Scalar = typename FieldType<decltype(member)>::Scalar;
    CHECK(((zero.*member) == static_cast<Scalar>(info.fill)).all());
  });

  S joined = a;
  if constexpr (std::is_same_v<S, Bonds>) {
    joined.append(b, 7);  // b's particles follow a's seven
  } else {
    joined.append(b);
  }
  REQUIRE(joined.size() == 8);
  joined.check_sizes();
  for (int r = 0; r < 5; ++r) CHECK(same_row(joined, r, a, r));
  for (int r = 0; r < 3; ++r)
    CHECK(same_row(joined, 5 + r, b, r, std::is_same_v<S, Bonds> ? 7 : 0));

  const std::vector<int> rows = {4, 1, 1, 0};
  const S picked = a.select(rows);
  REQUIRE(picked.size() == 4);
  for (int r = 0; r < 4; ++r) CHECK(same_row(picked, r, a, rows[r]));
  CHECK_THROWS_AS(a.select({0, 5}), Error);

  const std::vector<int> order = {2, 4, 0, 3, 1};
  S permuted = a;
  permuted.permute(order);
  for (int k = 0; k < 5; ++k) CHECK(same_row(permuted, k, a, order[k]));
  CHECK_THROWS_AS(permuted.permute({0, 1, 2, 3}), Error);
  CHECK_THROWS_AS(permuted.permute({0, 1, 2, 3, 3}), Error);

  // The size check names each field of the wrong size.
  S::for_each_field([&](FieldInfo info, auto member) {
    S broken = a;
    auto& field = broken.*member;
    field.conservativeResize(field.rows() + 1, field.cols());
    CAPTURE(std::string(info.name));
    // The field size() counts (mass, first) makes every other field the odd one out.
    if (broken.size() != a.size()) {
      CHECK_THROWS_AS(broken.check_sizes(), Error);
      return;
    }
    try {
      broken.check_sizes();
      FAIL("a field of the wrong size passed the size check");
    } catch (const Error& e) {
      const std::string message = e.what();
      CHECK(message.find(std::string("'") + info.name + "'") != std::string::npos);
    }
  });
}

TEST_CASE("bonds: particles renamed, rows written back, interface kind kept") {
  Bonds b = filled<Bonds>(4, 5, 3);
  const Bonds original = b;
  b.rename_particles({4, 3, 2, 1, 0});
  for (int k = 0; k < 4; ++k) {
    CHECK(b.first(k) == 4 - original.first(k));
    CHECK(b.second(k) == 4 - original.second(k));
  }
  CHECK_THROWS_AS(b.rename_particles({0, 1, 2}), Error);
  CHECK_THROWS_AS(b.rename_particles({0, -1, 2, 3, 4}), Error);

  Bonds part = original.select({3, 1});
  part.normal_stiffness *= 2;
  Bonds back = original;
  back.assign_rows({3, 1}, part);
  CHECK(back.normal_stiffness(3) == 2 * original.normal_stiffness(3));
  CHECK(back.normal_stiffness(0) == original.normal_stiffness(0));
  CHECK(same_row(back, 1, part, 1));
  CHECK_THROWS_AS(back.assign_rows({3}, part), Error);

  Bonds kinds;
  kinds.resize(2);
  kinds.kind(1) = static_cast<int>(BondKind::kInterface);
  CHECK(!kinds.is_interface(0));
  CHECK(kinds.is_interface(1));
}

namespace {

// Four particles in a row, bonded in a chain, the last bond an interface bond.
Model chain() {
  Model m;
  m.particles = filled<Particles>(4, 4, 4);
  for (int i = 0; i < 4; ++i) {
    m.particles.reference_position.row(i) << i, 0, 0;
    m.particles.radius(i) = 0.5;
  }
  m.bonds.resize(3);
  for (int b = 0; b < 3; ++b) {
    m.bonds.first(b) = b;
    m.bonds.second(b) = b + 1;
    m.bonds.normal_stiffness(b) = 10 + b;
    m.bonds.family(b) = b;
    set_bond_geometry(m.particles, m.bonds, b);
  }
  m.bonds.kind(2) = static_cast<int>(BondKind::kInterface);
  m.thickness = 2;
  m.check_consistency();
  return m;
}

}  // namespace

TEST_CASE("selecting particles keeps the bonds between them, renumbered") {
  const Model m = chain();
  const Model cut = select_particles(m, {3, 2, 0});
  CHECK(cut.thickness == 2);
  REQUIRE(cut.particles.size() == 3);
  for (int k = 0; k < 3; ++k)
    CHECK(same_row(cut.particles, k, m.particles, std::vector{3, 2, 0}[k]));
  REQUIRE(cut.bonds.size() == 1);  // only 2-3 survives, as (1, 0)
  CHECK(cut.bonds.first(0) == 1);
  CHECK(cut.bonds.second(0) == 0);
  CHECK(cut.bonds.is_interface(0));
  CHECK(cut.bonds.normal_stiffness(0) == 12);
  cut.check_consistency();
  CHECK_THROWS_AS(select_particles(m, {0, 0}), Error);
  CHECK_THROWS_AS(select_particles(m, {4}), Error);
}

TEST_CASE("renumbering a model carries every particle and bond field along") {
  const Model m = chain();
  Model r = m;
  const std::vector<int> order = {2, 0, 3, 1};
  renumber(r, order);
  std::vector<int> new_index(4);
  for (int k = 0; k < 4; ++k) {
    new_index[order[k]] = k;
    CHECK(same_row(r.particles, k, m.particles, order[k]));
  }
  REQUIRE(r.bonds.size() == m.bonds.size());
  for (int b = 0; b < m.bonds.size(); ++b) {
    int found = -1;
    for (int c = 0; c < r.bonds.size(); ++c)
      if (r.bonds.first(c) == new_index[m.bonds.first(b)] &&
          r.bonds.second(c) == new_index[m.bonds.second(b)])
        found = c;
    REQUIRE(found >= 0);
    Bonds expected = m.bonds.select({b});
    expected.rename_particles(new_index);
    CHECK(same_row(r.bonds, found, expected, 0));
  }
  r.check_consistency();
}

TEST_CASE("the consistency check refuses a bond kind that is no BondKind") {
  Model m = chain();
  m.bonds.kind(1) = 2;
  CHECK_THROWS_WITH_AS(m.check_consistency(), doctest::Contains("no BondKind"), Error);
  m = chain();
  m.bonds.family.conservativeResize(2);
  CHECK_THROWS_WITH_AS(m.check_consistency(), doctest::Contains("'family'"), Error);
}
