#include "strategies/lattice.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <array>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <numbers>
#include <optional>

#include "contacts/bond_kernel.hpp"
#include "core/elasticity.hpp"
#include "core/error.hpp"
#include "core/parallel_bond.hpp"
#include "core/progress.hpp"
#include "core/stopwatch.hpp"
#include "core/units.hpp"
#include "strategies/calibration.hpp"
#include "strategies/registry.hpp"
#include "strategies/specimen.hpp"

namespace plydem {
namespace {

// Voigt index pairs (11, 22, 33, 23, 13, 12).
constexpr int kVoigt[6][2] = {{0, 0}, {1, 1}, {2, 2}, {1, 2}, {0, 2}, {0, 1}};

// N(x)N and T^T.T of a unit direction as Voigt 6x6 matrices (eqs. 6 and 9, the latter with the
// -n_i n_j n_k n_l term inside, ERRATA §2).
void projection_tensors(const Eigen::Vector3d& n, Matrix6d& normal, Matrix6d& shear) {
  for (int I = 0; I < 6; ++I) {
    const int i = kVoigt[I][0], j = kVoigt[I][1];
    for (int J = 0; J < 6; ++J) {
      const int k = kVoigt[J][0], l = kVoigt[J][1];
      const double nnnn = n(i) * n(j) * n(k) * n(l);
      normal(I, J) = nnnn;
      shear(I, J) = 0.25 * (n(j) * n(k) * (i == l) + n(j) * n(l) * (i == k) +
                            n(i) * n(k) * (j == l) + n(i) * n(l) * (j == k)) -
                    nnnn;
    }
  }
}

// Nodes and weights of the m-point Gauss-Legendre rule on [-1, 1] (Newton on P_m).
void gauss_legendre(int m, std::vector<double>& node, std::vector<double>& weight) {
  node.assign(m, 0);
  weight.assign(m, 0);
  for (int k = 0; k < m; ++k) {
    double x = std::cos(std::numbers::pi * (k + 0.75) / (m + 0.5));
    double derivative = 1;
    for (int iteration = 0; iteration < 100; ++iteration) {
      double p0 = 1, p1 = x;
      for (int n = 2; n <= m; ++n) {
        const double p2 = ((2 * n - 1) * x * p1 - (n - 1) * p0) / n;
        p0 = p1;
        p1 = p2;
      }
      derivative = m * (x * p1 - p0) / (x * x - 1);
      const double dx = p1 / derivative;
      x -= dx;
      if (std::abs(dx) < 1e-16) break;
    }
    node[k] = x;
    weight[k] = 2 / ((1 - x * x) * derivative * derivative);
  }
}

// The in-plane transverse direction t = z x f, or y for a fibre along z.
Eigen::Vector3d transverse_of(const Eigen::Vector3d& fibre) {
  const Eigen::Vector3d t = Eigen::Vector3d::UnitZ().cross(fibre);
  return t.norm() > 1e-12 ? Eigen::Vector3d(t.normalized()) : Eigen::Vector3d::UnitY();
}

Eigen::Vector3d fibre_at(double ply_angle) {
  return {std::cos(ply_angle), std::sin(ply_angle), 0.0};
}

// The six independent entries of an in-plane stiffness, weighted so that their Euclidean norm is
// the Frobenius norm of the 3x3 matrix.
Eigen::Matrix<double, 6, 1> weighted_entries(const Eigen::Matrix3d& c) {
  const double r2 = std::numbers::sqrt2;
  Eigen::Matrix<double, 6, 1> v;
  v << c(0, 0), c(1, 1), r2 * c(0, 1), r2 * c(0, 2), r2 * c(1, 2), c(2, 2);
  return v;
}

// Bending and twisting of a parallel bond of radius R (hex2d's rule, eqs. 1-2).
FamilyStiffness with_rotational_springs(double normal, double shear, double radius) {
  const double r2 = radius * radius;
  return {normal, shear, normal * r2 / 4.0, shear * r2 / 2.0};
}

// ---------------------------------------------------------------------------------------------
// Relaxed stiffness of a periodic layer (solvers/periodic_homogenization.hpp, the engine's own bond
// law: fluctuations periodic in x and y, free in z, every particle spinning) and its sensitivity
// to each bond's stiffnesses.
class RelaxedLayer {
 public:
  explicit RelaxedLayer(const PeriodicModel& periodic) : periodic_(periodic) {}

  /// d(in-plane block)/d(k_n) and d/d(k_s) of every bond, bending and twisting following
  /// k_n R^2/4 and k_s R^2/2: by the envelope theorem D_b^T K_b' D_b / V, with D_b the bond's
  /// relaxed dofs (affine plus fluctuation) under the unit in-plane strains.
  struct Sensitivity {
    std::vector<Eigen::Matrix3d> normal, shear;
  };
  /// The relaxed stiffness of periodic_ (whose model the caller updates in place).
  Matrix6d relaxed(Sensitivity* sensitivity = nullptr, double radius = 0) {
    const Model& model = periodic_.model;
    Eigen::MatrixXd fluctuation;
    const PeriodicHomogenization h =
        homogenize_periodic(periodic_, {}, sensitivity ? &fluctuation : nullptr);
    if (sensitivity) {
      const int in_plane[3] = {0, 1, 5};
      const int m = model.bonds.size();
      sensitivity->normal.resize(m);
      sensitivity->shear.resize(m);
      for (int b = 0; b < m; ++b) {
        const Eigen::Vector3d branch = periodic_.branch(b);
        const int first = model.bonds.first(b), second = model.bonds.second(b);
        Eigen::Matrix<double, 12, 3> dofs_b;
        for (int s = 0; s < 3; ++s) {
          dofs_b.col(s).head<6>() = fluctuation.block<6, 1>(6 * first, in_plane[s]);
          dofs_b.col(s).tail<6>() = fluctuation.block<6, 1>(6 * second, in_plane[s]);
          // The unit strain moves the image of `second` by E branch relative to `first`.
          dofs_b.col(s).segment<3>(6) += voigt_unit_strain(in_plane[s]) * branch;
        }
        BondParameters unit = bond_parameters(model.bonds, b);
        unit.normal_stiffness = 1;
        unit.shear_stiffness = 0;
        unit.bending_stiffness = radius * radius / 4;
        unit.twisting_stiffness = 0;
        sensitivity->normal[b] =
            dofs_b.transpose() * parallel_bond_stiffness(unit) * dofs_b / periodic_.volume;
        unit.normal_stiffness = 0;
        unit.shear_stiffness = 1;
        unit.bending_stiffness = 0;
        unit.twisting_stiffness = radius * radius / 2;
        sensitivity->shear[b] =
            dofs_b.transpose() * parallel_bond_stiffness(unit) * dofs_b / periodic_.volume;
      }
    }
    return h.relaxed;
  }

