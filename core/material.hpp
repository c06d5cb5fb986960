#pragma once
/// \file
/// The lamina's material: a transversely isotropic ply with the fibre along local axis 1
/// (paper Table 1, with ERRATA §2: nu13 = nu12). SI units (Pa, kg/m^3).

#include <string>
#include <vector>

namespace plydem {

struct Material {
  std::string name;
  double E1 = 0;    ///< fibre-direction Young's modulus [Pa]
  double E2 = 0;    ///< transverse Young's modulus, E3 = E2 [Pa]
  double G12 = 0;   ///< in-plane shear modulus, G13 = G12 [Pa]
  double nu12 = 0;  ///< major Poisson's ratio, -eps2/eps1 under sigma1; nu13 = nu12
  double nu23 = 0;  ///< transverse Poisson's ratio
  /// Mass density [kg/m^3]. Not in the paper's Table 1; it sets the particles' masses and so the
  /// explicit time step, never an elastic result.
  double density = 2000.0;

  double nu21() const { return nu12 * E2 / E1; }
  double G23() const { return E2 / (2.0 * (1.0 + nu23)); }
};

/// Throws plydem::Error naming the problem unless every constant is finite and positive (density
/// too) and the 3D compliance of the transversely isotropic ply is positive definite.
void validate(const Material& material);

/// Names of the built-in materials ("eglass-my750", paper Table 1).
std::vector<std::string> builtin_material_names();

/// A built-in material by name, or a TOML file with keys name, E1, E2, G12, nu12, nu23 (SI, Pa) and
/// optionally density (kg/m^3). Validated before it is returned; throws plydem::Error otherwise.
Material load_material(const std::string& name_or_file);

}  // namespace plydem
