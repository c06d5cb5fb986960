/// \file
/// What a strategy written in Python builds with: the elasticity and homogenization helpers
/// (reduced_stiffness, affine_stiffness, relaxed_stiffness, ...), the one specimen assembler and
/// the boundary-cell completion, and the laminates built from a strategy.
#include "python/export.hpp"

#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "core/elasticity.hpp"
#include "core/homogenizer.hpp"
#include "core/model.hpp"
#include "strategies/boundary_cells.hpp"
#include "strategies/laminate.hpp"
#include "strategies/specimen.hpp"
#include "strategies/strategy.hpp"

namespace plydem::python {

namespace {

py::array matrix6(const Matrix6d& m) {
  py::array_t<double> result({6, 6});
  auto r = result.mutable_unchecked<2>();
  for (int i = 0; i < 6; ++i)
    for (int k = 0; k < 6; ++k) r(i, k) = m(i, k);
  return result;
}

}  // namespace

void export_homogenization(py::module_& m) {
  m.def("reduced_stiffness", &reduced_stiffness, py::arg("material"),
        "The ply's plane-stress stiffness Q in its own axes (1 along the fibre) [Pa], 3x3.");
  m.def("rotate_reduced_stiffness", &rotate_reduced_stiffness, py::arg("Q"), py::arg("ply_angle"),
        "Q-bar: Q turned by the ply angle [rad] into the specimen frame (x along the coupon).");
  m.def(
      "affine_stiffness",
      [](const UnitCell& cell, const std::vector<FamilyStiffness>& families) {
        return matrix6(affine_stiffness(cell, families));
      },
      py::arg("cell"), py::arg("families"),
      "The eq. (5) lattice sum of the cell with the families' springs (particles move with the "
      "strain, no spin): 6x6 stiffness [Pa], Voigt order 11 22 33 23 13 12.");
  m.def(
      "relaxed_stiffness",
      [](const UnitCell& cell, const std::vector<FamilyStiffness>& families) {
        return matrix6(relaxed_stiffness(cell, families));
      },
      py::arg("cell"), py::arg("families"),
      "The stiffness of the cell with spins and sublattice shifts at minimum energy, what the "
      "engine simulates: 6x6 [Pa].");
  m.def(
      "in_plane_block",
      [](const py::object& stiffness) { return in_plane_block(square_matrix<6>(stiffness, "")); },
      py::arg("stiffness"), "The (xx, yy, xy) block of a 6x6 stiffness: 3x3 [Pa].");
  m.def(
      "relative_difference",
      [](const py::object& a, const py::object& b) {
        return relative_difference(square_matrix<3>(a, "a"), square_matrix<3>(b, "b"));
      },
      py::arg("a"), py::arg("b"), "|a - b|_F / |b|_F of two 3x3 stiffnesses.");
}

void export_specimen(py::module_& m) {
  m.def(
      "assemble_specimen",
      [](const Eigen::Array<double, Eigen::Dynamic, 3>& position, double radius,
         double particle_volume, double density, const Eigen::ArrayXXi& pairs,
         const std::vector<int>& family, double thickness, const std::string& description,
         const std::vector<FamilyCalibration>& families) {
        require(pairs.cols() == 2 || pairs.size() == 0, "pairs must be an (m, 2) integer array");
        SpecimenLayout layout;
        layout.position = position;
        layout.radius = radius;
        layout.particle_volume = particle_volume;
        layout.density = density;
        for (Eigen::Index b = 0; b < pairs.rows(); ++b) {
          layout.pairs.emplace_back(pairs(b, 0), pairs(b, 1));
        }
        require(family.empty() || family.size() == layout.pairs.size(),
                "family has " + std::to_string(family.size()) + " entries for " +
                    std::to_string(layout.pairs.size()) + " pairs");
        for (int f : family) {
          require(f >= 0 && f < static_cast<int>(families.size()),
                  "bond family " + std::to_string(f) + " has no calibration (" +
                      std::to_string(families.size()) + " families given)");
        }
        layout.family = family;
        layout.thickness = thickness;
        layout.description = description;
        py::gil_scoped_release release;
        auto model = std::make_shared<Model>(assemble_specimen(layout, &families));
        model->check_consistency();
        return model;
      },
      py::arg("position"), py::arg("radius"), py::arg("particle_volume"), py::arg("density"),
      py::arg("pairs"), py::arg("family"), py::arg("thickness"), py::arg("description"),
      py::arg("families"),
      "The one specimen assembler (strategies/specimen.hpp) for a packing made in Python: "
      "particles at `position` ((n, 3) [m]) of one radius [m], each standing for "
      "particle_volume [m^3] of ply of `density` [kg/m^3] (mass, solid-sphere inertia), bonds "
      "between the rows of `pairs` ((m, 2) ints) with their geometry, bond b getting the springs "
      "of families[family[b]] (a list of FamilyCalibration, e.g. calibration.families) as a "
      "parallel bond of the particle radius. Grips are set by the tests. Returns a checked "
      "Model.");
  m.def(
      "complete_boundary_cells",
      [](Model& model, int family_count, int bulk_bonds) {
        return complete_boundary_cells(model.particles, model.bonds, family_count, bulk_bonds);
      },
      py::arg("model"), py::arg("family_count"), py::arg("bulk_bonds"),
      "Lets the bonds at free edges carry the share of their missing partners "
      "(strategies/boundary_cells.hpp), for a packing whose bulk particles have bulk_bonds bonds "
      "of each of family_count families; returns the number of bonds changed.");
}

void export_laminate(py::module_& m) {
  m.def("parse_layup", &parse_layup, py::arg("layup"),
        "A layup string, bottom ply first ('[0/90/0]', '[0/±45/90]s', ...) as angles [rad].");
  m.def(
      "build_laminate",
      [](const Strategy& strategy, const CouponSpec& coupon, const std::string& layup,
         double interface_normal, double interface_shear) {
        LaminateSpec spec;
        spec.coupon = coupon;
        spec.ply_angles = parse_layup(layup);
        spec.interface.normal = interface_normal;
        spec.interface.shear = interface_shear;
        py::gil_scoped_release release;
        Specimen specimen = build_laminate(strategy, spec);
        return std::make_shared<Model>(std::move(specimen.model));
      },
      py::arg("strategy"), py::arg("coupon"), py::arg("layup"), py::arg("interface_normal") = 0.0,
      py::arg("interface_shear") = 0.0,
      "Builds a laminate (paper Sec. 3.5): every ply of `layup` with the coupon's material and "
      "size (its ply_angle ignored), joined by interface bonds [N/m^3 per unit area; 0 = 10 E2/t "
      "and 10 G12/t].");
}

}  // namespace plydem::python
