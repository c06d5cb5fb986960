#include "core/particle_ordering.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <numeric>

#include "core/error.hpp"

namespace plydem {
namespace {

// Hilbert index of a point with integer coordinates x[0 .. dims-1] < 2^bits, by J. Skilling,
// "Programming the Hilbert curve", AIP Conf. Proc. 707 (2004) 381: the coordinates are turned
// in place into the "transposed" index, whose bits are then interleaved.
std::uint64_t hilbert_index(std::array<std::uint32_t, 3> x, int dims, int bits) {
  const std::uint32_t top = 1u << (bits - 1);
  for (std::uint32_t q = top; q > 1; q >>= 1) {
    const std::uint32_t p = q - 1;
    for (int i = 0; i < dims; ++i) {
      if (x[i] & q) {
        x[0] ^= p;
      } else {
        const std::uint32_t t = (x[0] ^ x[i]) & p;
        x[0] ^= t;
        x[i] ^= t;
      }
    }
  }
  for (int i = 1; i < dims; ++i) x[i] ^= x[i - 1];
  std::uint32_t t = 0;
  for (std::uint32_t q = top; q > 1; q >>= 1) {
    if (x[dims - 1] & q) t ^= q - 1;
  }
  for (int i = 0; i < dims; ++i) x[i] ^= t;
  std::uint64_t index = 0;
  for (int b = bits - 1; b >= 0; --b) {
    for (int i = 0; i < dims; ++i) index = (index << 1) | ((x[i] >> b) & 1u);
  }
  return index;
}

}  // namespace

std::vector<int> space_filling_curve_order(const Vector3Array& position) {
  const int n = static_cast<int>(position.rows());
  std::vector<int> order(n);
  std::iota(order.begin(), order.end(), 0);
  if (n < 2) return order;
  require(position.isFinite().all(), "a particle position is not finite: no space-filling order");
  const Eigen::Array3d low = position.colwise().minCoeff().transpose();
  const Eigen::Array3d extent = position.colwise().maxCoeff().transpose() - low;
  const double largest = extent.maxCoeff();
  if (!(largest > 0)) return order;  // every particle at one point
  // Drop the axes the particles do not spread along (a layer is planar).
  std::array<int, 3> axis{};
  int dims = 0;
  for (int c = 0; c < 3; ++c) {
    if (extent(c) > 1e-9 * largest) axis[dims++] = c;
  }
  // One scale for every axis keeps the curve's cells square, whatever the aspect ratio.
  const int bits = dims == 3 ? 21 : (dims == 2 ? 31 : 62);
  std::vector<std::uint64_t> key(n);
  if (dims == 1) {
    const double scale = std::ldexp(1.0, 52) / largest;
    for (int i = 0; i < n; ++i)
      key[i] = static_cast<std::uint64_t>((position(i, axis[0]) - low(axis[0])) * scale);
  } else {
    const double cells = std::ldexp(1.0, bits) - 1.0;
    const double scale = cells / largest;
    for (int i = 0; i < n; ++i) {
      std::array<std::uint32_t, 3> x{};
      for (int d = 0; d < dims; ++d) {
        const double q = std::min(cells, (position(i, axis[d]) - low(axis[d])) * scale);
        x[d] = static_cast<std::uint32_t>(q);
      }
      key[i] = hilbert_index(x, dims, bits);
    }
  }
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return key[a] < key[b]; });
  return order;
}

void check_permutation(const std::vector<int>& order, int count) {
  if (static_cast<int>(order.size()) != count) {
    throw Error(fmt::format("a particle ordering lists {} particles, the model has {}",
                            order.size(), count));
  }
  std::vector<char> seen(count, 0);
  for (int k = 0; k < count; ++k) {
    const int i = order[k];
    if (!(i >= 0 && i < count) || seen[i]) {
      throw Error(
          fmt::format("a particle ordering is not a permutation: entry {} names particle {} {}", k,
                      i, (i >= 0 && i < count) ? "twice" : "that does not exist"));
    }
    seen[i] = 1;
  }
}

void renumber(Model& model, const std::vector<int>& order) {
  Particles& p = model.particles;
  const int n = p.size();
  check_permutation(order, n);
  for (Vector3Array* a : {&p.reference_position, &p.displacement, &p.velocity, &p.rotation,
                          &p.angular_velocity, &p.force, &p.torque}) {
    const Vector3Array old = *a;
    for (int k = 0; k < n; ++k) a->row(k) = old.row(order[k]);
  }
  for (Eigen::ArrayXd* a : {&p.mass, &p.moment_of_inertia, &p.radius, &p.volume}) {
    const Eigen::ArrayXd old = *a;
    for (int k = 0; k < n; ++k) (*a)(k) = old(order[k]);
  }
  for (Eigen::ArrayXi* a : {&p.ply, &p.group}) {
    const Eigen::ArrayXi old = *a;
    for (int k = 0; k < n; ++k) (*a)(k) = old(order[k]);
  }

  Bonds& b = model.bonds;
  const int m = b.size();
  std::vector<int> new_index(n);
  for (int k = 0; k < n; ++k) new_index[order[k]] = k;
  for (int e = 0; e < m; ++e) {
    if (!(b.first(e) >= 0 && b.first(e) < n && b.second(e) >= 0 && b.second(e) < n))
      throw Error(
          fmt::format("bond {} refers to a missing particle ({}, {})", e, b.first(e), b.second(e)));
    b.first(e) = new_index[b.first(e)];
    b.second(e) = new_index[b.second(e)];
  }
  std::vector<int> bond_order(m);
  std::iota(bond_order.begin(), bond_order.end(), 0);
  auto low_high = [&](int e) {
    return std::pair(std::min(b.first(e), b.second(e)), std::max(b.first(e), b.second(e)));
  };
  std::stable_sort(bond_order.begin(), bond_order.end(),
                   [&](int x, int y) { return low_high(x) < low_high(y); });
  for (Eigen::ArrayXi* a : {&b.first, &b.second, &b.family}) {
    const Eigen::ArrayXi old = *a;
    for (int e = 0; e < m; ++e) (*a)(e) = old(bond_order[e]);
  }
  for (Eigen::ArrayXd* a : {&b.normal_stiffness, &b.shear_stiffness, &b.bending_stiffness,
                            &b.twisting_stiffness, &b.length, &b.lever_first, &b.lever_second}) {
    const Eigen::ArrayXd old = *a;
    for (int e = 0; e < m; ++e) (*a)(e) = old(bond_order[e]);
  }
  const Vector3Array old_normal = b.normal;
  for (int e = 0; e < m; ++e) b.normal.row(e) = old_normal.row(bond_order[e]);
}

}  // namespace plydem
