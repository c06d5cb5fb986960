#pragma once
/// \file
/// FEM references through CalculiX (`ccx`): the laminate as a 3D solid, meshed with structured
/// hexahedra, one or more elements through each ply, each ply with its own orthotropic material
/// and orientation. plydem writes the input deck, runs `ccx -i job` in a temporary directory, reads
/// the `.dat` file and measures the specimen the way the DEM tension test does
/// (experiments/protocols/tension.hpp): grips at both ends moved apart along x, the reaction
/// force, and strains from a least-squares fit of the mid-plane displacements of the central gauge
/// section. The facts this relies on (input conventions, output traps, boundary conditions) are
/// collected in shared/FEM_NOTES.md.
///
/// Frame and units. SI throughout (m, Pa, N). The specimen occupies x in [0, L], y in [0, W] like a
/// DEM coupon, and z in [-h/2, h/2] with the laminate's mid-plane at z = 0; plies are stacked from
/// z = -h/2 upwards, plies[0] at the bottom. A hole is centred at (L/2, W/2).
///
/// Material. A ply is transversely isotropic about its fibre (local axis 1): CalculiX gets
/// `*ELASTIC, TYPE=ENGINEERING CONSTANTS` with E1, E2, E3 = E2, nu12, nu13 = nu12, nu23, G12,
/// G13 = G12, G23 = E2 / (2 (1 + nu23)) (paper Table 1 with ERRATA §2), and an `*ORIENTATION`
/// whose axis 1 lies at the ply angle from +x in the x-y plane.
///
/// Boundary conditions (FEM_NOTES "Boundary conditions decide the answer"). The grips are the nodes
/// within `grip_length` of either end (only the end faces by default). They are moved apart along
/// x: ux = -delta/2 on the left grip, +delta/2 on the right one. With free grips nothing else is
/// prescribed there, so the ends contract and shear freely: a single ply is then in exactly
/// homogeneous uniaxial stress (a uniform ux on a plane x = const is compatible with it), and the
/// measured modulus is 1/S11-bar. The three rigid modes the grips leave (translation along y and
/// z, rotation about x) are removed on the mid-plane at the left end, through `*EQUATION`s that
/// interpolate between the node levels straddling z = 0: uy = uz = 0 at (0, ~W/2, 0) and uz = 0 at
/// (0, 0, 0). These supports are statically determinate, so they carry no force; they only fix
/// the rigid part of the displacement field. Clamped grips also hold uy = 0 on the grips.
///
/// Typical use (the moduli of a laminate, and a hole-in-plate field):
///
///   FemSpecimen coupon{plies, 20e-3, 10e-3};  // or {laminate_plies(spec), L, W} (core/laminate)
///   FemTensionResult r = fem_tension_test(coupon, FemSettings{});
///   if (!r.available) fmt::print("{}: FEM column skipped\n", r.message);
///
///   FemSpecimen plate{plies, 60e-3, 36e-3, 3e-3};
///   FemSettings s;
///   s.loading.end_displacement = 0.1e-3;
///   FemSolution f = run_calculix(plate, s);
///   std::optional<Eigen::Vector3d> u = f.displacement.at(x, y);  // mid-plane, nullopt in the hole

#include <Eigen/Dense>
#include <optional>
#include <string>
#include <vector>

#include "core/elasticity.hpp"
#include "core/model.hpp"
#include "experiments/protocols/tension.hpp"

