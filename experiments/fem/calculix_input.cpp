// Writing the CalculiX input deck (calculix_input): nodes, elements, plies' materials and
// orientations, grips, the mid-plane supports and the one linear static step.
#include "experiments/fem/calculix.hpp"

#include <fmt/format.h>

#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "core/error.hpp"
#include "experiments/fem/calculix_detail.hpp"

namespace plydem {

calculix_detail::MidPlane calculix_detail::mid_plane(const std::vector<double>& level_z) {
  const int levels = static_cast<int>(level_z.size());
  for (int l = 0; l + 1 < levels; ++l) {
    if (level_z[l] <= 0 && 0 <= level_z[l + 1])
      return {l, -level_z[l] / (level_z[l + 1] - level_z[l])};
  }
  throw Error("the mesh's node levels do not span the mid-plane z = 0");
}

namespace {

using calculix_detail::MidPlane;

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

}  // namespace

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
  const MidPlane mid = calculix_detail::mid_plane(mesh.level_z);
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

}  // namespace plydem
