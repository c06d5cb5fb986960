/// \file
/// plydem.LaminaStrength, plydem.Material (with load_material, builtin_materials) and
/// plydem.CouponSpec.
#include "python/export.hpp"

#include <string>
#include <utility>
#include <vector>

#include "core/material.hpp"
#include "experiments/runner/settings_descriptions.hpp"
#include "python/settings_python.hpp"
#include "strategies/strategy.hpp"

namespace plydem::python {

void export_material(py::module_& m) {
  py::class_<LaminaStrength>(m, "LaminaStrength",
                             "A ply's strengths [Pa] and fracture energies [J/m^2], 0 = not "
                             "given (core/material.hpp); keywords set them.")
      .def(py::init([](py::kwargs kwargs) { return from_kwargs<LaminaStrength>(kwargs); }),
           "LaminaStrength(XT=..., XC=..., YT=..., YC=..., S12=..., G_fibre=..., G_matrix=..., "
           "weibull_modulus=...)")
      .def_readwrite("XT", &LaminaStrength::XT, "longitudinal tensile strength [Pa]")
      .def_readwrite("XC", &LaminaStrength::XC, "longitudinal compressive strength [Pa]")
      .def_readwrite("YT", &LaminaStrength::YT, "transverse tensile strength [Pa]")
      .def_readwrite("YC", &LaminaStrength::YC, "transverse compressive strength [Pa]")
      .def_readwrite("S12", &LaminaStrength::S12, "in-plane shear strength [Pa]")
      .def_readwrite("G_fibre", &LaminaStrength::G_fibre,
                     "fracture energy of a crack across the fibres [J/m^2]")
      .def_readwrite("G_matrix", &LaminaStrength::G_matrix,
                     "fracture energy of a crack along the fibres [J/m^2]")
      .def_readwrite("weibull_modulus", &LaminaStrength::weibull_modulus,
                     "Weibull modulus of the bonds' strength scatter; 0 = none")
      .def_readwrite("puck_p12_tension", &LaminaStrength::puck_p12_tension,
                     "Puck's inclination parameter p12+ (transverse tension; default 0.30)")
      .def_readwrite("puck_p12_compression", &LaminaStrength::puck_p12_compression,
                     "Puck's inclination parameter p12- (transverse compression; default 0.25)");
  py::class_<Material>(m, "Material",
                       "A transversely isotropic ply, fibre along local axis 1 (paper Table 1). "
                       "Keywords: name, E1, E2, G12 [Pa], nu12, nu23, density [kg/m^3]; validated "
                       "(positive constants, positive-definite compliance).")
      .def(py::init([](py::kwargs kwargs) {
             Material material = from_kwargs<Material>(kwargs);
             validate(material);
             return material;
           }),
           "Material(name=..., E1=..., E2=..., G12=..., nu12=..., nu23=..., density=2000): raises "
           "plydem.Error unless the constants make a stable ply.")
      .def_readwrite("name", &Material::name, "label for reports")
      .def_readwrite("E1", &Material::E1, "fibre-direction Young's modulus [Pa]")
      .def_readwrite("E2", &Material::E2, "transverse Young's modulus, E3 = E2 [Pa]")
      .def_readwrite("G12", &Material::G12, "in-plane shear modulus, G13 = G12 [Pa]")
      .def_readwrite("nu12", &Material::nu12, "major Poisson's ratio; nu13 = nu12")
      .def_readwrite("nu23", &Material::nu23, "transverse Poisson's ratio")
      .def_readwrite("density", &Material::density, "mass density [kg/m^3]")
      .def_readwrite("strength", &Material::strength,
                     "LaminaStrength: XT, XC, YT, YC, S12 [Pa], G_fibre, G_matrix [J/m^2], "
                     "weibull_modulus (0 = not given)")
      .def_property(
          "failure_criterion",
          [](const Material& x) { return std::string(failure_model_name(x.failure_criterion)); },
          [](Material& x, const std::string& name) {
            x.failure_criterion = failure_model_named(name);
          },
          "how breaking runs decide failure: bond (the default; the only one the engine simulates "
          "yet), hashin, puck, max-stress, tsai-wu")
      .def_property(
          "shear_curve",
          [](const Material& x) {
            py::list points;
            for (const ShearCurvePoint& p : x.shear_curve)
              points.append(py::make_tuple(p.strain, p.stress));
            return points;
          },
          [](Material& x, const std::vector<std::pair<double, double>>& points) {
            x.shear_curve.clear();
            for (const auto& [strain, stress] : points) x.shear_curve.push_back({strain, stress});
          },
          "the measured in-plane shear curve: [(gamma12, tau12 [Pa]), ...] (validate() checks it)")
      .def_property_readonly("nu21", &Material::nu21, "minor Poisson's ratio nu12 E2 / E1")
      .def_property_readonly("G23", &Material::G23, "transverse shear modulus E2 / (2 (1 + nu23))")
      .def(
          "validate", [](const Material& material) { validate(material); },
          "Raises plydem.Error naming the problem unless the ply is stable.")
      .def("__repr__", [](const Material& x) {
        return "Material(name='" + x.name + "', E1=" + std::to_string(x.E1) +
               ", E2=" + std::to_string(x.E2) + ", G12=" + std::to_string(x.G12) +
               ", nu12=" + std::to_string(x.nu12) + ", nu23=" + std::to_string(x.nu23) + ")";
      });
  m.def("load_material", &load_material, py::arg("name_or_file"),
        "A built-in material by name (see builtin_materials()) or a TOML file with name, E1, E2, "
        "G12, nu12, nu23 [Pa] and optionally density; validated.");
  m.def("builtin_materials", &builtin_material_names, "Names of the built-in materials.");
}

void export_coupon(py::module_& m) {
  py::class_<CouponSpec> coupon(
      m, "CouponSpec",
      "The coupon a strategy builds: one ply, a rectangle in the x-y plane, long "
      "along x. Keywords: material, ply_angle [rad], length, width, thickness, "
      "particle_diameter [m], complete_boundary_cells.");
  coupon
      .def(py::init([](py::kwargs kwargs) {
             CouponSpec spec =
                 from_kwargs<CouponSpec>(kwargs, coupon_settings_description().defaults());
             spec.validate();
             return spec;
           }),
           "CouponSpec(**keywords); the material defaults to eglass-my750, sizes to the paper's "
           "coupon (10 x 0.83 mm, ply 0.2 mm, particles 0.05 mm).")
      .def_readwrite("material", &CouponSpec::material, "the ply's Material")
      .def("validate", &CouponSpec::validate, "Raises plydem.Error naming a bad size.");
  def_settings(coupon, coupon_settings_description());
}

}  // namespace plydem::python
