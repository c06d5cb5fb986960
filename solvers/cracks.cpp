#include "solvers/cracks.hpp"

#include <fmt/format.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>
#include <optional>

#include "contacts/bond_opening.hpp"
#include "contacts/cell_list.hpp"
#include "core/disjoint_sets.hpp"
#include "core/error.hpp"
#include "core/units.hpp"

namespace plydem {

std::string Crack::mode() const {
  if (shear == 0) return "tension";
  if (tension == 0) return "shear";
  return "mixed";
}

std::vector<Crack> find_cracks(const Model& model, const std::vector<BondBreak>& breaks,
                               double link_distance) {
  const Bonds& bonds = model.bonds;
  const Particles& p = model.particles;
  if (!(link_distance > 0)) link_distance = 1.5 * 2.0 * p.radius.maxCoeff();
  require(std::isfinite(link_distance) && link_distance > 0,
          fmt::format("find_cracks: the link distance must be positive, got {}", link_distance));
  const int n = static_cast<int>(breaks.size());
  std::vector<Crack> cracks;
  if (n == 0) return cracks;
  // Each break's crack group: (interface?, ply or interface index).
  std::vector<std::pair<bool, int>> group(n);
  PositionArray position(n, 3);
  for (int k = 0; k < n; ++k) {
    const int b = breaks[k].bond;
    require(b >= 0 && b < bonds.size(),
            fmt::format("find_cracks: break {} names bond {}, but the model has {} bonds", k, b,
                        bonds.size()));
    const bool interface = bonds.is_interface(b);
    group[k] = {interface, interface ? bonds.family(b) : p.ply(bonds.first(b))};
    position.row(k) = breaks[k].position.transpose().array();
  }
  DisjointSets sets(n);
  const Eigen::ArrayXd half = Eigen::ArrayXd::Constant(n, 0.5 * link_distance);
  for (const auto& [i, j] : find_contact_pairs(position, half, 1.0)) {
    if (group[i] != group[j]) continue;
    sets.join(i, j);
  }
  // Members of each crack, in order of their first break (the breaks are in solver order).
  std::map<int, std::vector<int>> members;
  std::vector<int> order;
  for (int k = 0; k < n; ++k) {
    const int root = sets.find(k);
    if (members[root].empty()) order.push_back(root);
    members[root].push_back(k);
  }
  const double diameter = 2.0 * p.radius.maxCoeff();
  for (int root : order) {
    const std::vector<int>& m = members[root];
    Crack c;
    c.id = static_cast<int>(cracks.size());
    c.interface = group[root].first;
    c.ply = group[root].second;
    c.bonds = static_cast<int>(m.size());
    c.first_at = std::numeric_limits<double>::infinity();
    for (int k : m) {
      c.centroid += breaks[k].position;
      if (breaks[k].mode == BondState::kBrokenShear)
        ++c.shear;
      else
        ++c.tension;
      if (breaks[k].at < c.first_at) {
        c.first_at = breaks[k].at;
        c.first_load = breaks[k].load;
      }
    }
    c.centroid /= static_cast<double>(m.size());
    Eigen::Vector2d axis;
    if (m.size() == 1) {
      const Eigen::Vector3d branch = bonds.normal.row(breaks[m.front()].bond).transpose();
      axis = Eigen::Vector2d(-branch.y(), branch.x());
      if (axis.norm() < 1e-12) axis = Eigen::Vector2d(1, 0);  // a bond along z
      axis.normalize();
    } else {
      Eigen::Matrix2d covariance = Eigen::Matrix2d::Zero();
      for (int k : m) {
        const Eigen::Vector2d r = (breaks[k].position - c.centroid).head<2>();
        covariance += r * r.transpose();
      }
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eigen(covariance);
      axis = eigen.eigenvectors().col(1);
    }
    if (axis.y() < 0 || (axis.y() == 0 && axis.x() < 0)) axis = -axis;
    c.angle = std::atan2(axis.y(), axis.x());
    if (c.angle >= std::numbers::pi) c.angle -= std::numbers::pi;
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (int k : m) {
      const double t = axis.dot((breaks[k].position - c.centroid).head<2>());
      lo = std::min(lo, t);
      hi = std::max(hi, t);
    }
    const Eigen::Vector3d along(axis.x(), axis.y(), 0.0);
    c.start = c.centroid + lo * along;
    c.end = c.centroid + hi * along;
    c.length = hi - lo + diameter;
    cracks.push_back(c);
  }
  return cracks;
}

double crack_density(const std::vector<Crack>& cracks, int ply, double x_begin, double x_end) {
  require(std::isfinite(x_begin) && std::isfinite(x_end) && x_end > x_begin,
          fmt::format("crack_density: the stretch [{}, {}] m is empty", x_begin, x_end));
  int count = 0;
  for (const Crack& c : cracks) {
    if (!c.interface && c.ply == ply && c.centroid.x() >= x_begin && c.centroid.x() <= x_end)
      ++count;
  }
  return count / (x_end - x_begin);
}

std::vector<CrackPlane> transverse_crack_planes(const Model& model,
                                                const std::vector<BondBreak>& breaks, int ply,
                                                double min_extent) {
  const Particles& p = model.particles;
  const Bonds& bonds = model.bonds;
  double x0 = std::numeric_limits<double>::infinity();
  for (int i = 0; i < p.size(); ++i)
    if (p.ply(i) == ply) x0 = std::min(x0, p.reference_position(i, 0));
  struct Band {
    double x_sum = 0, y_min = std::numeric_limits<double>::infinity(),
           y_max = -std::numeric_limits<double>::infinity(), diameter = 0;
    int bonds = 0;
  };
  // The band an in-ply bond of the ply crosses; nullopt for other bonds and for bonds along the
  // plane (their ends at the same x), which cross none.
  auto band_of = [&](int b) -> std::optional<long> {
    const int i = bonds.first(b), j = bonds.second(b);
    if (bonds.is_interface(b) || p.ply(i) != ply || p.ply(j) != ply) return std::nullopt;
    const double xi = p.reference_position(i, 0), xj = p.reference_position(j, 0);
    const double d = p.radius(i) + p.radius(j);
    if (std::abs(xi - xj) < 1e-6 * d) return std::nullopt;
    return std::lround(2.0 * (0.5 * (xi + xj) - x0) / d);
  };
  std::map<long, Band> bands;
  for (const BondBreak& br : breaks) {
    require(br.bond >= 0 && br.bond < bonds.size(),
            fmt::format("transverse crack planes: break of bond {} of {}", br.bond, bonds.size()));
    const int b = br.bond;
    const std::optional<long> index = band_of(b);
    if (!index) continue;
    const int i = bonds.first(b), j = bonds.second(b);
    const double mid = 0.5 * (p.reference_position(i, 0) + p.reference_position(j, 0));
    const double d = p.radius(i) + p.radius(j);
    Band& band = bands[*index];
    band.x_sum += mid;
    band.y_min = std::min(band.y_min, br.position.y());
    band.y_max = std::max(band.y_max, br.position.y());
    band.diameter = std::max(band.diameter, d);
    ++band.bonds;
  }
  std::map<long, int> crossing;
  for (int b = 0; b < bonds.size(); ++b)
    if (const std::optional<long> index = band_of(b)) ++crossing[*index];
  std::vector<CrackPlane> planes;
  for (const auto& [index, band] : bands) {
    CrackPlane c;
    c.position = band.x_sum / band.bonds;
    c.extent = band.y_max - band.y_min + band.diameter;
    c.bonds = band.bonds;
    c.crossing = crossing[index];
    if (c.extent >= min_extent) planes.push_back(c);
  }
  return planes;
}

std::string cracks_csv(const std::vector<Crack>& cracks) {
  std::string out =
      "id,kind,ply,x_mm,y_mm,z_mm,length_mm,angle_deg,bonds,tension,shear,mode,first_event,"
      "first_load\n";
  for (const Crack& c : cracks) {
    out += fmt::format("{},{},{},{:.6g},{:.6g},{:.6g},{:.6g},{:.4g},{},{},{},{},{:g},{:.10g}\n",
                       c.id, c.interface ? "interface" : "ply", c.ply, c.centroid.x() * kMmPerMetre,
                       c.centroid.y() * kMmPerMetre, c.centroid.z() * kMmPerMetre,
                       c.length * kMmPerMetre, c.angle * 180.0 / std::numbers::pi, c.bonds,
                       c.tension, c.shear, c.mode(), c.first_at, c.first_load);
  }
  return out;
}

std::vector<BondBreak> cut_transverse_crack(Model& model, double x, int first_ply, int last_ply) {
  const Particles& p = model.particles;
  Bonds& bonds = model.bonds;
  const int plies = p.size() > 0 ? p.ply.maxCoeff() + 1 : 0;
  require(
      first_ply >= 0 && first_ply <= last_ply && last_ply < plies,
      fmt::format("a crack cut through plies {} .. {} (0 = bottom): the model has plies 0 .. {}",
                  first_ply, last_ply, plies - 1));
  require(std::isfinite(x), "a crack cut's x is not a finite number");
  auto cracked = [&](int i) { return p.ply(i) >= first_ply && p.ply(i) <= last_ply; };
  for (int i = 0; i < p.size(); ++i) {
    if (!cracked(i)) continue;
    require(std::abs(p.reference_position(i, 0) - x) > 1e-9 * p.radius(i),
            fmt::format("a crack cut at x = {} mm runs through the centre of particle {}: put "
                        "the plane between particles",
                        x * kMmPerMetre, i));
  }
  std::vector<BondBreak> breaks;
  for (int b = 0; b < bonds.size(); ++b) {
    const int i = bonds.first(b), j = bonds.second(b);
    if (bonds.is_broken(b) || !cracked(i) || !cracked(j)) continue;
    if ((p.reference_position(i, 0) - x) * (p.reference_position(j, 0) - x) >= 0) continue;
    open_bond(bonds, b, BondState::kBrokenTension);
    BondBreak cut;
    cut.bond = b;
    cut.position = p.reference_position.row(i).matrix().transpose() +
                   bonds.lever_first(b) * bonds.normal.row(b).matrix().transpose();
    breaks.push_back(cut);
  }
  require(!breaks.empty(),
          fmt::format("a crack cut at x = {} mm through plies {} .. {} crosses no intact bond",
                      x * kMmPerMetre, first_ply, last_ply));
  return breaks;
}

}  // namespace plydem
