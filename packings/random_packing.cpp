#include "packings/random_packing.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <tuple>

#include "core/disjoint_sets.hpp"
#include "core/error.hpp"
#include "core/units.hpp"

namespace plydem {
namespace {

const char* kAxis[3] = {"x", "y", "z"};

// A double uniform in [0, 1) from the generator's top 53 bits: fixed by the generator's standard
// output sequence, unlike std::uniform_real_distribution.
double uniform(std::mt19937_64& generator) {
  return static_cast<double>(generator() >> 11) * 0x1.0p-53;
}

// Spheres binned in cells of edge >= one diameter, so that overlaps are looked for in the 27 cells
// around a candidate only.
class OverlapGrid {
 public:
  OverlapGrid(const Eigen::Vector3d& box, const std::array<bool, 3>& periodic, double diameter)
      : box_(box), periodic_(periodic), diameter_(diameter) {
    for (int a = 0; a < 3; ++a) {
      cells_[a] = std::max(1, static_cast<int>(std::floor(box(a) / diameter)));
      cells_[a] = std::min(cells_[a], 4096);
    }
    head_.assign(static_cast<std::size_t>(cells_[0]) * cells_[1] * cells_[2], -1);
  }

  bool overlaps(const Eigen::Vector3d& x) const {
    const std::array<int, 3> c = cell_of(x);
    const double d2 = diameter_ * diameter_;
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          std::array<int, 3> n{c[0] + dx, c[1] + dy, c[2] + dz};
          bool inside = true;
          for (int a = 0; a < 3; ++a) {
            if (n[a] < 0 || n[a] >= cells_[a]) {
              if (!periodic_[a]) inside = false;
              n[a] = (n[a] + cells_[a]) % cells_[a];
            }
          }
          if (!inside) continue;
          for (int k = head_[index(n)]; k >= 0; k = next_[k]) {
            if (distance_squared(x, centre_[k]) < d2) return true;
          }
        }
    return false;
  }

  void add(const Eigen::Vector3d& x) {
    const int k = static_cast<int>(centre_.size());
    const std::size_t i = index(cell_of(x));
    centre_.push_back(x);
    next_.push_back(head_[i]);
    head_[i] = k;
  }

  const std::vector<Eigen::Vector3d>& centres() const { return centre_; }

 private:
  std::array<int, 3> cell_of(const Eigen::Vector3d& x) const {
    std::array<int, 3> c{};
    for (int a = 0; a < 3; ++a) {
      c[a] = std::clamp(static_cast<int>(x(a) / box_(a) * cells_[a]), 0, cells_[a] - 1);
    }
    return c;
  }
  std::size_t index(const std::array<int, 3>& c) const {
    return (static_cast<std::size_t>(c[2]) * cells_[1] + c[1]) * cells_[0] + c[0];
  }
  // Minimum-image distance along periodic axes.
  double distance_squared(const Eigen::Vector3d& x, const Eigen::Vector3d& y) const {
    double sum = 0;
    for (int a = 0; a < 3; ++a) {
      double d = x(a) - y(a);
      if (periodic_[a]) d -= box_(a) * std::round(d / box_(a));
      sum += d * d;
    }
    return sum;
  }

  Eigen::Vector3d box_;
  std::array<bool, 3> periodic_;
  double diameter_;
  std::array<int, 3> cells_{};
  std::vector<int> head_;
  std::vector<int> next_;
  std::vector<Eigen::Vector3d> centre_;
};

void check_contact_radius(const RandomPacking& packing, double contact_radius) {
  require(std::isfinite(contact_radius) && contact_radius > 0,
          fmt::format("random packing: the contact radius I_R must be positive, got {}",
                      contact_radius));
  const double cutoff = contact_radius * packing.diameter;
  for (int a = 0; a < 3; ++a) {
    require(!packing.periodic[a] || packing.box(a) >= 3 * cutoff,
            fmt::format("random packing: the periodic edge along {} ({:.4g} mm) must be at least "
                        "3 bond cutoffs ({:.4g} mm) long",
                        kAxis[a], packing.box(a) * kMmPerMetre, 3 * cutoff * kMmPerMetre));
  }
}

// Sorts the bonds by (i, j, image) and drops repeats.
PackingBonds canonical(std::vector<std::tuple<int, int, Eigen::Vector3i>> found) {
  auto less = [](const auto& a, const auto& b) {
    const Eigen::Vector3i& ia = std::get<2>(a);
    const Eigen::Vector3i& ib = std::get<2>(b);
    return std::tie(std::get<0>(a), std::get<1>(a), ia(0), ia(1), ia(2)) <
           std::tie(std::get<0>(b), std::get<1>(b), ib(0), ib(1), ib(2));
  };
  std::sort(found.begin(), found.end(), less);
  found.erase(std::unique(found.begin(), found.end(),
                          [&](const auto& a, const auto& b) { return !less(a, b) && !less(b, a); }),
              found.end());
  PackingBonds bonds;
  bonds.image.resize(static_cast<Eigen::Index>(found.size()), 3);
  for (std::size_t b = 0; b < found.size(); ++b) {
    const auto& [i, j, image] = found[b];
    // One image per pair: the periodic edges are longer than 2 cutoffs.
    if (!bonds.pairs.empty() && bonds.pairs.back() == std::make_pair(i, j)) {
      throw Error(
          fmt::format("random packing: spheres {} and {} bond to two images of each other", i, j));
    }
    bonds.pairs.emplace_back(i, j);
    bonds.image.row(static_cast<Eigen::Index>(b)) = image.transpose().array();
  }
  return bonds;
}

// Bond i -> image of j, stored with the lower index first.
std::tuple<int, int, Eigen::Vector3i> oriented(int i, int j, const Eigen::Vector3i& image) {
  if (i < j) return {i, j, image};
  return {j, i, Eigen::Vector3i(-image)};
}

}  // namespace