 private:
  const PeriodicModel& periodic_;
};

// Per-bond factors of the law: kappa = 6 V / (N L^2), c = n.f, s = n.t.
struct BondLawGeometry {
  Eigen::ArrayXd kappa, c, s, z;
};

BondLawGeometry law_geometry(const Bonds& bonds, const Eigen::Vector3d& fibre,
                             double volume_per_bond) {
  const Eigen::Vector3d t = transverse_of(fibre);
  const Eigen::Vector3d w = fibre.cross(t);
  BondLawGeometry g;
  const int m = bonds.size();
  g.kappa.resize(m);
  g.c.resize(m);
  g.s.resize(m);
  g.z.resize(m);
  for (int b = 0; b < m; ++b) {
    const Eigen::Vector3d n = bonds.normal.row(b).transpose();
    g.kappa(b) = 6.0 * volume_per_bond / (bonds.length(b) * bonds.length(b));
    g.c(b) = n.dot(fibre);
    g.s(b) = n.dot(t);
    g.z(b) = n.dot(w);
  }
  return g;
}

// Writes the bond stiffnesses of `moduli`; returns the smallest k_n and k_s over the bonds.
std::pair<double, double> apply_law(const OrientationModuli& moduli, const BondLawGeometry& g,
                                    double radius, const Eigen::ArrayXd* scale, Bonds& bonds) {
  double min_normal = std::numeric_limits<double>::infinity(), min_shear = min_normal;
  for (int b = 0; b < bonds.size(); ++b) {
    const double factor = g.kappa(b) * (scale ? (*scale)(b) : 1.0);
    const FamilyStiffness k =
        with_rotational_springs(factor * moduli.normal_modulus(g.c(b), g.s(b), g.z(b)),
                                factor * moduli.shear_modulus(g.c(b), g.s(b), g.z(b)), radius);
    // A quartic law held non-negative on finitely many directions may dip slightly below zero
    // between them: such a bond gets no normal spring (build() refuses a clear dip).
    bonds.normal_stiffness(b) = std::max(0.0, k.normal);
    bonds.shear_stiffness(b) = k.shear;
    bonds.bending_stiffness(b) = std::max(0.0, k.bending);
    bonds.twisting_stiffness(b) = k.twisting;
    min_normal = std::min(min_normal, k.normal);
    min_shear = std::min(min_shear, k.shear);
  }
  return {min_normal, min_shear};
}

// Orientation bins of the report: 0-30, 30-60, 60-90 deg between bond and fibre.
int orientation_bin(double c) {
  const double theta = std::acos(std::min(1.0, std::abs(c)));
  return std::min(2, static_cast<int>(theta / (30 * kDegree)));
}

std::vector<FamilyCalibration> orientation_families(const Bonds& bonds, const BondLawGeometry& g,
                                                    double ply_angle) {
  std::vector<FamilyCalibration> families(3);
  std::array<int, 3> count{};
  const char* labels[3] = {"bonds 0-30 deg from the fibre (mean)",
                           "bonds 30-60 deg from the fibre (mean)",
                           "bonds 60-90 deg from the fibre (mean)"};
  for (int f = 0; f < 3; ++f) {
    families[f].label = labels[f];
    families[f].direction = ply_angle + (15 + 30 * f) * kDegree;
  }
  for (int b = 0; b < bonds.size(); ++b) {
    FamilyStiffness& k = families[orientation_bin(g.c(b))].stiffness;
    k.normal += bonds.normal_stiffness(b);
    k.shear += bonds.shear_stiffness(b);
    k.bending += bonds.bending_stiffness(b);
    k.twisting += bonds.twisting_stiffness(b);
    ++count[orientation_bin(g.c(b))];
  }
  for (int f = 0; f < 3; ++f) {
    if (count[f] == 0) continue;
    FamilyStiffness& k = families[f].stiffness;
    k.normal /= count[f];
    k.shear /= count[f];
    k.bending /= count[f];
    k.twisting /= count[f];
  }
  return families;
}

// A model of the packing's spheres with bond geometry (stiffnesses zero); masses and volumes share
// the box volume equally. Bonds across a periodic face get the branch to the neighbour's image.
Model packing_model(const RandomPacking& packing, const PackingBonds& bonds, double density) {
  SpecimenLayout layout;
  layout.position = packing.position;
  layout.radius = 0.5 * packing.diameter;
  layout.particle_volume = packing.box.prod() / static_cast<double>(packing.position.rows());
  layout.density = density;
  layout.pairs = bonds.pairs;
  layout.thickness = packing.box(2);
  Model model = assemble_specimen(layout);
  Bonds& b = model.bonds;
  for (int k = 0; k < bonds.size(); ++k) {
    const auto [i, j] = bonds.pairs[k];
    const Eigen::Vector3d branch =
        (packing.position.row(j) - packing.position.row(i)).transpose().matrix() +
        packing.box.cwiseProduct(bonds.image.row(k).transpose().cast<double>().matrix());
    const double length = branch.norm();
    b.normal.row(k) = (branch / length).transpose().array();
    b.length(k) = length;
    b.lever_first(k) = b.lever_second(k) = 0.5 * length;  // equal radii: mid-gap = mid-branch
  }
  return model;
}

// What a lattice coupon's bonds get beyond the report: the calibrated orientation law, the volume
// per bond of the coupon's own periodic packing, and which coupon it was calibrated for.
struct LatticeLaw : CalibrationDetail {
  OrientationModuli moduli;
  double volume_per_bond = 0;
  std::string coupon_key;
};

// Fraction of the ball of radius `reach` around x inside `box`, and inside the slab 0 <= z <=
// box.z (the calibration sample's domain), from a fixed grid of points in the unit ball.
class NeighbourhoodFraction {
 public:
  NeighbourhoodFraction() {
    const int m = 10;
    for (int i = -m; i <= m; ++i)
      for (int j = -m; j <= m; ++j)
        for (int k = -m; k <= m; ++k) {
          const Eigen::Vector3d q =
              (Eigen::Vector3d(i, j, k) + Eigen::Vector3d::Constant(0.5)) / (m + 0.5);
          if (q.norm() <= 1) points_.push_back(q);
        }
  }
  // Ratio (inside the slab) / (inside the box) for a centre inside the box.
  double completion(const Eigen::Vector3d& x, const Eigen::Vector3d& box, double reach) const {
    int slab = 0, inside = 0;
    for (const Eigen::Vector3d& q : points_) {
      const Eigen::Vector3d y = x + reach * q;
      if (y.z() < 0 || y.z() > box.z()) continue;
      ++slab;
      if (y.x() >= 0 && y.x() <= box.x() && y.y() >= 0 && y.y() <= box.y()) ++inside;
    }
    return inside > 0 ? static_cast<double>(slab) / inside : 1.0;
  }

