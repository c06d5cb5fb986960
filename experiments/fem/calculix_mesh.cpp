// Meshing a FemSpecimen (build_fem_mesh): the in-plane quadrilateral mesh (a rectangular grid, or
// an O-grid around a hole joined to grids on either side), extruded through the plies into
// hexahedra, with twin nodes on the faces of transverse cracks.
#include "experiments/fem/calculix.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "core/error.hpp"

namespace plydem {
namespace {

constexpr long kMaxElements = 2'000'000;

// --- The in-plane quadrilateral mesh ---------------------------------------------------------

// Quadrilaterals: 4 corners counter-clockwise, then (order 2) the mid-edge nodes of the edges
// 1-2, 2-3, 3-4, 4-1, as the faces of C3D20 elements want them.
struct PlaneMesh {
  int order = 1;
  std::vector<Eigen::Vector2d> node;
  std::vector<std::array<int, 8>> quad;

  int add(const Eigen::Vector2d& p) {
    node.push_back(p);
    return static_cast<int>(node.size()) - 1;
  }
  // `ids` is a logical grid of (order ni + 1) x (order nj + 1) node indices whose first index
  // runs along one side and second along the next one counter-clockwise; adds its ni x nj cells.
  void add_cells(const Eigen::ArrayXXi& ids) {
    const int r = order;
    const int ni = static_cast<int>(ids.rows() - 1) / r;
    const int nj = static_cast<int>(ids.cols() - 1) / r;
    for (int i = 0; i < ni; ++i) {
      for (int j = 0; j < nj; ++j) {
        std::array<int, 8> q{};
        q.fill(-1);
        q[0] = ids(r * i, r * j);
        q[1] = ids(r * (i + 1), r * j);
        q[2] = ids(r * (i + 1), r * (j + 1));
        q[3] = ids(r * i, r * (j + 1));
        if (r == 2) {
          q[4] = ids(2 * i + 1, 2 * j);
          q[5] = ids(2 * i + 2, 2 * j + 1);
          q[6] = ids(2 * i + 1, 2 * j + 2);
          q[7] = ids(2 * i, 2 * j + 1);
        }
        quad.push_back(q);
      }
    }
  }
};

// x = length * (i / n): exactly `length` at i = n.
double fraction(int i, int n) {
  return static_cast<double>(i) / static_cast<double>(n);
}

int ceil_count(double span, double size) {
  const double n = std::ceil(span / size - 1e-9);
  if (!(n < 1e7)) throw Error(fmt::format("{} elements across {} m is too fine a mesh", n, span));
  return std::max(1, static_cast<int>(n));
}

// The node x of a rectangle `length` long, elements at most `element_size` long, with a node at
// each of `stations` (sorted, inside (0, length)): each stretch between stations meshed uniformly.
// Order 2 adds the mid-edge x between.
std::vector<double> node_columns(double length, const std::vector<double>& stations,
                                 double element_size, int order) {
  std::vector<double> ends{0.0};
  ends.insert(ends.end(), stations.begin(), stations.end());
  ends.push_back(length);
  std::vector<double> x{0.0};
  for (std::size_t k = 0; k + 1 < ends.size(); ++k) {
    const double a = ends[k], span = ends[k + 1] - a;
    const int n = order * ceil_count(span, element_size);
    for (int i = 1; i <= n; ++i) x.push_back(i == n ? ends[k + 1] : a + span * fraction(i, n));
  }
  return x;
}

PlaneMesh rectangle_mesh(double length, double width, double element_size, int order,
                         const std::vector<double>& stations) {
  const std::vector<double> x = node_columns(length, stations, element_size, order);
  const int ny = ceil_count(width, element_size);
  PlaneMesh mesh;
  mesh.order = order;
  Eigen::ArrayXXi ids(static_cast<Eigen::Index>(x.size()), order * ny + 1);
  for (std::size_t i = 0; i < x.size(); ++i)
    for (int j = 0; j <= order * ny; ++j)
      ids(static_cast<Eigen::Index>(i), j) = mesh.add({x[i], width * fraction(j, order * ny)});
  mesh.add_cells(ids);
  return mesh;
}

// The plate [0, L] x [0, W] with a hole of radius R at its centre. Around the hole an O-grid
// fills the W x W square centred on it: ring node (k, m) lies at s(k) of the way from the hole's
// circle (angle -45 deg + 90 deg m / nt, counter-clockwise) to the square's edge (nt nodes per
// side, uniformly spaced), with s graded geometrically so that the elements grow from the hole's
// size to the outer one. Rectangular grids fill the rest on either side, sharing the square's
// edge nodes.
PlaneMesh hole_plate_mesh(double length, double width, double diameter, double element_size,
                          double hole_element_size, int order) {
  const double pi = std::numbers::pi;
  const double R = 0.5 * diameter, a = 0.5 * width, cx = 0.5 * length, cy = 0.5 * width;
  const int nt =
      std::max({2, ceil_count(width, element_size), ceil_count(0.5 * pi * R, hole_element_size)});
  const double h_in = 0.5 * pi * R / nt;  // element size along the hole
  const double h_out = width / nt;        // along the square
  const double radial = a - R;
  // The fewest rings whose geometric series from h_in to h_out spans the radial distance.
  int nr = 1;
  double growth = 1;
  if (h_out <= h_in) {
    nr = ceil_count(radial, h_in);
  } else {
    for (nr = 1; nr < 10000; ++nr) {
      growth = nr == 1 ? 1.0 : std::pow(h_out / h_in, 1.0 / (nr - 1));
      const double span = nr == 1 ? h_in : h_in * (std::pow(growth, nr) - 1) / (growth - 1);
      if (span >= radial) break;
    }
  }
  auto grade = [&](double xi) {  // xi in [0, 1] -> s in [0, 1]
    if (growth == 1.0) return xi;
    return (std::pow(growth, xi * nr) - 1) / (std::pow(growth, nr) - 1);
  };

  PlaneMesh mesh;
  mesh.order = order;
  const int r = order;
  const int m_count = 4 * r * nt;  // ring nodes around, periodic
  Eigen::ArrayXXi ring(r * nr + 1, m_count + 1);
  for (int k = 0; k <= r * nr; ++k) {
    const double s = grade(fraction(k, r * nr));
    for (int m = 0; m < m_count; ++m) {
      const double t = static_cast<double>(m) / (r * nt);  // [0, 4): side + fraction along it
      const double theta = -0.25 * pi + 0.5 * pi * t;
      const Eigen::Vector2d circle(cx + R * std::cos(theta), cy + R * std::sin(theta));
      const int side = std::min(3, static_cast<int>(t));
      const double f = t - side;
      Eigen::Vector2d square;
      switch (side) {
        case 0:
          square = {cx + a, width * f};
          break;
        case 1:
          square = {cx + a - width * f, width};
          break;
        case 2:
          square = {cx - a, width * (1 - f)};
          break;
        default:
          square = {cx - a + width * f, 0.0};
          break;
      }
      ring(k, m) = mesh.add(s == 1.0 ? square : Eigen::Vector2d((1 - s) * circle + s * square));
    }
    ring(k, m_count) = ring(k, 0);
  }
  mesh.add_cells(ring);  // (k outward, m counter-clockwise): counter-clockwise cells

  const double side_length = cx - a;
  if (side_length > 1e-9 * length) {
    const int nx = ceil_count(side_length, h_out);
    const int ny = r * nt;
    Eigen::ArrayXXi left(r * nx + 1, ny + 1), right(r * nx + 1, ny + 1);
    for (int j = 0; j <= ny; ++j) {
      const double y = width * fraction(j, ny);
      for (int i = 0; i <= r * nx; ++i) {
        if (i < r * nx) left(i, j) = mesh.add({side_length * fraction(i, r * nx), y});
        if (i > 0) {
          const double x = i == r * nx ? length : cx + a + side_length * fraction(i, r * nx);
          right(i, j) = mesh.add({x, y});
        }
      }
      left(r * nx, j) = ring(r * nr, 3 * r * nt - j);  // the square's left edge, downwards
      right(0, j) = ring(r * nr, j);                   // its right edge, upwards
    }
    mesh.add_cells(left);
    mesh.add_cells(right);
  }
  return mesh;
}

// --- Extruding it through the plies ----------------------------------------------------------

// Throws before anything is allocated when the mesh would clearly exceed kMaxElements.
void check_element_estimate(const FemSpecimen& specimen, const FemMeshSettings& settings,
                            double element_size, double hole_element_size) {
  const double L = specimen.length, W = specimen.width, D = specimen.hole_diameter;
  const bool hole = D > 0;
  const double plane_estimate =
      hole ? (L * W) / (element_size * element_size) +
                 4.0 * (0.5 * std::numbers::pi * D / hole_element_size) * 30.0
           : std::ceil(L / element_size) * std::ceil(W / element_size);
  const double estimate =
      plane_estimate * settings.elements_per_ply * static_cast<double>(specimen.plies.size());
  if (estimate > kMaxElements)
    throw Error(
        fmt::format("the FEM mesh would have about {:.3g} elements (limit {}): choose a "
                    "larger element size",
                    estimate, kMaxElements));
}

// Node levels through the thickness, bottom to top: `order` per element layer, `per_ply` element
// layers through each ply.
std::vector<double> node_levels(const FemSpecimen& specimen, int order, int per_ply) {
  const int plies = static_cast<int>(specimen.plies.size());
  const double h = specimen.thickness();
  std::vector<double> z(order * per_ply * plies + 1);
  double bottom = -0.5 * h;
  for (int p = 0; p < plies; ++p) {
    const double t = specimen.plies[p].thickness;
    const int first = order * per_ply * p;
    for (int s = 0; s < order * per_ply; ++s)
      z[first + s] = bottom + t * fraction(s, order * per_ply);
    bottom += t;
  }
  z.back() = 0.5 * h;
  return z;
}

// The nodes of the extruded mesh, numbered in the order the elements first use them. Cracks: the
// plane nodes on each crack's plane, and the node levels its faces own (those strictly inside its
// plies, and a top or bottom face it reaches). The elements on the crack's +x side take twins of
// those nodes, so the two faces part.
class ExtrudedNodes {
 public:
  ExtrudedNodes(const PlaneMesh& plane, const std::vector<double>& z,
                const std::vector<FemTransverseCrack>& cracks, int order, int per_ply, int plies,
                double length)
      : plane_(plane),
        z_(z),
        cracks_(cracks),
        plane_nodes_(static_cast<int>(plane.node.size())),
        node_of_(static_cast<std::size_t>(plane_nodes_) * z.size(), -1),
        twin_of_(node_of_.size(), -1),
        crack_of_(plane_nodes_, -1),
        crack_level_(cracks.size(), std::vector<bool>(z.size(), false)) {
    for (std::size_t k = 0; k < cracks.size(); ++k) {
      const FemTransverseCrack& c = cracks[k];
      for (int p = 0; p < plane_nodes_; ++p)
        if (std::abs(plane.node[p].x() - c.x) <= 1e-9 * length) crack_of_[p] = static_cast<int>(k);
      const int bottom = order * per_ply * c.first_ply, top = order * per_ply * (c.last_ply + 1);
      for (int l = bottom; l <= top; ++l)
        crack_level_[k][l] =
            (l > bottom || c.first_ply == 0) && (l < top || c.last_ply == plies - 1);
    }
  }

