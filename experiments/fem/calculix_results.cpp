// Reading CalculiX's results: the job.dat tables (displacements, the grips' reaction totals,
// element stresses), the measurements run_calculix makes of them, and the displacement field's
// interpolation anywhere in the plate.
#include "experiments/fem/calculix.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "experiments/fem/calculix_detail.hpp"

namespace plydem {
namespace calculix_detail {
namespace {

// A number as ccx's Fortran E format writes it; a three-digit exponent loses its 'E'
// ("1.234567-100").
double parse_number(const std::string& token, int line_number) {
  std::string text = token;
  if (text.find_first_of("eEdD") == std::string::npos) {
    const auto sign = text.find_last_of("+-");
    if (sign != std::string::npos && sign > 0) {
      text = fmt::format("{}E{}", text.substr(0, sign), text.substr(sign));
    }
  }
  std::replace(text.begin(), text.end(), 'D', 'E');
  std::replace(text.begin(), text.end(), 'd', 'E');
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  if (text.empty() || end != text.c_str() + text.size() || !std::isfinite(value))
    throw Error(
        fmt::format("CalculiX .dat line {}: '{}' is not a finite number", line_number, token));
  return value;
}

// Least-squares fit of u = a + g_x (x - x0) + g_y (y - y0) over points (x, y): returns (g_x, g_y).
Eigen::Vector2d fit_gradient(const std::vector<Eigen::Vector2d>& points,
                             const std::vector<double>& values) {
  const int n = static_cast<int>(points.size());
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (const auto& p : points) mean += p;
  mean /= n;
  Eigen::MatrixXd design(n, 3);
  Eigen::VectorXd rhs(n);
  for (int k = 0; k < n; ++k) {
    design(k, 0) = 1;
    design.block<1, 2>(k, 1) = (points[k] - mean).transpose();
    rhs(k) = values[k];
  }
  const auto qr = design.colPivHouseholderQr();
  if (qr.rank() < 3) throw Error("the FEM gauge-section nodes are collinear: no strain fit");
  const Eigen::Vector3d coef = qr.solve(rhs);
  return coef.tail<2>();
}

// Mid-plane strains of the gauge section (less the edge bands), and its mean thickness strain.
void measure_gauge_strains(const FemSpecimen& specimen, const FemSettings& settings,
                           const FemMesh& mesh, const DatResults& dat, FemSolution& solution) {
  const double h = specimen.thickness();
  const MidPlane mid = mid_plane(mesh.level_z);
  const int top = static_cast<int>(mesh.level_z.size()) - 1;
  const double gauge_half = 0.5 * settings.gauge_fraction * specimen.length;
  std::vector<Eigen::Vector2d> points;
  std::vector<double> ux, uy;
  double thickness_strain = 0;
  for (int p = 0; p < mesh.plane_position.rows(); ++p) {
    if (std::abs(mesh.plane_position(p, 0) - 0.5 * specimen.length) > gauge_half * (1 + 1e-12))
      continue;
    const double y = mesh.plane_position(p, 1);
    if (y < settings.edge_band * (1 - 1e-12) ||
        y > specimen.width - settings.edge_band * (1 - 1e-12))
      continue;
    const Eigen::Vector3d below =
        dat.displacement.row(mesh.level_node(p, mid.lower)).matrix().transpose();
    const Eigen::Vector3d above =
        dat.displacement.row(mesh.level_node(p, mid.lower + 1)).matrix().transpose();
    const Eigen::Vector3d u = (1 - mid.weight) * below + mid.weight * above;
    points.emplace_back(mesh.plane_position(p, 0), mesh.plane_position(p, 1));
    ux.push_back(u.x());
    uy.push_back(u.y());
    thickness_strain += (dat.displacement(mesh.level_node(p, top), 2) -
                         dat.displacement(mesh.level_node(p, 0), 2)) /
                        h;
  }
  if (points.size() < 3)
    throw Error(
        fmt::format("the FEM gauge section ({} of the length, less {} m edge bands) holds "
                    "only {} node columns: refine the mesh, widen the gauge or narrow the "
                    "bands",
                    settings.gauge_fraction, settings.edge_band, points.size()));
  const Eigen::Vector2d grad_x = fit_gradient(points, ux);
  const Eigen::Vector2d grad_y = fit_gradient(points, uy);
  solution.exx = grad_x.x();
  solution.eyy = grad_y.y();
  solution.gamma_xy = grad_x.y() + grad_y.x();
  solution.ezz = thickness_strain / static_cast<double>(points.size());
}

// Per element: the centroid of its nodes and the mean of its integration-point stresses.
void average_element_stresses(const FemMesh& mesh, const DatResults& dat, FemSolution& solution) {
  solution.element_centroid = Vector3Array::Zero(mesh.element_count(), 3);
  solution.element_stress.resize(mesh.element_count(), 6);
  solution.element_ply = mesh.element_ply;
  for (int e = 0; e < mesh.element_count(); ++e) {
    if (dat.stress_points(e) == 0)
      throw Error(fmt::format("CalculiX's job.dat lacks the stresses of element {}", e + 1));
    solution.element_stress.row(e) = dat.stress_sum.row(e) / dat.stress_points(e);
    for (int c = 0; c < mesh.element_nodes.cols(); ++c)
      solution.element_centroid.row(e) += mesh.node_position.row(mesh.element_nodes(e, c));
    solution.element_centroid.row(e) /= static_cast<double>(mesh.element_nodes.cols());
  }
}

}  // namespace

DatResults parse_dat(const std::string& text, int nodes, int elements, bool stresses) {
  DatResults r;
  r.displacement = Vector3Array::Zero(nodes, 3);
  r.seen.assign(nodes, false);
  if (stresses) {
    r.stress_sum = Eigen::Array<double, Eigen::Dynamic, 6>::Zero(elements, 6);
    r.stress_points = Eigen::ArrayXi::Zero(elements);
  }
  enum class Section { kNone, kDisplacement, kLeft, kRight, kStress } section = Section::kNone;
  std::istringstream in(text);
  std::string line;
  int line_number = 0;
  std::vector<std::string> tokens;
  while (std::getline(in, line)) {
    ++line_number;
    if (line.find("displacements (vx,vy,vz) for set NALL") != std::string::npos) {
      section = Section::kDisplacement;
      continue;
    }
    if (line.find("total force (fx,fy,fz) for set LEFT") != std::string::npos) {
      section = Section::kLeft;
      continue;
    }
    if (line.find("total force (fx,fy,fz) for set RIGHT") != std::string::npos) {
      section = Section::kRight;
      continue;
    }
    if (line.find("stresses (elem, integ.pnt.") != std::string::npos) {
      section = Section::kStress;
      continue;
    }
    if (line.find(" for set ") != std::string::npos) {
      section = Section::kNone;
      continue;
    }
    tokens.clear();
    std::istringstream words(line);
    for (std::string word; words >> word;) tokens.push_back(word);
    if (tokens.empty() || section == Section::kNone) continue;
    auto bad_line = [&] {
      return Error(
          fmt::format("CalculiX .dat line {} is not what plydem expects: '{}'", line_number, line));
    };
    switch (section) {
      case Section::kDisplacement: {
        if (tokens.size() != 4) throw bad_line();
        const int id = std::atoi(tokens[0].c_str());
        if (id < 1 || id > nodes) throw bad_line();
        for (int c = 0; c < 3; ++c)
          r.displacement(id - 1, c) = parse_number(tokens[c + 1], line_number);
        r.seen[id - 1] = true;
        break;
      }
      case Section::kLeft:
      case Section::kRight: {
        if (tokens.size() != 3) throw bad_line();
        Eigen::Vector3d f;
        for (int c = 0; c < 3; ++c) f(c) = parse_number(tokens[c], line_number);
        (section == Section::kLeft ? r.left_force : r.right_force) = f;
        (section == Section::kLeft ? r.left_seen : r.right_seen) = true;
        section = Section::kNone;
        break;
      }
      case Section::kStress: {
        if (!stresses) break;
        if (tokens.size() != 8) throw bad_line();
        const int id = std::atoi(tokens[0].c_str());
        if (id < 1 || id > elements) throw bad_line();
        for (int c = 0; c < 6; ++c)
          r.stress_sum(id - 1, c) += parse_number(tokens[c + 2], line_number);
        ++r.stress_points(id - 1);
        break;
      }
      case Section::kNone:
        break;
    }
  }
  return r;
}

void measure_solution(const FemSpecimen& specimen, const FemSettings& settings, const FemMesh& mesh,
                      const DatResults& dat, FemSolution& solution) {
  const long missing = std::count(dat.seen.begin(), dat.seen.end(), false);
  if (missing > 0 || !dat.left_seen || !dat.right_seen)
    throw Error(fmt::format("CalculiX's job.dat lacks {} of {} node displacements{}", missing,
                            mesh.node_count(),
                            dat.left_seen && dat.right_seen ? "" : " or a grip's reaction total"));
  solution.nodes = mesh.node_count();
  solution.elements = mesh.element_count();
  solution.degrees_of_freedom = 3 * mesh.node_count();
  solution.reaction_force = 0.5 * (dat.right_force.x() - dat.left_force.x());
  const double h = specimen.thickness();
  solution.gross_stress = solution.reaction_force / (specimen.width * h);
  measure_gauge_strains(specimen, settings, mesh, dat, solution);
  if (settings.element_stresses) average_element_stresses(mesh, dat, solution);
  solution.displacement = FemDisplacementField(mesh, dat.displacement);
}

}  // namespace calculix_detail

FemDisplacementField::FemDisplacementField(const FemMesh& mesh, Vector3Array displacement)
    : node_position_(mesh.node_position),
      node_displacement_(std::move(displacement)),
      plane_position_(mesh.plane_position),
      plane_quad_(mesh.plane_quad),
      level_z_(mesh.level_z),
      level_node_(mesh.level_node) {
  require(node_displacement_.rows() == node_position_.rows(),
          fmt::format("{} displacements for a mesh of {} nodes", node_displacement_.rows(),
                      node_position_.rows()));
  require(plane_quad_.rows() > 0 && level_z_.size() >= 2, "the FEM mesh is empty");
  const Eigen::Vector2d lo = plane_position_.colwise().minCoeff().matrix().transpose();
  const Eigen::Vector2d hi = plane_position_.colwise().maxCoeff().matrix().transpose();
  const double area = (hi - lo).prod();
  // About one quadrilateral per bucket on average.
  bucket_size_ = std::sqrt(area / static_cast<double>(plane_quad_.rows()));
  bucket_origin_ = lo;
  buckets_x_ = std::max(1, static_cast<int>(std::ceil((hi.x() - lo.x()) / bucket_size_)));
  buckets_y_ = std::max(1, static_cast<int>(std::ceil((hi.y() - lo.y()) / bucket_size_)));
  bucket_quads_.assign(static_cast<std::size_t>(buckets_x_) * buckets_y_, {});
  auto cell = [&](double v, double origin, int count) {
    return std::clamp(static_cast<int>(std::floor((v - origin) / bucket_size_)), 0, count - 1);
  };
  for (int q = 0; q < plane_quad_.rows(); ++q) {
    Eigen::Vector2d qlo = Eigen::Vector2d::Constant(INFINITY), qhi = -qlo;
    for (int c = 0; c < 4; ++c) {
      const Eigen::Vector2d p = plane_position_.row(plane_quad_(q, c)).matrix().transpose();
      qlo = qlo.cwiseMin(p);
      qhi = qhi.cwiseMax(p);
    }
    for (int i = cell(qlo.x(), lo.x(), buckets_x_); i <= cell(qhi.x(), lo.x(), buckets_x_); ++i)
      for (int j = cell(qlo.y(), lo.y(), buckets_y_); j <= cell(qhi.y(), lo.y(), buckets_y_); ++j)
        bucket_quads_[static_cast<std::size_t>(j) * buckets_x_ + i].push_back(q);
  }
}

std::optional<Eigen::Vector3d> FemDisplacementField::at(double x, double y, double z) const {
  if (empty() || !std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z)) return std::nullopt;
  const double z_tol = 1e-9 * (level_z_.back() - level_z_.front());
  if (z < level_z_.front() - z_tol || z > level_z_.back() + z_tol) return std::nullopt;
  int level = 0;
  while (level + 2 < static_cast<int>(level_z_.size()) && z > level_z_[level + 1]) ++level;
  const double wz =
      std::clamp((z - level_z_[level]) / (level_z_[level + 1] - level_z_[level]), 0.0, 1.0);