namespace plydem {

/// The solid element. C3D8I (8 nodes, incompatible modes) is fast and bends well with one
/// element per ply; C3D20R (20 nodes, reduced integration) is the quadratic reference. On
/// [0/30/45]s they agree to about 0.01% (FEM_NOTES), at ~15x the cost for C3D20R.
enum class FemElement { kC3D8I, kC3D20R };

/// "C3D8I" or "C3D20R".
const char* fem_element_name(FemElement element);

/// A transverse crack cut into a FEM specimen: the plane x = `x` across the full width, through
/// the plies first_ply .. last_ply (0 = the bottom one). The mesh has a node plane there and the
/// elements on its two sides do not share the nodes inside the cracked plies, so the crack's faces
/// are free (and may not touch: the problem is linear, for a crack that opens). The plies outside
/// stay whole: the crack ends at the interfaces that bound it, sharing their nodes (its tips), or
/// at the laminate's top or bottom face. The cross-ply's transverse crack, for example, runs
/// through the 90° layer and ends at the 0° plies.
struct FemTransverseCrack {
  double x = 0;       ///< [m], inside (0, L)
  int first_ply = 0;  ///< the lowest cracked ply (0 = bottom)
  int last_ply = 0;   ///< the highest cracked ply, >= first_ply
};

/// The specimen: a laminate cut as an L x W rectangle, optionally with a central circular hole or
/// with transverse cracks.
struct FemSpecimen {
  std::vector<Ply> plies;    ///< bottom (z = -h/2) to top
  double length = 10e-3;     ///< L, along x [m]
  double width = 2e-3;       ///< W, along y [m]
  double hole_diameter = 0;  ///< D [m]; 0 = no hole. A hole needs L >= W and D < W.
  /// Transverse cracks (not with a hole), at distinct x; none may cut every ply (that parts the
  /// specimen in two).
  std::vector<FemTransverseCrack> cracks{};

  /// h, the sum of the ply thicknesses [m].
  double thickness() const;
  /// Throws plydem::Error naming the first problem: no plies, an invalid ply material, a
  /// non-finite angle, a non-positive ply thickness, a non-positive or non-finite size, a hole
  /// that does not fit, or a crack outside the specimen, through plies it does not have, through
  /// every ply, at the x of another, or beside a hole.
  void validate() const;
};

/// How finely the specimen is meshed.
struct FemMeshSettings {
  FemElement element = FemElement::kC3D8I;
  int elements_per_ply = 1;  ///< elements through each ply's thickness
  /// In-plane element size away from the hole [m]; 0 = W / 8 (W / 16 with a hole: the ring
  /// of elements around the hole is mapped onto the W x W square that contains it).
  double element_size = 0;
  /// In-plane element size along the hole's edge [m]; 0 = pi D / 64 (16 elements a quarter).
  double hole_element_size = 0;

  /// Throws plydem::Error naming the first bad setting.
  void validate() const;
};

/// How the specimen is pulled.
struct FemLoading {
  /// How far the grips move apart along x in total, half at each end [m]; 0 = 1e-3 L (a nominal
  /// strain of 0.1%). The problem is linear, so moduli do not depend on it.
  double end_displacement = 0;
  /// Nodes within this distance of either end are gripped [m]; 0 = only the end faces.
  double grip_length = 0;
  /// kFree: only ux is prescribed on the grips (uniaxial stress); kClamped: also uy = 0.
  GripCondition grips = GripCondition::kFree;
};

struct FemSettings {
  FemMeshSettings mesh;
  FemLoading loading;
  /// Central fraction of the length whose mid-plane displacements give the fitted strains.
  double gauge_fraction = 0.5;
  /// Gauge nodes closer than this to a free edge (y = 0 or y = W) are left out of the strain fit
  /// [m]. A laminate's free-edge zone (about one thickness wide) contracts differently from the
  /// CLT state inside; 0 = the full width.
  double edge_band = 0;
  /// The CalculiX executable: a name looked up on PATH, or a path.
  std::string executable = "ccx";
  int threads = 1;  ///< OMP_NUM_THREADS and CCX_NPROC_EQUATION_SOLVER for ccx
  /// Also read the element stresses (`*EL PRINT, GLOBAL=YES`), averaged over each element's
  /// integration points. Costs a larger `.dat` file; off by default.
  bool element_stresses = false;
  /// Where ccx runs. Empty: a fresh temporary directory, removed afterwards. Otherwise this
  /// directory (created if missing) keeps job.inp, job.dat, job.log for inspection.
  std::string work_directory;