 private:
  std::vector<Eigen::Vector3d> points_;
};

// Affine stiffness: every particle follows the strain, none turns (eq. 5, each bond once).
Matrix6d affine_layer(const Model& model, double volume) {
  Matrix6d c = Matrix6d::Zero();
  Matrix6d normal, shear;
  for (int b = 0; b < model.bonds.size(); ++b) {
    const Eigen::Vector3d n = model.bonds.normal.row(b).transpose();
    projection_tensors(n, normal, shear);
    const double l2 = model.bonds.length(b) * model.bonds.length(b);
    c += l2 * (model.bonds.normal_stiffness(b) * normal + model.bonds.shear_stiffness(b) * shear);
  }
  return c / volume;
}

// The correction's unknowns: the six normal and three shear Bernstein coefficients, then the two
// couplings.
constexpr int kUnknowns = 11;
using Unknowns = Eigen::Matrix<double, kUnknowns, 1>;
using Entries = Eigen::Matrix<double, 6, 1>;
using Jacobian = Eigen::Matrix<double, 6, kUnknowns>;

Unknowns unknowns_of(const OrientationModuli& m) {
  Unknowns p;
  for (int k = 0; k < 6; ++k) p(k) = m.normal[k];
  for (int k = 0; k < 3; ++k) p(6 + k) = m.shear[k];
  p(9) = m.coupling;
  p(10) = m.coupling_oblique;
  return p;
}

OrientationModuli moduli_of(const Unknowns& p) {
  OrientationModuli m;
  for (int k = 0; k < 6; ++k) m.normal[k] = p(k);
  for (int k = 0; k < 3; ++k) m.shear[k] = p(6 + k);
  m.coupling = p(9);
  m.coupling_oblique = p(10);
  return m;
}

// Non-negative least squares: x >= 0 minimizing |A x - b| (Lawson and Hanson's active-set
// method, "Solving Least Squares Problems", 1974, ch. 23).
Eigen::VectorXd non_negative_least_squares(const Eigen::MatrixXd& a, const Eigen::VectorXd& b) {
  const int n = static_cast<int>(a.cols());
  Eigen::VectorXd x = Eigen::VectorXd::Zero(n);
  std::vector<bool> passive(n, false);
  const double tolerance = 1e-12 * a.norm() * std::max(b.norm(), 1e-300);
  auto solve_passive = [&] {
    std::vector<int> index;
    for (int j = 0; j < n; ++j)
      if (passive[j]) index.push_back(j);
    Eigen::MatrixXd sub(a.rows(), static_cast<Eigen::Index>(index.size()));
    for (std::size_t k = 0; k < index.size(); ++k)
      sub.col(static_cast<Eigen::Index>(k)) = a.col(index[k]);
    const Eigen::VectorXd y = sub.completeOrthogonalDecomposition().solve(b);
    Eigen::VectorXd z = Eigen::VectorXd::Zero(n);
    for (std::size_t k = 0; k < index.size(); ++k) z(index[k]) = y(static_cast<Eigen::Index>(k));
    return z;
  };
  for (int outer = 0; outer < 3 * n; ++outer) {
    const Eigen::VectorXd gradient = a.transpose() * (b - a * x);
    int entering = -1;
    double best = tolerance;
    for (int j = 0; j < n; ++j) {
      if (!passive[j] && gradient(j) > best) {
        best = gradient(j);
        entering = j;
      }
    }
    if (entering < 0) break;
    passive[entering] = true;
    for (int inner = 0; inner < 3 * n; ++inner) {
      const Eigen::VectorXd z = solve_passive();
      double alpha = 1;
      bool feasible = true;
      for (int j = 0; j < n; ++j) {
        if (passive[j] && z(j) <= 0) {
          feasible = false;
          alpha = std::min(alpha, x(j) / (x(j) - z(j)));
        }
      }
      if (feasible) {
        x = z;
        break;
      }
      x += alpha * (z - x);
      for (int j = 0; j < n; ++j) {
        if (passive[j] && x(j) <= 1e-15 * std::max(1.0, x.cwiseAbs().maxCoeff())) {
          passive[j] = false;
          x(j) = 0;
        }
      }
    }
  }
  return x;
}

// E_N of a bond with direction cosines (c, s, z) as a linear function of the unknowns.
Unknowns normal_row(double c, double s, double z) {
  const double x1 = c * c, x2 = s * s, x3 = z * z;
  Unknowns row = Unknowns::Zero();
  row.head<6>() << x1 * x1, x2 * x2, x3 * x3, 2 * x1 * x2, 2 * x1 * x3, 2 * x2 * x3;
  row(9) = 2 * c * s;
  row(10) = 2 * c * s * (x1 - x2);
  return row;
}

// Least squares with linear inequality constraints: y minimizing |E y - f| subject to G y >= h,
// for E of full column rank, through least-distance programming and NNLS (Lawson and Hanson,
// ch. 23): with E = U S V^T, z = S V^T y - U^T f turns the problem into min |z| subject to
// (G V S^-1) z >= h - G V S^-1 U^T f, whose solution is read off the NNLS residual.
Eigen::VectorXd constrained_least_squares(const Eigen::MatrixXd& e, const Eigen::VectorXd& f,
                                          const Eigen::MatrixXd& g, const Eigen::VectorXd& h) {
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(e, Eigen::ComputeThinU | Eigen::ComputeThinV);
  const Eigen::MatrixXd k = svd.matrixV() * svd.singularValues().cwiseInverse().asDiagonal();
  const Eigen::VectorXd uf = svd.matrixU().transpose() * f;
  const Eigen::MatrixXd g_hat = g * k;
  const Eigen::VectorXd h_hat = h - g_hat * uf;
  const int n = static_cast<int>(e.cols());
  Eigen::MatrixXd a(n + 1, g.rows());
  a.topRows(n) = g_hat.transpose();
  a.row(n) = h_hat.transpose();
  Eigen::VectorXd b = Eigen::VectorXd::Zero(n + 1);
  b(n) = 1;
  const Eigen::VectorXd u = non_negative_least_squares(a, b);
  const Eigen::VectorXd r = a * u - b;
  if (!(std::abs(r(n)) > 1e-12)) {
    throw Error("lattice: the orientation law's constraints cannot be met");
  }
  const Eigen::VectorXd z = -r.head(n) / r(n);
  return k * (z + uf);
}

// Directions spread evenly over a hemisphere (a Fibonacci lattice), as (c, s, z) cosines.
std::vector<Eigen::Vector3d> hemisphere_directions(int count) {
  std::vector<Eigen::Vector3d> d;
  const double golden = std::numbers::pi * (3 - std::sqrt(5.0));
  for (int k = 0; k < count; ++k) {
    const double z = (k + 0.5) / count;
    const double r = std::sqrt(1 - z * z);
    d.emplace_back(r * std::cos(golden * k), r * std::sin(golden * k), z);
  }
  return d;
}

}  // namespace

// ---------------------------------------------------------------------------------------------

OrientationModuli OrientationModuli::from_paper(const MicroplaneModuli& m) {
  // (1 - c^2) a + c^2 b = b x1 + a (x2 + x3), times x1 + x2 + x3 = 1 to reach degree two.
  const double a = m.normal_transverse, b = m.normal_axial;
  OrientationModuli o;
  o.normal = {b, a, a, 0.5 * (a + b), 0.5 * (a + b), a};
  o.shear = {m.shear_axial, m.shear_transverse, m.shear_transverse};
  return o;
}

double OrientationModuli::normal_modulus(double c, double s, double z) const {
  const double x1 = c * c, x2 = s * s, x3 = z * z;
  return normal[0] * x1 * x1 + normal[1] * x2 * x2 + normal[2] * x3 * x3 +
         2 * (normal[3] * x1 * x2 + normal[4] * x1 * x3 + normal[5] * x2 * x3) +
         2 * c * s * (coupling + (x1 - x2) * coupling_oblique);
}

double OrientationModuli::shear_modulus(double c, double s, double z) const {
  return shear[0] * c * c + shear[1] * s * s + shear[2] * z * z;
}

Matrix6d microplane_stiffness(const OrientationModuli& moduli, const Eigen::Vector3d& fibre) {
  require(std::abs(fibre.norm() - 1) < 1e-9,
          "microplane stiffness: the fibre must be a unit vector");
  const Eigen::Vector3d t = transverse_of(fibre);
  const Eigen::Vector3d w = fibre.cross(t);
  // Product rule exact for polynomials of degree 11 on the sphere: 6 Gauss-Legendre nodes in
  // cos(polar angle) times 12 equally spaced azimuths.
  static const auto rule = [] {
    std::vector<double> node, weight;
    gauss_legendre(6, node, weight);
    return std::make_pair(node, weight);
  }();
  const int azimuths = 12;
  Matrix6d c = Matrix6d::Zero();
  Matrix6d normal, shear;
  for (std::size_t q = 0; q < rule.first.size(); ++q) {
    const double u = rule.first[q], sine = std::sqrt(1 - u * u);
    for (int a = 0; a < azimuths; ++a) {
      const double phi = 2 * std::numbers::pi * a / azimuths;
      const Eigen::Vector3d n(sine * std::cos(phi), sine * std::sin(phi), u);
      const double weight = rule.second[q] * 2 * std::numbers::pi / azimuths;
      projection_tensors(n, normal, shear);
      const double cf = n.dot(fibre), sf = n.dot(t), zf = n.dot(w);
      c += weight *
           (moduli.normal_modulus(cf, sf, zf) * normal + moduli.shear_modulus(cf, sf, zf) * shear);
    }
  }
  return 3.0 / (2.0 * std::numbers::pi) * c;  // eq. (11)
}

Eigen::Matrix<double, 5, 4> microplane_matrix() {
  Eigen::Matrix<double, 5, 4> a;
  for (int k = 0; k < 4; ++k) {
    MicroplaneModuli unit;
    double* moduli[4] = {&unit.normal_transverse, &unit.normal_axial, &unit.shear_transverse,
                         &unit.shear_axial};
    *moduli[k] = 1;
    // The fibre along z, as in the paper; t = y.
    const Matrix6d c =
        microplane_stiffness(OrientationModuli::from_paper(unit), Eigen::Vector3d::UnitZ());
    a.col(k) << c(0, 0), c(2, 2), c(1, 2), c(0, 1), c(3, 3);
  }
  return a;
}

MicroplaneFit fit_microplane_moduli(const Material& material) {
  const Matrix6d c = stiffness_3d(material);  // material axes, 1 = fibre
  // The paper's frame has the fibre along 3: C1111 -> C22, C3333 -> C11, C2233 -> C12,
  // C1122 -> C23, C2323 -> C66 (= G12).
  Eigen::Matrix<double, 5, 1> target;
  target << c(1, 1), c(0, 0), c(0, 1), c(1, 2), c(5, 5);
  const Eigen::Matrix<double, 5, 4> a = microplane_matrix();
  MicroplaneFit fit;
  const Eigen::Vector4d paper = a.topRows<4>().fullPivLu().solve(target.head<4>());
  fit.paper = {paper(0), paper(1), paper(2), paper(3)};
  fit.paper_axial_shear = a.row(4).dot(paper);
  const Eigen::Vector4d clipped = paper.cwiseMax(0.0);
  fit.moduli = {clipped(0), clipped(1), clipped(2), clipped(3)};
  fit.relative_residual = (a * clipped - target).norm() / target.norm();
  return fit;
}

FamilyStiffness lattice_bond_stiffness(const OrientationModuli& moduli,
                                       const Eigen::Vector3d& fibre, const Eigen::Vector3d& branch,
                                       double volume_per_bond, double radius) {
  const double length = branch.norm();
  require(length > 0, "lattice bond of zero length");
  const Eigen::Vector3d n = branch / length;
  const double kappa = 6.0 * volume_per_bond / (length * length);
  const Eigen::Vector3d t = transverse_of(fibre);
  const double c = n.dot(fibre), s = n.dot(t), z = n.dot(fibre.cross(t));
  return with_rotational_springs(kappa * moduli.normal_modulus(c, s, z),
                                 kappa * moduli.shear_modulus(c, s, z), radius);
}

// ---------------------------------------------------------------------------------------------

LatticeStrategy::LatticeStrategy(bool corrected) : corrected_(corrected) {}

std::vector<StrategyOption> LatticeStrategy::options() const {
  return {
      {"seed", static_cast<double>(seed_),
       "random packing seed, an integer in [0, 2^53]; the same seed gives the same packing"},
      {"contact_radius", contact_radius_,
       "I_R of eq. (10): bonds join centres within I_R (r_i + r_j); > 1 (paper: 1.8)"},
      {"packing_fraction", packing_fraction_,
       fmt::format("sphere volume / box volume, in (0, {}] (paper: 0.29)", kMaxPackingFraction)},
      {"sample_diameters", sample_diameters_,
       "edge of the periodic calibration sample in x and y, in particle diameters (>= 8)"},
      {"particle_diameter", particle_diameter_,
       "particle diameter for calibrate() alone [m]; build() uses the coupon's"},
      {"max_error", max_error_,
       "largest relative error of Ex, Ey, Gxy, nu_xy of the corrected sample accepted; beyond "
       "it the strategy refuses"},
      {"tolerance", tolerance_,
       "relative error |relaxed - target| / |target| at which the correction stops"},
  };
}

void LatticeStrategy::set_option(const std::string& name, double value) {
  const std::string what = fmt::format("lattice option {} = {}", name, value);
  if (name == "seed") {
    require(std::isfinite(value) && value >= 0 && value <= 0x1.0p53 && value == std::floor(value),
            fmt::format("{}: the seed must be an integer in [0, 2^53]", what));
    seed_ = static_cast<std::uint64_t>(value);
  } else if (name == "contact_radius") {
    require(std::isfinite(value) && value > 1 && value <= 5,
            fmt::format("{}: the contact radius I_R must lie in (1, 5] (I_R = 1 bonds touching "
                        "spheres only, which a random packing hardly has)",
                        what));
    contact_radius_ = value;
  } else if (name == "packing_fraction") {
    require(std::isfinite(value) && value > 0 && value <= kMaxPackingFraction,
            fmt::format("{}: the packing fraction must lie in (0, {}]", what, kMaxPackingFraction));
    packing_fraction_ = value;
  } else if (name == "sample_diameters") {
    require(std::isfinite(value) && value >= 8 && value <= 200,
            fmt::format("{}: the calibration sample must be 8 to 200 diameters wide", what));
    sample_diameters_ = value;
  } else if (name == "particle_diameter") {
    require(std::isfinite(value) && value > 0,
            fmt::format("{}: the particle diameter must be positive [m]", what));
    particle_diameter_ = value;
  } else if (name == "max_error") {
    require(std::isfinite(value) && value > 0 && value < 1,
            fmt::format("{}: max_error must lie in (0, 1)", what));
    max_error_ = value;
  } else if (name == "tolerance") {
    require(std::isfinite(value) && value > 0 && value < 0.1,
            fmt::format("{}: the tolerance must lie in (0, 0.1)", what));
    tolerance_ = value;
  } else {
    Strategy::set_option(name, value);
  }
}

std::string LatticeStrategy::description() const {
  return corrected_
             ? "3D discrete lattice (paper Sec. 3.1): random packing, bonds within I_R = 1.8, "
               "microplane eq. (15) corrected until a relaxed periodic sample meets Q-bar"
             : "3D discrete lattice as in the paper: random packing, bonds within I_R = 1.8, "
               "eq. (15) microplane moduli, uncorrected (reports its true relaxed stiffness)";
}

RandomPackingSpec LatticeStrategy::coupon_packing(const CouponSpec& coupon) const {
  RandomPackingSpec spec;
  spec.box = Eigen::Vector3d(coupon.length, coupon.width, coupon.thickness);
  spec.periodic = {true, true, false};
  spec.diameter = coupon.particle_diameter;
  spec.packing_fraction = packing_fraction_;
  spec.seed = seed_;
  return spec;
}

std::optional<PackingEstimate> LatticeStrategy::estimate_packing(const CouponSpec& coupon) const {
  coupon.validate();
  RandomPackingSpec spec = coupon_packing(coupon);
  const double d = coupon.particle_diameter;
  // The sample: 12 diameters (4 bond reaches) in x and y, periodic there, and the coupon's
  // thickness up to 12 diameters (a thicker ply's bulk coordination is that of its middle).
  const double edge = std::max(12.0, 3.0 * contact_radius_ + 1.0) * d;
  RandomPackingSpec sample_spec = spec;
  sample_spec.box = Eigen::Vector3d(edge, edge, std::min(coupon.thickness, edge));
  const RandomPacking sample = random_sequential_addition(sample_spec);
  const PackingBonds bonds = bonds_within(sample, contact_radius_);
  const double n = static_cast<double>(sample.position.rows());
  // Mean |branch| along x and y: the share of bonds a cut face of the coupon removes.
  double reach_x = 0, reach_y = 0;
  for (int k = 0; k < bonds.size(); ++k) {
    const auto [i, j] = bonds.pairs[k];
    const Eigen::Vector3d branch =
        (sample.position.row(j) - sample.position.row(i)).transpose().matrix() +
        sample_spec.box.cwiseProduct(bonds.image.row(k).transpose().cast<double>().matrix());
    reach_x += std::abs(branch.x());
    reach_y += std::abs(branch.y());
  }
  const double per_bond = bonds.size() > 0 ? 1.0 / bonds.size() : 0.0;
  reach_x *= per_bond;
  reach_y *= per_bond;
  int top = 0, bottom = 0;
  const double z_max = sample.position.col(2).maxCoeff(), z_min = sample.position.col(2).minCoeff();
  for (int i = 0; i < sample.position.rows(); ++i) {
    top += sample.position(i, 2) >= z_max - 0.5 * d ? 1 : 0;
    bottom += sample.position(i, 2) <= z_min + 0.5 * d ? 1 : 0;
  }
  PackingEstimate e;
  // The coupon's count directly: count() is an int, too small for the largest requests.
  e.particles =
      std::round(spec.packing_fraction * spec.box.prod() / (std::numbers::pi / 6.0 * d * d * d));
  e.bonds = e.particles * (bonds.size() / n) * std::max(0.0, 1.0 - reach_x / coupon.length) *
            std::max(0.0, 1.0 - reach_y / coupon.width);
  e.top_surface_particles = top / (edge * edge) * coupon.length * coupon.width;
  e.bottom_surface_density = bottom / (edge * edge);
  e.layers = std::max(1, static_cast<int>(std::lround(coupon.thickness / d)));
  return e;
}

PeriodicModel LatticeStrategy::calibration_sample(const OrientationModuli& moduli, double ply_angle,
                                                  double thickness, double diameter,
                                                  double density) const {
  const double edge = sample_diameters_ * diameter;
  return periodic_sample(moduli, ply_angle, Eigen::Vector3d(edge, edge, thickness), diameter,
                         density, 0);
}

PeriodicModel LatticeStrategy::periodic_sample(const OrientationModuli& moduli, double ply_angle,
                                               const Eigen::Vector3d& box, double diameter,
                                               double density, double volume_per_bond) const {
  RandomPackingSpec spec;
  spec.box = box;
  spec.periodic = {true, true, false};
  spec.diameter = diameter;
  spec.packing_fraction = packing_fraction_;
  spec.seed = seed_;
  RandomPacking packing = random_sequential_addition(spec);
  PackingBonds bonds = bonds_within(packing, contact_radius_);
  keep_largest_cluster(packing, bonds);
  require(bonds.size() > 0, "lattice: the calibration sample has no bonds");

  PeriodicModel periodic;
  periodic.model = packing_model(packing, bonds, density);
  periodic.lattice_vectors = spec.box.asDiagonal();
  periodic.periodic = {true, true, false};
  periodic.bond_image = bonds.image;
  periodic.volume = spec.box.prod();
  if (!(volume_per_bond > 0)) volume_per_bond = periodic.volume / bonds.size();
  const BondLawGeometry g =
      law_geometry(periodic.model.bonds, fibre_at(ply_angle), volume_per_bond);
  apply_law(moduli, g, 0.5 * diameter, nullptr, periodic.model.bonds);
  periodic.model.description = fmt::format("lattice periodic sample, {} particles, {} bonds",
                                           packing.position.rows(), bonds.size());
  return periodic;
}

namespace {

// Admissible laws, all linear constraints (matrix) p >= bound: E_N >= 0 along every bond of the
// sample and along 2000 directions of a hemisphere (E_N is even in n), so that any coupon's bonds
// are covered; E_T >= `shear_floor` in every direction, i.e. each shear coefficient >= it (a
// particle needs some shear spring, or the spins of all particles together turn freely).
struct LawConstraints {
  Eigen::MatrixXd matrix;
  Eigen::VectorXd bound;
};

LawConstraints admissible_laws(const BondLawGeometry& g, int bonds, double shear_floor) {
  std::vector<Unknowns> rows;
  for (const Eigen::Vector3d& d : hemisphere_directions(2000)) {
    rows.push_back(normal_row(d(0), d(1), d(2)));
  }
  for (int b = 0; b < bonds; ++b) rows.push_back(normal_row(g.c(b), g.s(b), g.z(b)));
  LawConstraints out;
  out.matrix.resize(static_cast<Eigen::Index>(rows.size()) + 3, kUnknowns);
  out.bound = Eigen::VectorXd::Zero(out.matrix.rows());
  for (std::size_t r = 0; r < rows.size(); ++r) {
    out.matrix.row(static_cast<Eigen::Index>(r)) = rows[r].transpose();
  }
  for (int k = 0; k < 3; ++k) {
    const Eigen::Index r = static_cast<Eigen::Index>(rows.size()) + k;
    out.matrix.row(r).setZero();
    out.matrix(r, 6 + k) = 1;
    out.bound(r) = shear_floor;
  }
  return out;
}

// The sample's relaxed in-plane stiffness under the law of unknowns q and, with a Jacobian, its
// exact derivative in them: by the envelope theorem d(relaxed)/d(k) of each bond comes from the
// relaxed bond deformations of the same solve. Counts the homogenizations in `evaluations`.
class SampleResponse {
 public:
  SampleResponse(Model& model, const BondLawGeometry& g, double radius, RelaxedLayer& homogenizer,
                 int& evaluations)
      : model_(model),
        g_(g),
        radius_(radius),
        homogenizer_(homogenizer),
        evaluations_(evaluations) {}

