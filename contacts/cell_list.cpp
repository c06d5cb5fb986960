#include "contacts/cell_list.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <sstream>
#include <string>
#include <utility>

#include "core/error.hpp"
#include "core/progress.hpp"

namespace plydem {
namespace {

/// One particle packed for locality: the cell list reads a candidate's centre and radius together.
struct Sphere {
  double x, y, z, r;
};

// Neither function may decide a pair differently from the other, so both call this one compiled
// copy: inlined into two different loops, the compiler could contract a*b+c into an FMA in one
// and not the other, and a pair at exactly the cutoff would then differ by the last bit.
[[gnu::noinline]] bool in_contact(const Sphere& a, const Sphere& b, double contact_radius) {
  const double dx = a.x - b.x;
  const double dy = a.y - b.y;
  const double dz = a.z - b.z;
  const double cutoff = contact_radius * (a.r + b.r);
  return dx * dx + dy * dy + dz * dz <= cutoff * cutoff;
}

// A cheap inlined screen before in_contact. Every term is non-negative, so however the compiler
// rounds or contracts them, both sums lie within a few ulps (~1e-15) of each other; the 1e-12
// slack keeps every pair in_contact would accept.
inline bool maybe_in_contact(const Sphere& a, const Sphere& b, double contact_radius) {
  const double dx = a.x - b.x;
  const double dy = a.y - b.y;
  const double dz = a.z - b.z;
  const double cutoff = contact_radius * (a.r + b.r);
  return dx * dx + dy * dy + dz * dz <= cutoff * cutoff * (1.0 + 1e-12);
}

std::string to_text(double value) {
  std::ostringstream out;
  out << value;
  return out.str();
}

/// Checks the contract shared by both functions; allocates nothing unless it throws.
void validate(const PositionArray& position, const Eigen::ArrayXd& radius, double contact_radius,
              const char* caller) {
  const std::string where = std::string(caller) + ": ";
  require(std::isfinite(contact_radius) && contact_radius > 0.0,
          where + "contact_radius must be finite and > 0, got " + to_text(contact_radius));
  require(position.rows() == radius.size(),
          where + "position has " + std::to_string(position.rows()) + " rows but radius has " +
              std::to_string(radius.size()) + " entries");
  // Pairs are reported with int indices.
  require(position.rows() <= std::numeric_limits<int>::max(),
          where + "too many particles (" + std::to_string(position.rows()) + ")");
  for (Eigen::Index i = 0; i < position.rows(); ++i) {
    // Plain ifs, not require(): the message is built only when a particle is actually bad.
    const double x = position(i, 0), y = position(i, 1), z = position(i, 2), r = radius(i);
    if (!(std::isfinite(x) && std::isfinite(y) && std::isfinite(z))) {
      throw Error(where + "particle " + std::to_string(i) + " has a non-finite position (" +
                  to_text(x) + ", " + to_text(y) + ", " + to_text(z) + ")");
    }
    if (!(std::isfinite(r) && r > 0.0)) {
      throw Error(where + "particle " + std::to_string(i) + " has radius " + to_text(r) +
                  ", which must be finite and > 0");
    }
  }
}

Sphere sphere_at(const PositionArray& position, const Eigen::ArrayXd& radius, Eigen::Index i) {
  return {position(i, 0), position(i, 1), position(i, 2), radius(i)};
}

// Cell coordinates stay below 2^20 + 2 per axis, so three of them fit a 64-bit key with room for
// the +1 neighbour of the last cell, and a cell count per axis never overflows an int.
constexpr double kMaxCellsPerAxis = 1 << 20;

// The cell edge is widened by this relative amount so that rounding in the cell coordinates
// (at most ~2^-30 of a cell at 2^20 cells) can never put a pair that passes in_contact into
// cells two apart.
constexpr double kCellEdgeMargin = 1e-6;

/// Packs integer cell coordinates into one key whose order is (z, y, x) lexicographic, so the
/// cells of one row with consecutive x are contiguous in key order.
struct CellKeyCodec {
  int shift_y;
  int shift_z;
  std::uint64_t encode(std::uint64_t cx, std::uint64_t cy, std::uint64_t cz) const {
    return cx | (cy << shift_y) | (cz << shift_z);
  }
};

/// Sorts (key, particle) by key with an LSD radix sort over the bits the keys actually use:
/// a layer of 10^6 particles needs ~21 key bits, i.e. two passes instead of a comparison sort.
void radix_sort_by_key(std::vector<std::uint64_t>& key, std::vector<int>& particle, int key_bits) {
  constexpr int kDigitBits = 11;
  constexpr std::size_t kBuckets = std::size_t{1} << kDigitBits;
  const std::size_t n = key.size();
  std::vector<std::uint64_t> key_tmp(n);
  std::vector<int> particle_tmp(n);
  std::vector<std::size_t> start(kBuckets);
  for (int shift = 0; shift < key_bits; shift += kDigitBits) {
    std::fill(start.begin(), start.end(), 0);
    for (std::uint64_t k : key) ++start[(k >> shift) & (kBuckets - 1)];
    std::size_t sum = 0;
    for (std::size_t& s : start) {
      const std::size_t count = s;
      s = sum;
      sum += count;
    }
    for (std::size_t p = 0; p < n; ++p) {
      const std::size_t dst = start[(key[p] >> shift) & (kBuckets - 1)]++;
      key_tmp[dst] = key[p];
      particle_tmp[dst] = particle[p];
    }
    key.swap(key_tmp);
    particle.swap(particle_tmp);
  }
}

/// The particles bucketed into the occupied cells of a uniform grid. Memory is O(N) however
/// sparse the particles are: empty cells are never stored.
struct CellList {
  CellKeyCodec codec;
  std::uint64_t mask_x, mask_y;
  std::vector<std::uint64_t> cell_key;  ///< occupied cells, ascending
  std::vector<int> cell_begin;          ///< cell c holds slots [cell_begin[c], cell_begin[c + 1])
  std::vector<int> particle;            ///< particle index per slot
  std::vector<Sphere> sphere;           ///< particle data per slot, for locality
};

CellList build_cell_list(const PositionArray& position, const Eigen::ArrayXd& radius,
                         double contact_radius) {
  const Eigen::Index n = position.rows();
  const double max_radius = radius.maxCoeff();
  const double cell_edge = contact_radius * 2.0 * max_radius * (1.0 + kCellEdgeMargin);
  require(std::isfinite(cell_edge),
          "find_contact_pairs: the cell edge contact_radius * 2 * max radius overflows");

  // Cells are counted from the lower corner of the bounding box, so only the extent (not the
  // absolute position) has to fit the per-axis cell limit.
  const Eigen::Array<double, 1, 3> lower = position.colwise().minCoeff();
  const Eigen::Array<double, 1, 3> upper = position.colwise().maxCoeff();
  std::array<std::uint64_t, 3> cells_per_axis{};
  for (int axis = 0; axis < 3; ++axis) {
    const double cells = (upper(axis) - lower(axis)) / cell_edge;
    if (!(cells < kMaxCellsPerAxis)) {
      std::ostringstream message;
      message << "find_contact_pairs: the particles span " << upper(axis) - lower(axis)
              << " along axis " << axis << ", more than 2^20 cells of edge " << cell_edge
              << " (contact_radius * 2 * max radius); split the domain or check the positions";
      throw Error(message.str());
    }
    cells_per_axis[static_cast<std::size_t>(axis)] = static_cast<std::uint64_t>(cells) + 1;
  }
  // Each field holds cell coordinates up to cells_per_axis, the +1 neighbour of the last cell,
  // so a neighbour key never carries into the next field.
  const int bits_x = std::bit_width(cells_per_axis[0]);
  const int bits_y = std::bit_width(cells_per_axis[1]);
  const int bits_z = std::bit_width(cells_per_axis[2]);

  CellList list;
  list.codec = {bits_x, bits_x + bits_y};
  list.mask_x = (std::uint64_t{1} << bits_x) - 1;
  list.mask_y = (std::uint64_t{1} << bits_y) - 1;

  std::vector<std::uint64_t> key(static_cast<std::size_t>(n));
  list.particle.resize(static_cast<std::size_t>(n));
  for (Eigen::Index p = 0; p < n; ++p) {
    // Non-negative, so truncation is floor; below cells_per_axis by the check above.
    const auto cx = static_cast<std::uint64_t>((position(p, 0) - lower(0)) / cell_edge);
    const auto cy = static_cast<std::uint64_t>((position(p, 1) - lower(1)) / cell_edge);
    const auto cz = static_cast<std::uint64_t>((position(p, 2) - lower(2)) / cell_edge);
    key[static_cast<std::size_t>(p)] = list.codec.encode(cx, cy, cz);
    list.particle[static_cast<std::size_t>(p)] = static_cast<int>(p);
  }
  radix_sort_by_key(key, list.particle, bits_x + bits_y + bits_z);

  // The sorted keys are compacted in place into the occupied cells' keys: fresh memory is the
  // main cost at 10^6 particles, so nothing here is allocated twice or grown by copying.
  list.sphere.resize(static_cast<std::size_t>(n));
  list.cell_begin.reserve(static_cast<std::size_t>(n) + 1);
  std::size_t cell_count = 0;
  for (std::size_t slot = 0; slot < key.size(); ++slot) {
    if (slot == 0 || key[slot] != key[cell_count - 1]) {
      key[cell_count++] = key[slot];
      list.cell_begin.push_back(static_cast<int>(slot));
    }
    list.sphere[slot] = sphere_at(position, radius, list.particle[slot]);
  }
  list.cell_begin.push_back(static_cast<int>(n));
  key.resize(cell_count);
  list.cell_key = std::move(key);
  return list;
}

/// Calls visit(i, j), i < j, once for every pair in contact, in no particular order.
template <class Visit>
void for_each_contact(const CellList& list, double contact_radius, Visit visit) {
  const std::vector<std::uint64_t>& cell_key = list.cell_key;
  const std::vector<int>& cell_begin = list.cell_begin;
  const std::vector<int>& particle = list.particle;
  const std::vector<Sphere>& sphere = list.sphere;
  // The lower particle index goes first so in_contact sees its arguments as the brute force does.
  auto test_pair = [&](int a, int b) {
    if (!maybe_in_contact(sphere[static_cast<std::size_t>(a)], sphere[static_cast<std::size_t>(b)],
                          contact_radius)) {
      return;
    }
    if (particle[static_cast<std::size_t>(a)] > particle[static_cast<std::size_t>(b)]) {
      std::swap(a, b);
    }
    const auto sa = static_cast<std::size_t>(a);
    const auto sb = static_cast<std::size_t>(b);
    if (in_contact(sphere[sa], sphere[sb], contact_radius)) visit(particle[sa], particle[sb]);
  };

  // Half shell: each cell is paired with itself and with the 13 neighbours whose key is larger,
  // so every pair of cells is visited once. Those 13 are the next cell along x, plus three rows
  // of three cells (x-1..x+1) each: (y+1, z), (y-1, z+1), (y, z+1), (y+1, z+1).
  constexpr std::array<std::array<int, 2>, 4> kRowOffsets{{{1, 0}, {-1, 1}, {0, 1}, {1, 1}}};
  // The first cell of each row at or after the row's lower key; row keys only grow as the
  // home cell advances in key order, so each cursor sweeps the cells once: no search needed.
  std::array<std::size_t, 4> row_cursor{};
  const std::size_t cell_count = cell_key.size();

  for (std::size_t c = 0; c < cell_count; ++c) {
    const int begin = cell_begin[c];
    const int end = cell_begin[c + 1];
    for (int a = begin; a < end; ++a) {
      for (int b = a + 1; b < end; ++b) test_pair(a, b);
    }
    auto test_cell = [&](std::size_t other) {
      for (int a = begin; a < end; ++a) {
        for (int b = cell_begin[other]; b < cell_begin[other + 1]; ++b) test_pair(a, b);
      }
    };
    if (c + 1 < cell_count && cell_key[c + 1] == cell_key[c] + 1) test_cell(c + 1);

    const std::uint64_t cx = cell_key[c] & list.mask_x;
    const std::uint64_t cy = (cell_key[c] >> list.codec.shift_y) & list.mask_y;
    const std::uint64_t cz = cell_key[c] >> list.codec.shift_z;
    for (std::size_t row = 0; row < kRowOffsets.size(); ++row) {
      const int dy = kRowOffsets[row][0];
      const int dz = kRowOffsets[row][1];
      if (dy < 0 && cy == 0) continue;
      const std::uint64_t ry = cy + static_cast<std::uint64_t>(dy);  // wraps back for dy = -1
      const std::uint64_t rz = cz + static_cast<std::uint64_t>(dz);
      const std::uint64_t row_lower = list.codec.encode(cx == 0 ? 0 : cx - 1, ry, rz);
      const std::uint64_t row_upper = list.codec.encode(cx + 1, ry, rz);
      std::size_t& cursor = row_cursor[row];
      while (cursor < cell_count && cell_key[cursor] < row_lower) ++cursor;
      for (std::size_t other = cursor; other < cell_count && cell_key[other] <= row_upper;
           ++other) {
        test_cell(other);
      }
    }
  }
}

}  // namespace

std::vector<std::pair<int, int>> find_contact_pairs(const PositionArray& position,
                                                    const Eigen::ArrayXd& radius,
                                                    double contact_radius) {
  validate(position, radius, contact_radius, "find_contact_pairs");
  const auto n = static_cast<std::size_t>(position.rows());
  if (n == 0) return {};
  ProgressMeter meter("building the coupon: neighbour search", 4, "steps");
  const CellList list = build_cell_list(position, radius, contact_radius);
  meter.update(1);

  // Two sweeps, counting then filling: the pairs land directly in (i, j) order by a counting
  // sort on i, with no growing buffer and no second copy. Re-testing the candidates is cheaper
  // than the memory.
  std::vector<std::size_t> start(n + 1, 0);
  for_each_contact(list, contact_radius,
                   [&](int i, int) { ++start[static_cast<std::size_t>(i) + 1]; });
  for (std::size_t i = 0; i < n; ++i) start[i + 1] += start[i];
  meter.update(2);
  std::vector<std::pair<int, int>> pairs(start[n]);
  for_each_contact(list, contact_radius, [&](int i, int j) {
    pairs[start[static_cast<std::size_t>(i)]++] = {i, j};
  });
  meter.update(3);
  // start[i] now marks the end of i's pairs, which is where i + 1's begin.
  std::size_t begin = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t end = start[i];
    if (end - begin > 1) {
      std::sort(pairs.begin() + static_cast<std::ptrdiff_t>(begin),
                pairs.begin() + static_cast<std::ptrdiff_t>(end));
    }
    begin = end;
  }
  return pairs;
}

std::vector<std::pair<int, int>> find_contact_pairs_brute_force(const PositionArray& position,
                                                                const Eigen::ArrayXd& radius,
                                                                double contact_radius) {
  validate(position, radius, contact_radius, "find_contact_pairs_brute_force");
  const Eigen::Index n = position.rows();
  std::vector<Sphere> sphere(static_cast<std::size_t>(n));
  for (Eigen::Index i = 0; i < n; ++i) {
    sphere[static_cast<std::size_t>(i)] = sphere_at(position, radius, i);
  }
  std::vector<std::pair<int, int>> pairs;
  for (std::size_t i = 0; i < sphere.size(); ++i) {
    for (std::size_t j = i + 1; j < sphere.size(); ++j) {
      if (in_contact(sphere[i], sphere[j], contact_radius)) {
        pairs.emplace_back(static_cast<int>(i), static_cast<int>(j));
      }
    }
  }
  return pairs;
}

}  // namespace plydem