  /// Throws plydem::Error naming the first bad setting.
  void validate() const;
};

/// Whether CalculiX can be run.
struct CalculixAvailability {
  bool available = false;
  std::string executable;  ///< the resolved path when available
  /// When unavailable, why, in one line: "CalculiX (ccx) is not installed: ...".
  std::string message;
};
/// Looks `executable` up (on PATH unless it contains a '/'); never throws.
CalculixAvailability calculix_availability(const std::string& executable = "ccx");

/// A structured hexahedral mesh of a FemSpecimen, ready to be written as a CalculiX deck.
///
/// In plane, a quadrilateral mesh: a rectangular grid for a plain coupon; with a hole, an O-grid
/// around the hole (rings blended linearly from the hole's circle to the W x W square around it,
/// graded geometrically from the hole element size to the outer one) joined node to node to
/// rectangular grids on either side. The quadrilateral mesh is extruded through the plies. A
/// specimen's transverse cracks get node columns at their x (each stretch between them meshed
/// uniformly) and twin nodes for the elements on their +x side (FemTransverseCrack); the corner
/// grid holds the -x side's nodes there.
/// Quadratic elements take their mid-edge nodes from the same mapping, so they lie on the hole's
/// circle. The "corner grid" (plane_position, plane_quad, level_z, level_node) is the mesh's
/// element corners in plane, on every node level through the thickness (C3D20R: the elements'
/// corner levels and their mid levels): what FemDisplacementField interpolates on.
struct FemMesh {
  FemElement element = FemElement::kC3D8I;
  Vector3Array node_position;  ///< row = node index; CalculiX node id = index + 1 [m]
  /// One row per element: 8 or 20 node indices in CalculiX's order (for C3D20R: 8 corners, the
  /// 4 mid-edge nodes of the bottom face, the 4 of the top face, the 4 vertical mid-edge nodes).
  Eigen::Array<int, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> element_nodes;
  Eigen::ArrayXi element_ply;  ///< ply index of each element (0 = bottom)

  Eigen::Array<double, Eigen::Dynamic, 2> plane_position;  ///< in-plane corner nodes [m]
  Eigen::Array<int, Eigen::Dynamic, 4> plane_quad;         ///< counter-clockwise seen from +z
  std::vector<double> level_z;  ///< z of the node levels, bottom to top [m]
  /// level_node(p, l): the node at plane corner node p on level l.
  Eigen::ArrayXXi level_node;

  int node_count() const { return static_cast<int>(node_position.rows()); }
  int element_count() const { return static_cast<int>(element_nodes.rows()); }
};

/// Meshes the specimen. Throws plydem::Error if the specimen or the settings are invalid or the
/// mesh would exceed 2 million elements.
FemMesh build_fem_mesh(const FemSpecimen& specimen, const FemMeshSettings& settings);

/// The CalculiX input deck for `mesh` of `specimen` under `loading` (end_displacement > 0 here):
/// nodes, elements per ply, materials, orientations, grips and mid-plane supports, one linear
/// static step printing U (all nodes), the reaction totals of both grips and, if asked, the element
/// stresses in global axes. Material constants are written with 10 significant digits (input
/// lines are limited to 132 characters), coordinates exactly.
std::string calculix_input(const FemSpecimen& specimen, const FemMesh& mesh,
                           const FemLoading& loading, bool element_stresses);

/// The nodal displacements of a solved mesh, and their interpolation anywhere in the plate.
///
/// Interpolation is trilinear on the corner grid: the point's quadrilateral is found through a
/// bucket grid, its bilinear map inverted by Newton's method, the four corners' values combined
/// with the bilinear weights on the two node levels that straddle z, then linearly in z. This is
/// exactly the C3D8 displacement field (C3D8I's incompatible modes are internal to each element
/// and not part of it); for C3D20R it uses the corner and vertical mid-edge nodes (every node
/// level) and leaves out the in-plane mid-edge nodes. To compare with a DEM field,
/// sample both on one grid inside the plate; the supports fix the rigid translation along y at
/// the left end, so remove the mean uy of each field (or fit and remove an in-plane rigid motion)
/// before comparing uy.
class FemDisplacementField {
 public:
  FemDisplacementField() = default;
  /// Throws plydem::Error if the displacement array does not match the mesh.
  FemDisplacementField(const FemMesh& mesh, Vector3Array displacement);