  // The node at plane node p on `level`.
  int node(int p, int level) { return id(node_of_, p, level); }
  // The node an element whose centre lies at `centre_x` uses there: a crack's twin on its +x side.
  int element_node(int p, int level, double centre_x) {
    const int k = crack_of_[p];
    if (k < 0 || !crack_level_[k][level] || centre_x < cracks_[k].x) return node(p, level);
    return id(twin_of_, p, level);
  }
  Vector3Array positions() const {
    Vector3Array out(static_cast<Eigen::Index>(position_.size()), 3);
    for (std::size_t i = 0; i < position_.size(); ++i)
      out.row(static_cast<Eigen::Index>(i)) = position_[i].transpose().array();
    return out;
  }

 private:
  int id(std::vector<int>& table, int p, int level) {
    int& slot = table[static_cast<std::size_t>(level) * plane_nodes_ + p];
    if (slot < 0) {
      slot = static_cast<int>(position_.size());
      position_.emplace_back(plane_.node[p].x(), plane_.node[p].y(), z_[level]);
    }
    return slot;
  }

  const PlaneMesh& plane_;
  const std::vector<double>& z_;
  const std::vector<FemTransverseCrack>& cracks_;
  int plane_nodes_;
  std::vector<int> node_of_, twin_of_, crack_of_;
  std::vector<std::vector<bool>> crack_level_;
  std::vector<Eigen::Vector3d> position_;
};

// The hexahedra, ply by ply (each ply's elements contiguous), layer by layer, quadrilateral by
// quadrilateral, with their nodes in CalculiX's order.
void add_elements(FemMesh& mesh, const PlaneMesh& plane, ExtrudedNodes& nodes, int order,
                  int layers, int per_ply) {
  const long element_count = static_cast<long>(plane.quad.size()) * layers;
  const int per_element = order == 2 ? 20 : 8;
  mesh.element_nodes.resize(element_count, per_element);
  mesh.element_ply.resize(element_count);
  long e = 0;
  for (int layer = 0; layer < layers; ++layer) {
    const int bottom = order * layer, top = order * (layer + 1);
    for (const auto& q : plane.quad) {
      double centre_x = 0;
      for (int c = 0; c < 4; ++c) centre_x += 0.25 * plane.node[q[c]].x();
      auto at = [&](int p, int level) { return nodes.element_node(p, level, centre_x); };
      for (int c = 0; c < 4; ++c) {
        mesh.element_nodes(e, c) = at(q[c], bottom);
        mesh.element_nodes(e, 4 + c) = at(q[c], top);
      }
      if (order == 2) {
        for (int c = 0; c < 4; ++c) {
          mesh.element_nodes(e, 8 + c) = at(q[4 + c], bottom);
          mesh.element_nodes(e, 12 + c) = at(q[4 + c], top);
          mesh.element_nodes(e, 16 + c) = at(q[c], bottom + 1);
        }
      }
      mesh.element_ply(e) = layer / per_ply;
      ++e;
    }
  }
}

// The corner grid: the quadrilaterals' corners in plane, and their nodes on every level (the
// corner nodes of C3D20R elements also carry the vertical mid-edge nodes).
void set_corner_grid(FemMesh& mesh, const PlaneMesh& plane, const std::vector<double>& z,
                     ExtrudedNodes& nodes) {
  const int plane_nodes = static_cast<int>(plane.node.size());
  const int levels = static_cast<int>(z.size());
  std::vector<int> corner_index(plane_nodes, -1);
  int corners = 0;
  for (const auto& q : plane.quad)
    for (int c = 0; c < 4; ++c)
      if (corner_index[q[c]] < 0) corner_index[q[c]] = corners++;
  mesh.plane_position.resize(corners, 2);
  for (int p = 0; p < plane_nodes; ++p)
    if (corner_index[p] >= 0)
      mesh.plane_position.row(corner_index[p]) = plane.node[p].transpose().array();
  mesh.plane_quad.resize(static_cast<Eigen::Index>(plane.quad.size()), 4);
  for (std::size_t k = 0; k < plane.quad.size(); ++k)
    for (int c = 0; c < 4; ++c)
      mesh.plane_quad(static_cast<Eigen::Index>(k), c) = corner_index[plane.quad[k][c]];
  mesh.level_z = z;
  mesh.level_node.resize(corners, levels);
  for (int p = 0; p < plane_nodes; ++p) {
    if (corner_index[p] < 0) continue;
    for (int l = 0; l < levels; ++l) mesh.level_node(corner_index[p], l) = nodes.node(p, l);
  }
}

}  // namespace

FemMesh build_fem_mesh(const FemSpecimen& specimen, const FemMeshSettings& settings) {
  specimen.validate();
  settings.validate();
  const int order = settings.element == FemElement::kC3D20R ? 2 : 1;
  const double L = specimen.length, W = specimen.width, D = specimen.hole_diameter;
  const bool hole = D > 0;
  const double element_size =
      settings.element_size > 0 ? settings.element_size : W / (hole ? 16.0 : 8.0);
  const double hole_element_size =
      settings.hole_element_size > 0 ? settings.hole_element_size : std::numbers::pi * D / 64.0;
  check_element_estimate(specimen, settings, element_size, hole_element_size);
  std::vector<FemTransverseCrack> cracks = specimen.cracks;
  std::sort(cracks.begin(), cracks.end(),
            [](const FemTransverseCrack& a, const FemTransverseCrack& b) { return a.x < b.x; });
  std::vector<double> stations;
  for (const FemTransverseCrack& c : cracks) stations.push_back(c.x);
  const PlaneMesh plane = hole ? hole_plate_mesh(L, W, D, element_size, hole_element_size, order)
                               : rectangle_mesh(L, W, element_size, order, stations);

  const int per_ply = settings.elements_per_ply;
  const int plies = static_cast<int>(specimen.plies.size());
  const int layers = per_ply * plies;
  const std::vector<double> z = node_levels(specimen, order, per_ply);
  const long element_count = static_cast<long>(plane.quad.size()) * layers;
  if (element_count > kMaxElements)
    throw Error(
        fmt::format("the FEM mesh would have {} elements (limit {}): choose a larger element "
                    "size",
                    element_count, kMaxElements));

  FemMesh mesh;
  mesh.element = settings.element;
  ExtrudedNodes nodes(plane, z, cracks, order, per_ply, plies, L);
  add_elements(mesh, plane, nodes, order, layers, per_ply);
  mesh.node_position = nodes.positions();
  set_corner_grid(mesh, plane, z, nodes);
  return mesh;
}

}  // namespace plydem