int RandomPackingSpec::count() const {
  const double sphere = std::numbers::pi / 6.0 * diameter * diameter * diameter;
  return static_cast<int>(std::lround(packing_fraction * box.prod() / sphere));
}

void RandomPackingSpec::validate() const {
  require(std::isfinite(diameter) && diameter > 0,
          fmt::format("random packing: the sphere diameter must be positive, got {} m", diameter));
  for (int a = 0; a < 3; ++a) {
    require(std::isfinite(box(a)) && box(a) > 0,
            fmt::format("random packing: the box edge along {} must be positive, got {} m",
                        kAxis[a], box(a)));
    require(!periodic[a] || box(a) >= 3 * diameter,
            fmt::format("random packing: the periodic edge along {} ({:.4g} mm) must be at least "
                        "3 diameters ({:.4g} mm)",
                        kAxis[a], box(a) * kMmPerMetre, 3 * diameter * kMmPerMetre));
  }
  require(std::isfinite(packing_fraction) && packing_fraction > 0 &&
              packing_fraction <= kMaxPackingFraction,
          fmt::format("random packing: the packing fraction must lie in (0, {}], got {}",
                      kMaxPackingFraction, packing_fraction));
  const double estimate =
      packing_fraction * box.prod() / (std::numbers::pi / 6.0 * diameter * diameter * diameter);
  require(estimate < 5e7, fmt::format("random packing: the box would hold about {:.3g} spheres "
                                      "(at most 5e7)",
                                      estimate));
  require(count() >= 2,
          fmt::format("random packing: a {:.4g} x {:.4g} x {:.4g} mm box at packing fraction {} "
                      "holds fewer than two spheres of diameter {:.4g} mm",
                      box(0) * kMmPerMetre, box(1) * kMmPerMetre, box(2) * kMmPerMetre,
                      packing_fraction, diameter * kMmPerMetre));
}

RandomPacking random_sequential_addition(const RandomPackingSpec& spec) {
  spec.validate();
  const int count = spec.count();
  std::mt19937_64 generator(spec.seed);
  OverlapGrid grid(spec.box, spec.periodic, spec.diameter);
  RandomPacking packing;
  packing.box = spec.box;
  packing.periodic = spec.periodic;
  packing.diameter = spec.diameter;
  const long max_attempts = 1000L * count;
  while (static_cast<int>(grid.centres().size()) < count) {
    if (packing.attempts >= max_attempts) {
      throw Error(fmt::format(
          "random packing: placed only {} of {} spheres in {} attempts; lower the packing "
          "fraction ({}) or enlarge the box",
          grid.centres().size(), count, packing.attempts, spec.packing_fraction));
    }
    ++packing.attempts;
    Eigen::Vector3d x;
    for (int a = 0; a < 3; ++a) {
      x(a) = uniform(generator) * spec.box(a);
      if (x(a) >= spec.box(a)) x(a) = 0;  // rounding of (1 - 2^-53) L; keeps [0, L) periodic
    }
    if (!grid.overlaps(x)) grid.add(x);
  }
  packing.position.resize(count, 3);
  for (int i = 0; i < count; ++i) packing.position.row(i) = grid.centres()[i].transpose().array();
  return packing;
}