  bool empty() const { return node_displacement_.rows() == 0; }
  const Vector3Array& node_position() const { return node_position_; }
  const Vector3Array& node_displacement() const { return node_displacement_; }
  /// The displacement [m] at (x, y, z); nullopt outside the plate (in the hole too, beyond the
  /// polygon of its meshed edge). z = 0 is the mid-plane, +-h/2 the top and bottom faces.
  std::optional<Eigen::Vector3d> at(double x, double y, double z = 0) const;

 private:
  Vector3Array node_position_;
  Vector3Array node_displacement_;
  Eigen::Array<double, Eigen::Dynamic, 2> plane_position_;
  Eigen::Array<int, Eigen::Dynamic, 4> plane_quad_;
  std::vector<double> level_z_;
  Eigen::ArrayXXi level_node_;
  // Bucket grid over the plane: the quadrilaterals whose bounding box overlaps each cell.
  Eigen::Vector2d bucket_origin_ = Eigen::Vector2d::Zero();
  double bucket_size_ = 0;
  int buckets_x_ = 0, buckets_y_ = 0;
  std::vector<std::vector<int>> bucket_quads_;
};

/// How far a particle model's displacement field lies from a FEM one, at the particles.
struct FieldComparison {
  int points = 0;   ///< particles inside the FEM plate (the others are skipped)
  int skipped = 0;  ///< particles outside it (beyond the plate, in the hole)
  /// |ux_particles - ux_fem| / |ux_fem|, 2-norms over the compared particles.
  double ux_error = 0;
  /// |uy_particles - uy_fem - c| / |uy_fem - mean(uy_fem)| with c = mean(uy_particles - uy_fem):
  /// the rigid translation along y, which the two models' supports fix differently, is removed
  /// (the grips hold ux, so there is no rigid ux or in-plane rotation to remove).
  double uy_error = 0;
};
/// Samples `fem` at each particle's reference position (x, y, z - z_offset) and compares with the
/// particle's displacement: the relative L2 errors of ux and uy. `z_offset` is the particle
/// model's mid-plane z: 0 for a single layer, (n - 1) t / 2 for build_laminate's n plies of
/// thickness t (strategies/laminate.hpp puts ply k at z = k t). Throws plydem::Error if fewer than
/// 2 particles lie in the FEM plate or the FEM field is empty.
FieldComparison compare_displacements(const FemDisplacementField& fem, const Particles& particles,
                                      double z_offset = 0);

/// What one CalculiX run measured.
struct FemSolution {
  /// False when ccx could not be found; then only `message` is set.
  bool available = false;
  std::string message;
  FemElement element = FemElement::kC3D8I;
  int nodes = 0, elements = 0;
  int degrees_of_freedom = 0;   ///< 3 per node
  double end_displacement = 0;  ///< total grip travel [m]
  /// The x-force the grips carry, 0.5 (RF_right - RF_left) from the reaction totals [N].
  /// reaction_force / end_displacement is the specimen's axial stiffness between the grips [N/m]:
  /// the measure for a cracked specimen, whose mid-plane (the strain fit below) may be cut.
  double reaction_force = 0;
  /// reaction_force / (W h): the mean axial stress of the full cross-section [Pa].
  double gross_stress = 0;
  /// Least-squares fit of ux = a + exx x + c y, uy = b + d x + eyy y over the mid-plane nodes of
  /// the central gauge section (gamma_xy = c + d), less the edge bands; with a hole, the section's
  /// mean strain.
  double exx = 0, eyy = 0, gamma_xy = 0;
  /// The gauge section's mean through-thickness strain, (uz_top - uz_bottom) / h.
  double ezz = 0;
  FemDisplacementField displacement;
  /// With FemSettings::element_stresses: per element, the centroid of its nodes [m] and the mean
  /// of its integration-point stresses in global axes, columns xx yy zz xy xz yz [Pa]. Empty
  /// otherwise.
  Vector3Array element_centroid;
  Eigen::Array<double, Eigen::Dynamic, 6> element_stress;
  Eigen::ArrayXi element_ply;
  double solver_seconds = 0;  ///< ccx's wall time
  double wall_seconds = 0;    ///< meshing, writing, ccx and reading
};

/// Meshes `specimen`, runs CalculiX and measures it. Throws plydem::Error for invalid input, and
/// when ccx runs but fails (the message quotes its log's error lines). A missing ccx is not an
/// error: the solution comes back with available = false and the reason.
FemSolution run_calculix(const FemSpecimen& specimen, const FemSettings& settings);

/// The in-plane moduli of a laminate, measured like the DEM tension test.
struct FemTensionResult {
  bool available = false;
  std::string message;  ///< why not, when unavailable
  /// Ex = gross_stress / exx, nu_xy = -eyy / exx, shear_coupling_x = gamma_xy / exx from the pull
  /// along x; Ey and nu_yx from the same coupon with every ply turned by -90 deg (the laminate
  /// pulled along its y axis). Gxy is not measured (0).
  InPlaneConstants fem;
  double nu_xz = 0;  ///< -ezz / exx of the pull along x
  /// CLT of the laminate from core/elasticity (laminate_constants), for reports.
  InPlaneConstants theory;
  FemSolution along_x, along_y;
};

/// Two CalculiX runs (the layup as given, and turned by -90 deg) of the specimen, which must have
/// no hole. Unavailable (not thrown) when ccx is missing.
FemTensionResult fem_tension_test(const FemSpecimen& specimen, const FemSettings& settings);

/// How the CalculiX twin of a DEM tension test (fem_twin_tension_test) is meshed and run.
struct FemTwinSettings {
  /// element_size 0 = two particle diameters (W / 8 if that is finer); two elements through each
  /// ply. On a [45/-45]s E-glass coupon 3 x 0.83 mm (0.05 mm particles) this lies within 0.1% of
  /// the converged Ex: one element per ply is 0.45% stiff, three and four move Ex by -0.07% and
  /// -0.10% (the free edges' interlaminar stresses need the layers); halving the in-plane size
  /// moves it by 0.02%.
  FemMeshSettings mesh{.element = FemElement::kC3D8I, .elements_per_ply = 2};
  std::string executable = "ccx";
  int threads = 1;
};

/// CalculiX of a DEM tension test's own coupons, "the same coupon": the plies, length, width and
/// grips (length, free or clamped) of `settings`; each pull's strain fitted, as the DEM's is
/// (core/measurements.hpp), on the FEM displacement field sampled at the very particles that gave
/// the DEM's strain (its gauge section and edge band, each particle at its ply's mid-surface);
/// the stress is the grips' force over the gross section W h. The pull along y turns every ply
/// by -90 deg, as the DEM's does. Free edges, a narrow coupon's free-edge zones and the grips are
/// then physics that both models share, and the DEM against this FEM is the particle model's own
/// error. `dem` must come from a TensionTest run with `settings` (its coupons' models are read for
/// the gauge particles). Unavailable (not thrown) when ccx is missing; throws plydem::Error when a
/// coupon has no gauge particle inside the FEM plate.
FemTensionResult fem_twin_tension_test(const TensionSettings& settings, const TensionResult& dem,
                                       const FemTwinSettings& twin);
/// The in-plane element size the twin uses [m] (twin.mesh.element_size, or its default).
double fem_twin_element_size(const TensionSettings& settings, const FemTwinSettings& twin);

}  // namespace plydem