  const double tol = 1e-9 * bucket_size_;
  const double fx = (x - bucket_origin_.x()) / bucket_size_;
  const double fy = (y - bucket_origin_.y()) / bucket_size_;
  if (fx < -1e-9 || fy < -1e-9 || fx > buckets_x_ + 1e-9 || fy > buckets_y_ + 1e-9)
    return std::nullopt;
  const int i = std::clamp(static_cast<int>(std::floor(fx)), 0, buckets_x_ - 1);
  const int j = std::clamp(static_cast<int>(std::floor(fy)), 0, buckets_y_ - 1);
  const Eigen::Vector2d target(x, y);
  static constexpr double kXi[4] = {-1, 1, 1, -1};
  static constexpr double kEta[4] = {-1, -1, 1, 1};
  for (int q : bucket_quads_[static_cast<std::size_t>(j) * buckets_x_ + i]) {
    Eigen::Vector2d corner[4];
    Eigen::Vector2d lo = Eigen::Vector2d::Constant(INFINITY), hi = -lo;
    for (int c = 0; c < 4; ++c) {
      corner[c] = plane_position_.row(plane_quad_(q, c)).matrix().transpose();
      lo = lo.cwiseMin(corner[c]);
      hi = hi.cwiseMax(corner[c]);
    }
    if ((target.array() < lo.array() - tol).any() || (target.array() > hi.array() + tol).any())
      continue;
    // Invert the bilinear map by Newton's method.
    double xi = 0, eta = 0;
    for (int iteration = 0; iteration < 30; ++iteration) {
      Eigen::Vector2d mapped = Eigen::Vector2d::Zero();
      Eigen::Matrix2d jacobian = Eigen::Matrix2d::Zero();
      for (int c = 0; c < 4; ++c) {
        const double n = 0.25 * (1 + kXi[c] * xi) * (1 + kEta[c] * eta);
        mapped += n * corner[c];
        jacobian.col(0) += 0.25 * kXi[c] * (1 + kEta[c] * eta) * corner[c];
        jacobian.col(1) += 0.25 * kEta[c] * (1 + kXi[c] * xi) * corner[c];
      }
      const Eigen::Vector2d step = jacobian.fullPivLu().solve(target - mapped);
      xi += step.x();
      eta += step.y();
      if (step.norm() < 1e-13) break;
    }
    if (!(std::abs(xi) <= 1 + 1e-9 && std::abs(eta) <= 1 + 1e-9)) continue;
    Eigen::Vector3d u = Eigen::Vector3d::Zero();
    for (int c = 0; c < 4; ++c) {
      const double n = 0.25 * (1 + kXi[c] * xi) * (1 + kEta[c] * eta);
      const int p = plane_quad_(q, c);
      u += n * ((1 - wz) * node_displacement_.row(level_node_(p, level)).matrix().transpose() +
                wz * node_displacement_.row(level_node_(p, level + 1)).matrix().transpose());
    }
    return u;
  }
  return std::nullopt;
}