PackingBonds bonds_within(const RandomPacking& packing, double contact_radius) {
  check_contact_radius(packing, contact_radius);
  const int n = static_cast<int>(packing.position.rows());
  const double cutoff = contact_radius * packing.diameter;
  // Ghost copies of the spheres within one cutoff of a periodic face, axis by axis, so that edge
  // and corner images are copied too. Originals come first.
  std::vector<Eigen::Vector3d> x;
  std::vector<int> origin;
  std::vector<Eigen::Vector3i> image;
  for (int i = 0; i < n; ++i) {
    x.push_back(packing.position.row(i).transpose().matrix());
    origin.push_back(i);
    image.push_back(Eigen::Vector3i::Zero());
  }
  for (int a = 0; a < 3; ++a) {
    if (!packing.periodic[a]) continue;
    const std::size_t existing = x.size();
    for (std::size_t k = 0; k < existing; ++k) {
      for (int shift : {-1, 1}) {
        const bool near = shift > 0 ? x[k](a) < cutoff : x[k](a) > packing.box(a) - cutoff;
        if (!near) continue;
        Eigen::Vector3d ghost = x[k];
        ghost(a) += shift * packing.box(a);
        Eigen::Vector3i ghost_image = image[k];
        ghost_image(a) += shift;
        x.push_back(ghost);
        origin.push_back(origin[k]);
        image.push_back(ghost_image);
      }
    }
  }
  PositionArray extended(static_cast<Eigen::Index>(x.size()), 3);
  for (std::size_t k = 0; k < x.size(); ++k) {
    extended.row(static_cast<Eigen::Index>(k)) = x[k].transpose().array();
  }
  const Eigen::ArrayXd radius =
      Eigen::ArrayXd::Constant(static_cast<Eigen::Index>(x.size()), 0.5 * packing.diameter);
  std::vector<std::tuple<int, int, Eigen::Vector3i>> found;
  for (const auto& [a, b] : find_contact_pairs(extended, radius, contact_radius)) {
    if (a >= n) continue;  // two ghosts: the same bond is found between originals or a ghost
    if (origin[b] == a) {
      throw Error(fmt::format("random packing: sphere {} bonds to its own periodic image", a));
    }
    found.push_back(oriented(a, origin[b], image[b]));
  }
  return canonical(std::move(found));
}

PackingBonds bonds_within_brute_force(const RandomPacking& packing, double contact_radius) {
  check_contact_radius(packing, contact_radius);
  const int n = static_cast<int>(packing.position.rows());
  const double cutoff = contact_radius * packing.diameter;
  int range[3];
  for (int a = 0; a < 3; ++a) range[a] = packing.periodic[a] ? 1 : 0;
  std::vector<std::tuple<int, int, Eigen::Vector3i>> found;
  for (int i = 0; i < n; ++i)
    for (int j = i; j < n; ++j)
      for (int sx = -range[0]; sx <= range[0]; ++sx)
        for (int sy = -range[1]; sy <= range[1]; ++sy)
          for (int sz = -range[2]; sz <= range[2]; ++sz) {
            const Eigen::Vector3i s(sx, sy, sz);
            if (i == j && s.isZero()) continue;
            double sum = 0;
            for (int a = 0; a < 3; ++a) {
              const double d =
                  packing.position(i, a) - (packing.position(j, a) + s(a) * packing.box(a));
              sum += d * d;
            }
            if (sum > cutoff * cutoff) continue;
            if (i == j) {
              throw Error(
                  fmt::format("random packing: sphere {} bonds to its own periodic image", i));
            }
            found.emplace_back(i, j, s);
          }
  return canonical(std::move(found));
}

int keep_largest_cluster(RandomPacking& packing, PackingBonds& bonds) {
  const int n = static_cast<int>(packing.position.rows());
  DisjointSets sets(n);
  auto root = [&](int i) { return sets.find(i); };
  for (const auto& [i, j] : bonds.pairs) sets.join(i, j);
  std::vector<int> size(n, 0);
  for (int i = 0; i < n; ++i) ++size[root(i)];
  const int largest = static_cast<int>(std::max_element(size.begin(), size.end()) - size.begin());
  std::vector<int> renumber(n, -1);
  int kept = 0;
  for (int i = 0; i < n; ++i) {
    if (root(i) == largest) renumber[i] = kept++;
  }
  if (kept == n) return 0;
  PositionArray position(kept, 3);
  for (int i = 0; i < n; ++i) {
    if (renumber[i] >= 0) position.row(renumber[i]) = packing.position.row(i);
  }
  packing.position = std::move(position);
  PackingBonds pruned;
  pruned.image.resize(bonds.size(), 3);
  for (int b = 0; b < bonds.size(); ++b) {
    const auto [i, j] = bonds.pairs[b];
    if (renumber[i] < 0) continue;  // a bond lies within one cluster
    pruned.image.row(pruned.size()) = bonds.image.row(b);
    pruned.pairs.emplace_back(renumber[i], renumber[j]);
  }
  pruned.image.conservativeResize(pruned.size(), 3);
  bonds = std::move(pruned);
  return n - kept;
}

}  // namespace plydem
