#pragma once
/// \file
/// The lamina's material: a transversely isotropic ply with the fibre along local axis 1
/// (paper Table 1, with ERRATA §2: nu13 = nu12). SI units (Pa, kg/m^3).

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace plydem {

/// A ply's strengths and fracture energies (paper's future work; ../shared/DAMAGE_NOTES.md §1),
/// all optional: 0 = not given. Strengths are magnitudes (XC and YC positive in compression).
struct LaminaStrength {
  double XT = 0;        ///< longitudinal tensile strength [Pa]
  double XC = 0;        ///< longitudinal compressive strength [Pa]
  double YT = 0;        ///< transverse tensile strength [Pa]
  double YC = 0;        ///< transverse compressive strength [Pa]
  double S12 = 0;       ///< in-plane shear strength [Pa]
  double G_fibre = 0;   ///< fracture energy of a crack across the fibres [J/m^2]
  double G_matrix = 0;  ///< fracture energy of a crack along the fibres [J/m^2]
  /// Weibull modulus m of the bonds' strength scatter; 0 = no scatter.
  double weibull_modulus = 0;
  /// Puck's inclination parameters of the inter-fibre fracture envelope
  /// (core/failure_criteria.hpp), p12+ under transverse tension and p12- under compression: Puck's
  /// values for glass/epoxy unless the material file gives puck_p12_tension and
  /// puck_p12_compression (carbon/epoxy: about 0.35, 0.30).
  double puck_p12_tension = 0.30;
  double puck_p12_compression = 0.25;

  /// XT, YT and S12 are all given (what a tension test to failure needs).
  bool tensile_and_shear() const { return XT > 0 && YT > 0 && S12 > 0; }
  /// G_fibre and G_matrix are both given (what softening bonds need).
  bool fracture_energies() const { return G_fibre > 0 && G_matrix > 0; }
};

/// How a breaking model decides that the ply fails (material key `failure_criterion`): bond by bond
/// with the PFC parallel-bond law ("bond", the default), or at the material point by a lamina
/// criterion ("hashin", "puck", "max-stress", "tsai-wu"; core/failure_criteria.hpp).
enum class PlyFailureModel { kBond, kHashin, kPuck, kMaxStress, kTsaiWu };

/// The material file's name of a failure model, and the model of a name (nullopt if unknown).
const char* failure_model_name(PlyFailureModel model);
std::optional<PlyFailureModel> failure_model_from_name(std::string_view name);
/// The model of a name; throws plydem::Error "unknown failure_criterion 'NAME' (expected one of
/// ...)" for any other (the material file and Python give the same message).
PlyFailureModel failure_model_named(std::string_view name);
/// "bond, hashin, puck, max-stress, tsai-wu".
std::string failure_model_names();

/// One point the ply's in-plane shear response passes through (material key `shear_curve`).
struct ShearCurvePoint {
  double strain = 0;  ///< engineering shear strain gamma12 [-]
  double stress = 0;  ///< tau12 [Pa]
};

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
  LaminaStrength strength;  ///< optional (all zero for a material without strengths)
  PlyFailureModel failure_criterion = PlyFailureModel::kBond;
  /// The measured in-plane shear curve, strictly increasing in both strain and stress, never above
  /// the linear G12 gamma line; empty: linear to S12 (core/shear_curve.hpp fits it).
  std::vector<ShearCurvePoint> shear_curve;
  /// Coefficients of thermal expansion along the fibre and across it (alpha3 = alpha2) [1/K], for
  /// cure stresses (strategies/cure_stress.hpp); thermal_expansion_given is false for a material
  /// without them (material file keys alpha1, alpha2: both or neither).
  double alpha1 = 0, alpha2 = 0;
  bool thermal_expansion_given = false;

  double nu21() const { return nu12 * E2 / E1; }
  double G23() const { return E2 / (2.0 * (1.0 + nu23)); }
};

/// Throws plydem::Error naming the problem unless every constant is finite and positive (density
/// too) and the 3D compliance of the transversely isotropic ply is positive definite; every
/// strength and fracture energy given must be finite and positive (0 = not given).
void validate(const Material& material);

/// Throws plydem::Error naming the material and every one of XT, YT, S12 it lacks, and what needs
/// them (`purpose`, e.g. "the cross-ply experiment"); with `softening`, G_fibre and G_matrix too.
/// Also refuses a material whose failure_criterion is not "bond": failure at the material point
/// runs in plydem strength only (experiments/protocols/strength.hpp require_strength_run), and a
/// breaking run would otherwise break bond by bond without saying so.
void require_strengths(const Material& material, const std::string& purpose,
                       bool softening = false);

/// Names of the built-in materials: "eglass-my750" (paper Table 1, with the WWFE-I strengths of
/// Soden, Hinton & Kaddour, Compos. Sci. Technol. 58 (1998) 1011), and the WWFE-I carbon/epoxy
/// plies "t300-914c" and "as4-3501-6" (same source, Table 1).
std::vector<std::string> builtin_material_names();

/// A built-in material by name, or a TOML file with keys name, E1, E2, G12, nu12, nu23 (SI, Pa) and
/// optionally density (kg/m^3), strengths XT, XC, YT, YC, S12 (Pa), fracture energies G_fibre,
/// G_matrix (J/m^2) and weibull_modulus. Validated before it is returned; throws plydem::Error
/// otherwise.
Material load_material(const std::string& name_or_file);
/// The material file's TOML text, read as load_material reads a file; `origin` names it in
/// messages.
Material parse_material(const std::string& text, const std::string& origin);

}  // namespace plydem