  Eigen::Matrix3d operator()(const Unknowns& q, Jacobian* jacobian) {
    apply_law(moduli_of(q), g_, radius_, nullptr, model_.bonds);
    ++evaluations_;
    const Eigen::Matrix3d c =
        in_plane_block(homogenizer_.relaxed(jacobian ? &sensitivity_ : nullptr, radius_));
    if (jacobian) {
      jacobian->setZero();
      for (int b = 0; b < model_.bonds.size(); ++b) {
        const Unknowns row = normal_row(g_.c(b), g_.s(b), g_.z(b));
        const Entries dn = g_.kappa(b) * weighted_entries(sensitivity_.normal[b]);
        const Entries ds = g_.kappa(b) * weighted_entries(sensitivity_.shear[b]);
        *jacobian += dn * row.transpose();
        jacobian->col(6) += g_.c(b) * g_.c(b) * ds;
        jacobian->col(7) += g_.s(b) * g_.s(b) * ds;
        jacobian->col(8) += g_.z(b) * g_.z(b) * ds;
      }
    }
    return c;
  }

 private:
  Model& model_;
  const BondLawGeometry& g_;
  double radius_;
  RelaxedLayer& homogenizer_;
  int& evaluations_;
  RelaxedLayer::Sensitivity sensitivity_;
};

// What the correction reached: the law's unknowns, the sample's relaxed in-plane stiffness with
// them, and the Gauss-Newton steps taken.
struct LawCorrection {
  Unknowns law;
  Eigen::Matrix3d relaxed;
  int iterations = 0;
};

// Gauss-Newton on the six independent entries of the relaxed in-plane stiffness (weighted to give
// the Frobenius norm) over the eleven coefficients of the orientation law, from `origin`. The
// system is underdetermined; each step is the smallest (relative change per coefficient) that
// zeroes the linearized error, subject to the law staying admissible; Levenberg-Marquardt damping
// of the relative step is raised when a step fails to lower the error, lowered when it succeeds.
// Stops at `tolerance`, or when five steps have gained less than 0.1% of the error (the law cannot
// get closer: the constraints hold it), or after 100 steps.
LawCorrection correct_law(SampleResponse& evaluate, const Unknowns& origin,
                          const LawConstraints& admissible, double shear_floor,
                          const Eigen::Matrix3d& target, double tolerance, int particles) {
  const double unit = origin.cwiseAbs().maxCoeff();
  const Unknowns weight = origin.cwiseAbs().cwiseMax(0.1 * unit);
  const Entries goal = weighted_entries(target);
  const double goal_norm = goal.norm();
  LawCorrection out;
  Unknowns& p = out.law;
  p = origin;
  for (int k = 6; k < 9; ++k) p(k) = std::max(p(k), shear_floor);
  Jacobian jacobian;
  out.relaxed = evaluate(p, &jacobian);
  Entries residual = weighted_entries(out.relaxed) - goal;
  double damping = 1e-4;
  int failures = 0;
  std::vector<double> history{residual.norm()};
  ProgressMeter meter(fmt::format("calibrating the lattice on its {}-particle sample", particles),
                      0, "Gauss-Newton steps");
  while (residual.norm() / goal_norm >= tolerance && out.iterations < 100 && failures < 12 &&
         !(history.size() > 5 && history.back() > 0.999 * history[history.size() - 6])) {
    ++out.iterations;
    // In units of the largest paper modulus, so that the least-distance problem is well scaled.
    Eigen::MatrixXd e(6 + kUnknowns, kUnknowns);
    Eigen::VectorXd f(6 + kUnknowns);
    e.topRows<6>() = jacobian * unit / goal_norm;
    f.head<6>() = (jacobian * p - residual) / goal_norm;
    e.bottomRows<kUnknowns>() =
        std::sqrt(damping) * unit * weight.cwiseInverse().asDiagonal().toDenseMatrix();
    f.tail<kUnknowns>() = std::sqrt(damping) * p.cwiseQuotient(weight);
    const Unknowns trial =
        unit * constrained_least_squares(e, f, admissible.matrix, admissible.bound / unit);
    Jacobian trial_jacobian;
    const Eigen::Matrix3d c = evaluate(trial, &trial_jacobian);
    const Entries r = weighted_entries(c) - goal;
    if (r.norm() < residual.norm()) {
      p = trial;
      out.relaxed = c;
      residual = r;
      jacobian = trial_jacobian;
      damping = std::max(damping / 4, 1e-12);
      failures = 0;
    } else {
      damping *= 8;
      ++failures;
    }
    history.push_back(residual.norm());
    meter.update(out.iterations, fmt::format("relative error {:.3g} (stops below {:.3g})",
                                             residual.norm() / goal_norm, tolerance));
  }
  return out;
}

// The calibration's one-line account of the law and the sample.
std::string calibration_method(const LatticeCalibration& out, bool corrected) {
  const OrientationModuli& m = out.moduli;
  return fmt::format(
      "{}; E_N Bernstein coefficients (b11 b22 b33 b12 b13 b23) {:.4g} GPa, E_T (t1 t2 t3) {:.4g} "
      "GPa, couplings {:.3g} {:.3g} GPa; periodic sample {:.3g} x {:.3g} x {:.3g} mm, {} "
      "particles, {} bonds, coordination {:.2f}",
      corrected ? fmt::format("lattice: eq. (15) moduli corrected on the relaxed sample in {} "
                              "Gauss-Newton steps",
                              out.iterations)
                : std::string("lattice-paper: eq. (15) moduli, negative ones set to zero"),
      fmt::join(Eigen::Map<const Eigen::Matrix<double, 6, 1>>(m.normal.data()) * kGPaPerPa, " "),
      fmt::join(Eigen::Map<const Eigen::Vector3d>(m.shear.data()) * kGPaPerPa, " "),
      m.coupling * kGPaPerPa, m.coupling_oblique * kGPaPerPa, out.sample_box(0) * kMmPerMetre,
      out.sample_box(1) * kMmPerMetre, out.sample_box(2) * kMmPerMetre, out.sample_particles,
      out.sample_bonds, out.sample_coordination);
}

}  // namespace

LatticeCalibration LatticeStrategy::calibrate_lattice(const Material& material, double ply_angle,
                                                      double thickness, double diameter,
                                                      const Eigen::Vector2d* sample_size,
                                                      const OrientationModuli* start_law) const {
  const Stopwatch clock;
  validate(material);
  require(std::isfinite(ply_angle), "ply angle is not finite");
  require(std::isfinite(thickness) && thickness > 0,
          fmt::format("ply thickness must be positive, got {} m", thickness));
  require(std::isfinite(diameter) && diameter > 0,
          fmt::format("particle diameter must be positive, got {} m", diameter));

  LatticeCalibration out;
  Calibration& cal = out.calibration;
  cal.lattice_angle = ply_angle;
  cal.target = rotate_reduced_stiffness(reduced_stiffness(material), ply_angle);
  out.fit = fit_microplane_moduli(material);
  const OrientationModuli paper = OrientationModuli::from_paper(out.fit.moduli);

  PeriodicModel sample =
      sample_size ? periodic_sample(paper, ply_angle,
                                    Eigen::Vector3d(sample_size->x(), sample_size->y(), thickness),
                                    diameter, material.density, 0)
                  : calibration_sample(paper, ply_angle, thickness, diameter, material.density);
  Model& model = sample.model;
  out.sample_particles = model.particles.size();
  out.sample_bonds = model.bonds.size();
  out.sample_coordination = 2.0 * out.sample_bonds / out.sample_particles;
  out.sample_box = sample.lattice_vectors.diagonal();
  out.volume_per_bond = sample.volume / out.sample_bonds;
  const BondLawGeometry g = law_geometry(model.bonds, fibre_at(ply_angle), out.volume_per_bond);
  const double radius = 0.5 * diameter;

  RelaxedLayer homogenizer(sample);
  apply_law(paper, g, radius, nullptr, model.bonds);
  ++out.evaluations;
  out.relaxed_uncorrected = in_plane_block(homogenizer.relaxed());
  out.affine_uncorrected = in_plane_block(affine_layer(model, sample.volume));
  out.moduli = paper;
  Eigen::Matrix3d relaxed = out.relaxed_uncorrected;

  if (corrected_) {
    // The correction starts from the paper's law (or `start_law`); the shear coefficients are
    // held at 1% of E2 or more.
    const Unknowns origin = unknowns_of(start_law ? *start_law : paper);
    const double shear_floor =
        (std::getenv("PLYDEM_FLOOR") ? std::atof(std::getenv("PLYDEM_FLOOR")) : 0.01) * material.E2;
    const LawConstraints admissible = admissible_laws(g, model.bonds.size(), shear_floor);
    SampleResponse response(model, g, radius, homogenizer, out.evaluations);
    const LawCorrection corrected = correct_law(response, origin, admissible, shear_floor,
                                                cal.target, tolerance_, model.particles.size());
    out.iterations = corrected.iterations;
    relaxed = corrected.relaxed;
    out.moduli = moduli_of(corrected.law);
    apply_law(out.moduli, g, radius, nullptr, model.bonds);
  }
  cal.relaxed = relaxed;
  cal.relaxed_error = relative_difference(relaxed, cal.target);
  cal.affine = in_plane_block(affine_layer(model, sample.volume));
  cal.families = orientation_families(model.bonds, g, ply_angle);
  cal.method = calibration_method(out, corrected_);
  out.seconds = clock.seconds();
  return out;
}

void LatticeStrategy::check_reached(const LatticeCalibration& cal, const Material& material,
                                    double ply_angle, double thickness) const {
  if (!corrected_) return;  // lattice-paper reports its error; it does not promise the target
  const InPlaneConstants reached = in_plane_constants(cal.calibration.relaxed);
  const InPlaneConstants target = in_plane_constants(cal.calibration.target);
  struct Component {
    const char* name;
    double reached, target;
  };
  const Component components[] = {{"Ex", reached.Ex, target.Ex},
                                  {"Ey", reached.Ey, target.Ey},
                                  {"Gxy", reached.Gxy, target.Gxy},
                                  {"nu_xy", reached.nu_xy, target.nu_xy}};
  std::string missed;
  for (const Component& c : components) {
    const double error = (c.reached - c.target) / std::abs(c.target);
    if (std::abs(error) > max_error_) {
      const bool modulus = c.name[0] != 'n';
      missed += fmt::format(
          "{}{} = {:.4g}{} where the target is {:.4g}{} ({:+.2f}%)", missed.empty() ? "" : "; ",
          c.name, c.reached * (modulus ? kGPaPerPa : 1), modulus ? " GPa" : "",
          c.target * (modulus ? kGPaPerPa : 1), modulus ? " GPa" : "", 100 * error);
    }
  }
  if (!missed.empty()) {
    Unreachable refusal;
    refusal.strategy = "lattice";
    refusal.material = material.name;
    refusal.ply_angle = ply_angle;
    refusal.reason = fmt::format(
        "the random packing with non-negative bonds: after the automatic correction ({} steps) "
        "the sample has {} (the nearest the orientation law reaches; tolerance max_error = "
        "{:.3g}, which --strategy-option max_error=... relaxes)",
        cal.iterations, missed, max_error_);
    refusal.frame = "specimen frame";
    refusal.target = cal.calibration.target;
    refusal.nearest = cal.calibration.relaxed;
    refuse_unreachable(std::move(refusal), material, thickness);
  }
}

Calibration LatticeStrategy::calibrate(const Material& material, double ply_angle,
                                       double thickness) const {
  const LatticeCalibration cal =
      calibrate_lattice(material, ply_angle, thickness, particle_diameter_);
  check_reached(cal, material, ply_angle, thickness);
  return cal.calibration;
}

std::string LatticeStrategy::calibration_key(const CouponSpec& coupon) const {
  // The coupon's own packing is the calibration sample: its size and sphere diameter belong to it.
  return fmt::format("{}|size {:a} x {:a}|diameter {:a}", Strategy::calibration_key(coupon),
                     coupon.length, coupon.width, coupon.particle_diameter);
}

Calibration LatticeStrategy::calibrate_coupon(const CouponSpec& coupon) const {
  coupon.validate();
  // The coupon's packing is made periodic in x and y, so that it is its own calibration sample:
  // a random network's stiffness differs from one realization to the next by several percent at
  // these sizes (a 16-diameter sample calibrated exactly gives Ex from 38 to 47 GPa on other
  // seeds), so the correction measures and corrects this very packing. The coupon is then the
  // sample with the bonds across the periodic faces cut.
  const Eigen::Vector2d size(coupon.length, coupon.width);
  LatticeCalibration cal;
  if (corrected_) {
    const LatticeCalibration start = calibrate_lattice(coupon.material, coupon.ply_angle,
                                                       coupon.thickness, coupon.particle_diameter);
    // A target the law cannot reach on the small sample is refused before the coupon's own,
    // slower correction.
    check_reached(start, coupon.material, coupon.ply_angle, coupon.thickness);
    cal = calibrate_lattice(coupon.material, coupon.ply_angle, coupon.thickness,
                            coupon.particle_diameter, &size, &start.moduli);
    cal.iterations += start.iterations;
    cal.evaluations += start.evaluations;
  } else {
    cal = calibrate_lattice(coupon.material, coupon.ply_angle, coupon.thickness,
                            coupon.particle_diameter, &size);
  }
  check_reached(cal, coupon.material, coupon.ply_angle, coupon.thickness);
  auto law = std::make_shared<LatticeLaw>();
  law->moduli = cal.moduli;
  law->volume_per_bond = cal.volume_per_bond;
  law->coupon_key = calibration_key(coupon);
  cal.calibration.detail = std::move(law);
  return cal.calibration;
}

Model LatticeStrategy::assemble(const CouponSpec& coupon, const Calibration& calibration) const {
  const auto* law = dynamic_cast<const LatticeLaw*>(calibration.detail.get());
  require(law != nullptr,
          "lattice: a coupon is built with the calibration of its own packing "
          "(LatticeStrategy::calibrate_coupon), which this calibration is not");
  require(law->coupon_key == calibration_key(coupon),
          "lattice: the calibration given was computed for another coupon (size, particle "
          "diameter, ply or options differ); the coupon's own packing is its calibration sample");
  RandomPackingSpec spec = coupon_packing(coupon);
  RandomPacking packing = random_sequential_addition(spec);
  PackingBonds all_bonds = bonds_within(packing, contact_radius_);
  keep_largest_cluster(packing, all_bonds);
  PackingBonds bonds;
  for (int k = 0; k < all_bonds.size(); ++k) {
    if ((all_bonds.image.row(k) == 0).all()) bonds.pairs.push_back(all_bonds.pairs[k]);
  }
  bonds.image.setZero(bonds.size(), 3);
  const int removed = keep_largest_cluster(packing, bonds);
  const int n = static_cast<int>(packing.position.rows());
  require(n >= 2 && bonds.size() > 0, "lattice: the coupon holds fewer than two bonded particles");

  Model model = packing_model(packing, bonds, coupon.material.density);
  // The sample's volume per bond: the periodic packing, before its periodic bonds were cut.
  const double volume_per_bond = law->volume_per_bond;
  const Eigen::Vector3d fibre = fibre_at(coupon.ply_angle);
  const BondLawGeometry g = law_geometry(model.bonds, fibre, volume_per_bond);
  std::optional<Eigen::ArrayXd> scale;
  if (coupon.complete_boundary_cells) {
    // Bonds near the coupon's edges carry the share of the neighbours beyond the edge that the
    // calibration sample (periodic in x and y) has: (s_i + s_j) / 2 with s the ratio of the
    // neighbourhood ball inside the sample's slab to that inside the coupon.
    const NeighbourhoodFraction fraction;
    const double reach = contact_radius_ * coupon.particle_diameter;
    Eigen::ArrayXd s(n);
    for (int i = 0; i < n; ++i) {
      s(i) = fraction.completion(packing.position.row(i).transpose(), spec.box, reach);
    }
    scale.emplace(model.bonds.size());
    for (int b = 0; b < model.bonds.size(); ++b) {
      (*scale)(b) = 0.5 * (s(model.bonds.first(b)) + s(model.bonds.second(b)));
    }
  }
  const auto [min_normal, min_shear] = apply_law(law->moduli, g, 0.5 * coupon.particle_diameter,
                                                 scale ? &*scale : nullptr, model.bonds);
  // apply_law set slightly negative k_n to zero; a clearly negative one is refused.
  const double mean_normal = model.bonds.normal_stiffness.mean();
  if (!(min_normal >= -1e-2 * mean_normal && min_shear >= 0)) {
    throw Error(fmt::format(
        "lattice: a coupon bond got a negative stiffness (k_n {:.3g}, k_s {:.3g} N/m; mean k_n "
        "{:.3g} N/m): the corrected orientation law is not admissible in that bond's direction",
        min_normal, min_shear, mean_normal));
  }
  for (int b = 0; b < model.bonds.size(); ++b) model.bonds.family(b) = orientation_bin(g.c(b));
  model.description = fmt::format(
      "{} random packing, ply angle {:.4g} deg, {} particles ({} loose removed), {} bonds, "
      "coordination {:.2f}, seed {}",
      corrected_ ? "lattice" : "lattice-paper", coupon.ply_angle / kDegree, n, removed,
      model.bonds.size(), 2.0 * model.bonds.size() / n, seed_);
  model.check_consistency();
  return model;
}

void register_lattice(Registry& registry) {
  registry.add("lattice", LatticeStrategy(true).description(),
               [] { return std::make_unique<LatticeStrategy>(true); });
  registry.add("lattice-paper", LatticeStrategy(false).description(),
               [] { return std::make_unique<LatticeStrategy>(false); });
}

}  // namespace plydem
