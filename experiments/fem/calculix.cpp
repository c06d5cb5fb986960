#include "experiments/fem/calculix.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <numbers>
#include <sstream>
#include <string_view>

#include "core/error.hpp"
#include "core/measurements.hpp"
#include "experiments/output/external_tool.hpp"
#include "experiments/protocols/coupon.hpp"
#include "strategies/laminate.hpp"

namespace plydem {
namespace {

using Clock = std::chrono::steady_clock;
namespace fs = std::filesystem;

constexpr long kMaxElements = 2'000'000;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

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

// --- Writing the deck ------------------------------------------------------------------------

// A number as CalculiX reads it: ccx takes at most 20 characters of each field (Fortran f20.0), so
// a shortest round-trip form such as 9.999999999999999e-05 (21 characters) would be cut to
// 9.999999999999999e-0. Full precision where it fits, else the most digits that fit.
std::string ccx_number(double value) {
  if (!std::isfinite(value))
    throw Error(fmt::format("cannot write {} into a CalculiX deck", value));
  if (std::abs(value) < 1e-99) return "0";
  std::string text = fmt::format("{}", value);
  for (int digits = 16; text.size() > 20; --digits) text = fmt::format("{:.{}g}", value, digits);
  return text;
}

// Node or element ids, 16 to a line (CalculiX's limit for set lines).
void append_id_lines(std::string& out, const std::vector<int>& ids) {
  for (std::size_t k = 0; k < ids.size(); ++k) {
    out += fmt::format("{}{}", ids[k], (k + 1) % 16 == 0 || k + 1 == ids.size() ? "\n" : ",");
  }
}

// The node levels that straddle z = 0, and the weight of the upper one.
struct MidPlane {
  int lower = 0;
  double weight = 0;
};
MidPlane mid_plane(const std::vector<double>& level_z) {
  const int levels = static_cast<int>(level_z.size());
  for (int l = 0; l + 1 < levels; ++l) {
    if (level_z[l] <= 0 && 0 <= level_z[l + 1])
      return {l, -level_z[l] / (level_z[l + 1] - level_z[l])};
  }
  throw Error("the mesh's node levels do not span the mid-plane z = 0");
}

// Plane corner nodes on the left end (x = 0): the one nearest y = W/2 and the one at y = 0.
std::pair<int, int> left_end_supports(const FemMesh& mesh, double length, double width) {
  int centre = -1, corner = -1;
  const double tol = 1e-9 * length;
  for (int p = 0; p < mesh.plane_position.rows(); ++p) {
    if (mesh.plane_position(p, 0) > tol) continue;
    const double y = mesh.plane_position(p, 1);
    if (centre < 0 ||
        std::abs(y - 0.5 * width) < std::abs(mesh.plane_position(centre, 1) - 0.5 * width))
      centre = p;
    if (corner < 0 || y < mesh.plane_position(corner, 1)) corner = p;
  }
  if (centre < 0 || corner == centre)
    throw Error("the mesh has fewer than two nodes on its left end");
  return {centre, corner};
}

// `dof` = 0 on the mid-plane at plane node p: one *EQUATION (or *BOUNDARY line when a node level
// lies on the mid-plane) appended to `equations` or `boundaries`.
void pin_mid_plane(const FemMesh& mesh, const MidPlane& mid, int p, int dof, std::string& equations,
                   std::string& boundaries) {
  const int below = mesh.level_node(p, mid.lower) + 1;
  const int above = mesh.level_node(p, mid.lower + 1) + 1;
  const double w = mid.weight;
  if (w < 1e-9) {
    boundaries += fmt::format("{},{},{},0\n", below, dof, dof);
  } else if (w > 1 - 1e-9) {
    boundaries += fmt::format("{},{},{},0\n", above, dof, dof);
  } else if (w >= 0.5) {  // the larger coefficient on the eliminated (first) term
    equations += fmt::format("2\n{},{},{},{},{},{}\n", above, dof, ccx_number(w), below, dof,
                             ccx_number(1 - w));
  } else {
    equations += fmt::format("2\n{},{},{},{},{},{}\n", below, dof, ccx_number(1 - w), above, dof,
                             ccx_number(w));
  }
}

// --- Running ccx -----------------------------------------------------------------------------

std::string read_text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(fmt::format("cannot read CalculiX output {}", path.string()));
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// A temporary directory removed on destruction, or the user's, kept.
class WorkDirectory {
 public:
  explicit WorkDirectory(const std::string& requested) {
    if (!requested.empty()) {
      path_ = requested;
      std::error_code ec;
      fs::create_directories(path_, ec);
      if (!fs::is_directory(path_))
        throw Error(fmt::format("cannot create the CalculiX work directory {}", requested));
      return;
    }
    std::string pattern = (fs::temp_directory_path() / "plydem-ccx-XXXXXX").string();
    if (::mkdtemp(pattern.data()) == nullptr)
      throw Error(fmt::format("cannot create a temporary directory like {}", pattern));
    path_ = pattern;
    remove_ = true;
  }
  ~WorkDirectory() {
    if (!remove_) return;
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  WorkDirectory(const WorkDirectory&) = delete;
  WorkDirectory& operator=(const WorkDirectory&) = delete;
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
  bool remove_ = false;
};

// The lines of ccx's log that report errors (and input cards it could not read), or the log's
// tail when there are none.
std::string log_problems(const std::string& log) {
  std::istringstream in(log);
  std::string line, problems;
  std::vector<std::string> tail;
  bool in_error = false;
  int problem_lines = 0;
  while (std::getline(in, line)) {
    const bool error = line.find("*ERROR") != std::string::npos ||
                       line.find("*WARNING reading") != std::string::npos ||
                       line.find("cannot be inter") != std::string::npos;
    if (error || (in_error && !line.empty() && line.find('*') == std::string::npos)) {
      if (++problem_lines <= 12) problems += line + "\n";
      in_error = true;
    } else {
      in_error = false;
    }
    tail.push_back(line);
    if (tail.size() > 15) tail.erase(tail.begin());
  }
  if (problem_lines > 12) problems += fmt::format("... ({} more lines)\n", problem_lines - 12);
  if (!problems.empty()) return problems;
  std::string text;
  for (const auto& l : tail) text += l + "\n";
  return text;
}

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

struct DatResults {
  Vector3Array displacement;
  std::vector<bool> seen;
  Eigen::Vector3d left_force = Eigen::Vector3d::Zero();
  Eigen::Vector3d right_force = Eigen::Vector3d::Zero();
  bool left_seen = false, right_seen = false;
  Eigen::Array<double, Eigen::Dynamic, 6> stress_sum;
  Eigen::ArrayXi stress_points;
};

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

}  // namespace

const char* fem_element_name(FemElement element) {
  return element == FemElement::kC3D20R ? "C3D20R" : "C3D8I";
}

double FemSpecimen::thickness() const {
  double h = 0;
  for (const Ply& ply : plies) h += ply.thickness;
  return h;
}

void FemSpecimen::validate() const {
  require(!plies.empty(), "the FEM specimen has no plies");
  for (std::size_t k = 0; k < plies.size(); ++k) {
    const Ply& ply = plies[k];
    try {
      plydem::validate(ply.material);
    } catch (const Error& e) {
      throw Error(fmt::format("ply {} (from the bottom): {}", k + 1, e.what()));
    }
    if (!std::isfinite(ply.angle))
      throw Error(fmt::format("ply {} (from the bottom): angle is not a finite number", k + 1));
    if (!(std::isfinite(ply.thickness) && ply.thickness > 0))
      throw Error(fmt::format("ply {} (from the bottom): thickness must be positive, got {} m",
                              k + 1, ply.thickness));
  }
  require(std::isfinite(length) && length > 0,
          fmt::format("FEM specimen length must be positive, got {} m", length));
  require(std::isfinite(width) && width > 0,
          fmt::format("FEM specimen width must be positive, got {} m", width));
  require(std::isfinite(hole_diameter) && hole_diameter >= 0,
          fmt::format("hole diameter must be >= 0, got {} m", hole_diameter));
  if (hole_diameter > 0) {
    require(length >= width,
            fmt::format("a plate with a hole must be at least as long as it is wide "
                        "(length {} mm, width {} mm)",
                        length * 1e3, width * 1e3));
    require(hole_diameter < 0.9 * width,
            fmt::format("the hole ({} mm) must be narrower than 0.9 x the plate's width ({} mm)",
                        hole_diameter * 1e3, width * 1e3));
  }
  const int last = static_cast<int>(plies.size()) - 1;
  for (std::size_t k = 0; k < cracks.size(); ++k) {
    const FemTransverseCrack& c = cracks[k];
    const std::string which = fmt::format("FEM crack {} (at x = {} mm)", k + 1, c.x * 1e3);
    require(hole_diameter == 0, which + ": a specimen with a hole cannot also have cracks");
    require(
        std::isfinite(c.x) && c.x > 1e-9 * length && c.x < length * (1 - 1e-9),
        fmt::format("{}: must lie inside the specimen's length (0, {} mm)", which, length * 1e3));
    require(c.first_ply >= 0 && c.first_ply <= c.last_ply && c.last_ply <= last,
            fmt::format("{}: plies {} .. {} (from the bottom, 1-based) are not plies 1 .. {} of "
                        "the specimen, lowest first",
                        which, c.first_ply + 1, c.last_ply + 1, last + 1));
    require(!(c.first_ply == 0 && c.last_ply == last),
            which + ": cuts every ply, which parts the specimen in two");
    for (std::size_t j = 0; j < k; ++j)
      require(std::abs(cracks[j].x - c.x) > 1e-9 * length,
              fmt::format("{}: lies at the x of crack {}; give one crack per x", which, j + 1));
  }
}

void FemMeshSettings::validate() const {
  require(elements_per_ply >= 1 && elements_per_ply <= 100,
          fmt::format("elements per ply must lie in [1, 100], got {}", elements_per_ply));
  require(std::isfinite(element_size) && element_size >= 0,
          fmt::format("FEM element size must be >= 0 (0 = automatic), got {} m", element_size));
  require(std::isfinite(hole_element_size) && hole_element_size >= 0,
          fmt::format("FEM hole element size must be >= 0 (0 = automatic), got {} m",
                      hole_element_size));
}

void FemSettings::validate() const {
  mesh.validate();
  require(std::isfinite(loading.end_displacement) && loading.end_displacement >= 0,
          fmt::format("FEM end displacement must be >= 0 (0 = 0.1% of the length), got {} m",
                      loading.end_displacement));
  require(std::isfinite(loading.grip_length) && loading.grip_length >= 0,
          fmt::format("FEM grip length must be >= 0, got {} m", loading.grip_length));
  require(std::isfinite(gauge_fraction) && gauge_fraction > 0 && gauge_fraction <= 1,
          fmt::format("gauge fraction must lie in (0, 1], got {}", gauge_fraction));
  require(std::isfinite(edge_band) && edge_band >= 0,
          fmt::format("FEM edge band must be >= 0, got {} m", edge_band));
  require(!executable.empty(), "the CalculiX executable name is empty");
  require(threads >= 1 && threads <= 1024, fmt::format("threads must be >= 1, got {}", threads));
}

CalculixAvailability calculix_availability(const std::string& executable) {
  CalculixAvailability result;
  if (executable.empty()) {
    result.message = "CalculiX (ccx) is not installed: no executable name given";
    return result;
  }
  if (const std::optional<std::string> path = find_executable(executable)) {
    result.available = true;
    result.executable = *path;
  } else if (executable.find('/') != std::string::npos) {
    result.message =
        fmt::format("CalculiX (ccx) is not installed: '{}' is not an executable file", executable);
  } else {
    result.message = fmt::format(
        "CalculiX (ccx) is not installed: '{}' not found on PATH (Debian: apt-get install "
        "calculix-ccx)",
        executable);
  }
  return result;
}

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
  // Estimate before allocating anything.
  {
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
  std::vector<FemTransverseCrack> cracks = specimen.cracks;
  std::sort(cracks.begin(), cracks.end(),
            [](const FemTransverseCrack& a, const FemTransverseCrack& b) { return a.x < b.x; });
  std::vector<double> stations;
  for (const FemTransverseCrack& c : cracks) stations.push_back(c.x);
  const PlaneMesh plane = hole ? hole_plate_mesh(L, W, D, element_size, hole_element_size, order)
                               : rectangle_mesh(L, W, element_size, order, stations);

  // Node levels through the thickness: `order` per element layer.
  const int per_ply = settings.elements_per_ply;
  const int plies = static_cast<int>(specimen.plies.size());
  const int layers = per_ply * plies;
  const double h = specimen.thickness();
  std::vector<double> z(order * layers + 1);
  {
    double bottom = -0.5 * h;
    for (int p = 0; p < plies; ++p) {
      const double t = specimen.plies[p].thickness;
      const int first = order * per_ply * p;
      for (int s = 0; s < order * per_ply; ++s)
        z[first + s] = bottom + t * fraction(s, order * per_ply);
      bottom += t;
    }
    z.back() = 0.5 * h;
  }
  const long element_count = static_cast<long>(plane.quad.size()) * layers;
  if (element_count > kMaxElements)
    throw Error(
        fmt::format("the FEM mesh would have {} elements (limit {}): choose a larger element "
                    "size",
                    element_count, kMaxElements));

  FemMesh mesh;
  mesh.element = settings.element;
  const int plane_nodes = static_cast<int>(plane.node.size());
  const int levels = static_cast<int>(z.size());
  std::vector<int> node_of(static_cast<std::size_t>(plane_nodes) * z.size(), -1);
  std::vector<Eigen::Vector3d> position;
  auto node = [&](int p, int level) {
    int& id = node_of[static_cast<std::size_t>(level) * plane_nodes + p];
    if (id < 0) {
      id = static_cast<int>(position.size());
      position.emplace_back(plane.node[p].x(), plane.node[p].y(), z[level]);
    }
    return id;
  };
  // Cracks: the plane nodes on each crack's plane, and the node levels its faces own (those
  // strictly inside its plies, and a top or bottom face it reaches). The elements on the crack's
  // +x side take twins of those nodes, so the two faces part.
  std::vector<int> crack_of(plane_nodes, -1);
  std::vector<std::vector<bool>> crack_level(cracks.size(), std::vector<bool>(levels, false));
  for (std::size_t k = 0; k < cracks.size(); ++k) {
    const FemTransverseCrack& c = cracks[k];
    for (int p = 0; p < plane_nodes; ++p)
      if (std::abs(plane.node[p].x() - c.x) <= 1e-9 * L) crack_of[p] = static_cast<int>(k);
    const int bottom = order * per_ply * c.first_ply, top = order * per_ply * (c.last_ply + 1);
    for (int l = bottom; l <= top; ++l)
      crack_level[k][l] = (l > bottom || c.first_ply == 0) && (l < top || c.last_ply == plies - 1);
  }
  std::vector<int> twin_of(node_of.size(), -1);
  auto element_node = [&](int p, int level, double centre_x) {
    const int k = crack_of[p];
    if (k < 0 || !crack_level[k][level] || centre_x < cracks[k].x) return node(p, level);
    int& id = twin_of[static_cast<std::size_t>(level) * plane_nodes + p];
    if (id < 0) {
      id = static_cast<int>(position.size());
      position.emplace_back(plane.node[p].x(), plane.node[p].y(), z[level]);
    }
    return id;
  };
  const int per_element = order == 2 ? 20 : 8;
  mesh.element_nodes.resize(element_count, per_element);
  mesh.element_ply.resize(element_count);
  long e = 0;
  for (int layer = 0; layer < layers; ++layer) {  // ply by ply: each ply's elements contiguous
    const int bottom = order * layer, top = order * (layer + 1);
    for (const auto& q : plane.quad) {
      double centre_x = 0;
      for (int c = 0; c < 4; ++c) centre_x += 0.25 * plane.node[q[c]].x();
      auto at = [&](int p, int level) { return element_node(p, level, centre_x); };
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
  mesh.node_position.resize(static_cast<Eigen::Index>(position.size()), 3);
  for (std::size_t i = 0; i < position.size(); ++i)
    mesh.node_position.row(static_cast<Eigen::Index>(i)) = position[i].transpose().array();

  // The corner grid.
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
  // Every level: the corner nodes of C3D20R elements also carry the vertical mid-edge nodes.
  mesh.level_z = z;
  mesh.level_node.resize(corners, levels);
  for (int p = 0; p < plane_nodes; ++p) {
    if (corner_index[p] < 0) continue;
    for (int l = 0; l < levels; ++l) mesh.level_node(corner_index[p], l) = node(p, l);
  }
  return mesh;
}

std::string calculix_input(const FemSpecimen& specimen, const FemMesh& mesh,
                           const FemLoading& loading, bool element_stresses) {
  specimen.validate();
  require(std::isfinite(loading.end_displacement) && loading.end_displacement > 0,
          fmt::format("the CalculiX deck needs a positive end displacement, got {} m",
                      loading.end_displacement));
  require(std::isfinite(loading.grip_length) && loading.grip_length >= 0 &&
              2 * loading.grip_length < specimen.length,
          fmt::format("FEM grip length must lie in [0, L/2), got {} m", loading.grip_length));
  const int plies = static_cast<int>(specimen.plies.size());
  std::string out;
  out.reserve(static_cast<std::size_t>(mesh.node_count()) * 70 +
              static_cast<std::size_t>(mesh.element_count()) * 100);
  out += fmt::format(
      "** plydem: {} x {} x {} m laminate of {} plies{}, {} {} elements\n", specimen.length,
      specimen.width, specimen.thickness(), plies,
      specimen.hole_diameter > 0 ? fmt::format(" with a {} m hole", specimen.hole_diameter) : "",
      mesh.element_count(), fem_element_name(mesh.element));

  out += "*NODE,NSET=NALL\n";
  for (int i = 0; i < mesh.node_count(); ++i)
    out += fmt::format("{},{},{},{}\n", i + 1, ccx_number(mesh.node_position(i, 0)),
                       ccx_number(mesh.node_position(i, 1)), ccx_number(mesh.node_position(i, 2)));

  out += fmt::format("*ELEMENT,TYPE={},ELSET=EALL\n", fem_element_name(mesh.element));
  const int per_element = static_cast<int>(mesh.element_nodes.cols());
  for (int e = 0; e < mesh.element_count(); ++e) {
    out += fmt::format("{}", e + 1);
    for (int c = 0; c < per_element; ++c) {
      // At most 16 entries on a line: the id and 15 nodes, then a continuation line.
      out += c == 15 ? ",\n" : ",";
      out += fmt::format("{}", mesh.element_nodes(e, c) + 1);
    }
    out += "\n";
  }
  for (int p = 0; p < plies; ++p) {
    int first = -1, last = -1;
    for (int e = 0; e < mesh.element_count(); ++e) {
      if (mesh.element_ply(e) != p) continue;
      if (first < 0) first = e;
      if (last >= 0 && e != last + 1) throw Error("the FEM mesh's ply elements are not contiguous");
      last = e;
    }
    if (first < 0) throw Error(fmt::format("ply {} has no elements in the FEM mesh", p + 1));
    out += fmt::format("*ELSET,ELSET=PLY{},GENERATE\n{},{},1\n", p + 1, first + 1, last + 1);
  }

  // Grips.
  const double tol = 1e-9 * specimen.length;
  std::vector<int> left, right;
  for (int i = 0; i < mesh.node_count(); ++i) {
    const double x = mesh.node_position(i, 0);
    if (x <= loading.grip_length + tol) left.push_back(i + 1);
    if (x >= specimen.length - loading.grip_length - tol) right.push_back(i + 1);
  }
  require(!left.empty() && !right.empty(), "a FEM grip holds no node");
  out += "*NSET,NSET=LEFT\n";
  append_id_lines(out, left);
  out += "*NSET,NSET=RIGHT\n";
  append_id_lines(out, right);

  // One material and orientation per ply: fibre (local 1) at the ply angle in the x-y plane.
  for (int p = 0; p < plies; ++p) {
    const Material& m = specimen.plies[p].material;
    const double c = std::cos(specimen.plies[p].angle), s = std::sin(specimen.plies[p].angle);
    out += fmt::format("*MATERIAL,NAME=MPLY{}\n*ELASTIC,TYPE=ENGINEERING CONSTANTS\n", p + 1);
    // Eight fields of at most 20 characters overflow the 132-character line: 10 digits.
    out += fmt::format("{:.10g},{:.10g},{:.10g},{:.10g},{:.10g},{:.10g},{:.10g},{:.10g}\n", m.E1,
                       m.E2, m.E2, m.nu12, m.nu12, m.nu23, m.G12, m.G12);
    out += fmt::format("{:.10g},0.\n", m.G23());
    out += fmt::format("*ORIENTATION,NAME=OPLY{},SYSTEM=RECTANGULAR\n{},{},0,{},{},0\n", p + 1,
                       ccx_number(c), ccx_number(s), ccx_number(-s), ccx_number(c));
    out += fmt::format("*SOLID SECTION,ELSET=PLY{},MATERIAL=MPLY{},ORIENTATION=OPLY{}\n", p + 1,
                       p + 1, p + 1);
  }

  // Rigid modes the grips leave, removed on the mid-plane at the left end.
  const MidPlane mid = mid_plane(mesh.level_z);
  const auto [centre, corner] = left_end_supports(mesh, specimen.length, specimen.width);
  std::string equations, pins;
  if (loading.grips == GripCondition::kFree) pin_mid_plane(mesh, mid, centre, 2, equations, pins);
  pin_mid_plane(mesh, mid, centre, 3, equations, pins);
  pin_mid_plane(mesh, mid, corner, 3, equations, pins);
  if (!equations.empty()) out += "*EQUATION\n" + equations;

  const double half = 0.5 * loading.end_displacement;
  out += "*STEP\n*STATIC\n*BOUNDARY\n";
  out += fmt::format("LEFT,1,1,{}\nRIGHT,1,1,{}\n", ccx_number(-half), ccx_number(half));
  if (loading.grips == GripCondition::kClamped) out += "LEFT,2,2,0\nRIGHT,2,2,0\n";
  out += pins;
  out += "*NODE PRINT,NSET=NALL\nU\n";
  out += "*NODE PRINT,NSET=LEFT,TOTALS=ONLY\nRF\n";
  out += "*NODE PRINT,NSET=RIGHT,TOTALS=ONLY\nRF\n";
  if (element_stresses) out += "*EL PRINT,ELSET=EALL,GLOBAL=YES\nS\n";
  out += "*END STEP\n";
  return out;
}

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

FemSolution run_calculix(const FemSpecimen& specimen, const FemSettings& settings) {
  const auto start = Clock::now();
  specimen.validate();
  settings.validate();
  FemSolution solution;
  solution.element = settings.mesh.element;
  const CalculixAvailability ccx = calculix_availability(settings.executable);
  if (!ccx.available) {
    solution.message = ccx.message;
    return solution;
  }
  const FemMesh mesh = build_fem_mesh(specimen, settings.mesh);
  FemLoading loading = settings.loading;
  if (loading.end_displacement == 0) loading.end_displacement = 1e-3 * specimen.length;
  const std::string deck = calculix_input(specimen, mesh, loading, settings.element_stresses);

  const WorkDirectory directory(settings.work_directory);
  {
    std::ofstream file(directory.path() / "job.inp", std::ios::binary);
    file << deck;
    if (!file) throw Error(fmt::format("cannot write {}", (directory.path() / "job.inp").string()));
  }
  const std::string command = fmt::format(
      "cd {} && OMP_NUM_THREADS={} CCX_NPROC_EQUATION_SOLVER={} {} -i job > job.log 2>&1",
      shell_quote(directory.path().string()), settings.threads, settings.threads,
      shell_quote(ccx.executable));
  const auto solve_start = Clock::now();
  const int status = std::system(command.c_str());
  solution.solver_seconds = seconds_since(solve_start);
  const fs::path log_path = directory.path() / "job.log";
  const std::string log = fs::exists(log_path) ? read_text(log_path) : std::string();
  const int exit_code = status == -1 ? -1 : (WIFEXITED(status) ? WEXITSTATUS(status) : -1);
  if (exit_code != 0 || log.find("*ERROR") != std::string::npos ||
      log.find("*WARNING reading") != std::string::npos ||
      log.find("Job finished") == std::string::npos) {
    throw Error(fmt::format("CalculiX ({}) failed on {} (exit code {}):\n{}", ccx.executable,
                            (directory.path() / "job.inp").string(), exit_code, log_problems(log)));
  }

  const DatResults dat = parse_dat(read_text(directory.path() / "job.dat"), mesh.node_count(),
                                   mesh.element_count(), settings.element_stresses);
  const long missing = std::count(dat.seen.begin(), dat.seen.end(), false);
  if (missing > 0 || !dat.left_seen || !dat.right_seen)
    throw Error(fmt::format("CalculiX's job.dat lacks {} of {} node displacements{}", missing,
                            mesh.node_count(),
                            dat.left_seen && dat.right_seen ? "" : " or a grip's reaction total"));

  solution.available = true;
  solution.nodes = mesh.node_count();
  solution.elements = mesh.element_count();
  solution.degrees_of_freedom = 3 * mesh.node_count();
  solution.end_displacement = loading.end_displacement;
  solution.reaction_force = 0.5 * (dat.right_force.x() - dat.left_force.x());
  const double h = specimen.thickness();
  solution.gross_stress = solution.reaction_force / (specimen.width * h);

  // Mid-plane strains of the gauge section, and its mean thickness strain.
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

  if (settings.element_stresses) {
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
  solution.displacement = FemDisplacementField(mesh, dat.displacement);
  solution.wall_seconds = seconds_since(start);
  return solution;
}

namespace {

// The pulls along x and along y (every ply turned by -90 deg), and CLT; only the message when
// ccx is missing.
FemTensionResult run_both_pulls(const FemSpecimen& specimen, const FemSettings& settings) {
  FemTensionResult result;
  result.theory = laminate_constants(specimen.plies);
  result.along_x = run_calculix(specimen, settings);
  if (!result.along_x.available) {
    result.message = result.along_x.message;
    return result;
  }
  FemSpecimen turned = specimen;
  for (Ply& ply : turned.plies) ply.angle -= 0.5 * std::numbers::pi;
  result.along_y = run_calculix(turned, settings);
  return result;
}

// Ex, nu_xy, gamma_xy/eps_x from the pull along x; Ey, nu_yx from the one along y.
void set_moduli_from_pulls(FemTensionResult& result) {
  for (const FemSolution* pull : {&result.along_x, &result.along_y}) {
    if (!(pull->exx > 0))
      throw Error(fmt::format("the FEM coupon did not stretch (fitted strain {})", pull->exx));
  }
  result.available = true;
  const FemSolution& x = result.along_x;
  const FemSolution& y = result.along_y;
  result.fem.Ex = x.gross_stress / x.exx;
  result.fem.nu_xy = -x.eyy / x.exx;
  result.fem.shear_coupling_x = x.gamma_xy / x.exx;
  result.fem.Ey = y.gross_stress / y.exx;
  result.fem.nu_yx = -y.eyy / y.exx;
  result.nu_xz = -x.ezz / x.exx;
}

}  // namespace

FemTensionResult fem_tension_test(const FemSpecimen& specimen, const FemSettings& settings) {
  specimen.validate();
  settings.validate();
  require(specimen.hole_diameter == 0,
          "the FEM tension test measures moduli on a coupon without a hole");
  FemTensionResult result = run_both_pulls(specimen, settings);
  if (!result.along_x.available) return result;
  set_moduli_from_pulls(result);
  return result;
}

namespace {

// The DEM coupon's gauge particles (as the tension test selects them) at their positions in the
// FEM frame: x and y as built, z from the particles' mid-plane.
std::vector<Eigen::Vector3d> gauge_points(const Model& coupon, const TensionSettings& s,
                                          double grip_length) {
  Particles p = coupon.particles;
  const CouponGrips grips = assign_grips(p, grip_length);
  const GaugeSection gauge =
      gauge_section(p, grips, s.gauge_fraction, s.edge_band_diameters, s.coupon.particle_diameter);
  const double z_mid =
      0.5 * (p.reference_position.col(2).minCoeff() + p.reference_position.col(2).maxCoeff());
  std::vector<Eigen::Vector3d> points;
  points.reserve(gauge.particles.size());
  for (int i : gauge.particles) {
    points.emplace_back(p.reference_position(i, 0), p.reference_position(i, 1),
                        p.reference_position(i, 2) - z_mid);
  }
  return points;
}

// Replaces the solution's strain fit by the fit at `points` (the DEM's gauge particles).
void fit_at_points(FemSolution& solution, const std::vector<Eigen::Vector3d>& points) {
  Eigen::Array<double, Eigen::Dynamic, 2> position(static_cast<Eigen::Index>(points.size()), 2);
  Eigen::Array<double, Eigen::Dynamic, 2> displacement(position.rows(), 2);
  Eigen::Index n = 0;
  for (const Eigen::Vector3d& x : points) {
    const std::optional<Eigen::Vector3d> u = solution.displacement.at(x.x(), x.y(), x.z());
    if (!u) continue;
    position.row(n) << x.x(), x.y();
    displacement.row(n) << u->x(), u->y();
    ++n;
  }
  require(n >= 3,
          fmt::format("the FEM twin of the coupon: only {} of its {} gauge particles lie in "
                      "the FEM plate",
                      n, points.size()));
  const GaugeStrain strain = fit_plane_strain(position.topRows(n), displacement.topRows(n));
  solution.exx = strain.exx;
  solution.eyy = strain.eyy;
  solution.gamma_xy = strain.gamma_xy;
}

}  // namespace

double fem_twin_element_size(const TensionSettings& settings, const FemTwinSettings& twin) {
  if (twin.mesh.element_size > 0) return twin.mesh.element_size;
  return std::min(2 * settings.coupon.particle_diameter, settings.coupon.width / 8);
}

FemTensionResult fem_twin_tension_test(const TensionSettings& settings, const TensionResult& dem,
                                       const FemTwinSettings& twin) {
  require(dem.along_x.model && dem.along_y.model,
          "the FEM twin of a tension test needs the DEM's coupons (run the tension test first)");
  const CouponSpec& coupon = settings.coupon;
  FemSpecimen specimen;
  specimen.plies = settings.layup.empty()
                       ? std::vector<Ply>{Ply{coupon.material, dem.ply_angle, coupon.thickness}}
                       : laminate_plies(LaminateSpec{coupon, settings.layup, settings.interface});
  specimen.length = coupon.length;
  specimen.width = coupon.width;

  FemSettings fem;
  fem.mesh = twin.mesh;
  fem.mesh.element_size = fem_twin_element_size(settings, twin);
  fem.loading.grips = settings.grips;
  fem.loading.grip_length = TensionTest(settings).grip_length();
  fem.gauge_fraction = settings.gauge_fraction;
  fem.executable = twin.executable;
  fem.threads = twin.threads;

  FemTensionResult result = run_both_pulls(specimen, fem);
  if (!result.along_x.available) return result;
  fit_at_points(result.along_x,
                gauge_points(*dem.along_x.model, settings, fem.loading.grip_length));
  fit_at_points(result.along_y,
                gauge_points(*dem.along_y.model, settings, fem.loading.grip_length));
  set_moduli_from_pulls(result);
  return result;
}

}  // namespace plydem