FieldComparison compare_displacements(const FemDisplacementField& fem, const Particles& particles,
                                      double z_offset) {
  require(!fem.empty(), "the FEM displacement field is empty (was CalculiX run?)");
  require(std::isfinite(z_offset), "the particles' mid-plane offset is not finite");
  FieldComparison result;
  std::vector<Eigen::Vector2d> fem_u, particle_u;
  for (int i = 0; i < particles.size(); ++i) {
    const auto u = fem.at(particles.reference_position(i, 0), particles.reference_position(i, 1),
                          particles.reference_position(i, 2) - z_offset);
    if (!u) {
      ++result.skipped;
      continue;
    }
    fem_u.emplace_back(u->x(), u->y());
    particle_u.emplace_back(particles.displacement(i, 0), particles.displacement(i, 1));
  }
  result.points = static_cast<int>(fem_u.size());
  if (result.points < 2)
    throw Error(
        fmt::format("only {} of {} particles lie inside the FEM plate: are the two models in "
                    "the same frame ([0, L] x [0, W], mid-plane z = 0)?",
                    result.points, particles.size()));
  const double n = result.points;
  double fem_uy_mean = 0, shift = 0;
  for (int k = 0; k < result.points; ++k) {
    fem_uy_mean += fem_u[k].y() / n;
    shift += (particle_u[k].y() - fem_u[k].y()) / n;
  }
  double dx = 0, fx = 0, dy = 0, fy = 0;
  for (int k = 0; k < result.points; ++k) {
    dx += std::pow(particle_u[k].x() - fem_u[k].x(), 2);
    fx += std::pow(fem_u[k].x(), 2);
    dy += std::pow(particle_u[k].y() - fem_u[k].y() - shift, 2);
    fy += std::pow(fem_u[k].y() - fem_uy_mean, 2);
  }
  require(fx > 0 && fy > 0, "the FEM field does not move the compared points: no relative error");
  result.ux_error = std::sqrt(dx / fx);
  result.uy_error = std::sqrt(dy / fy);
  return result;
}

}  // namespace plydem
