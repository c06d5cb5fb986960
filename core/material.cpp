#include "core/material.hpp"

#include <fmt/format.h>

#include <cmath>
#include <filesystem>
#include <optional>
#include <sstream>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "core/elasticity.hpp"
#include "core/error.hpp"
#include "core/toml_reader.hpp"

namespace plydem {
namespace {

// Six significant digits: enough to recognise the value the user gave.
std::string format_number(double value) {
  return fmt::format("{:.6g}", value);
}

// fmt, not operator+: GCC 12 at -O2 reports a false -Wrestrict on "'" + std::string + "'".
std::string in_quotes(std::string_view text) {
  return fmt::format("'{}'", text);
}

void require_finite_positive(const Material& material, const char* key, double value,
                             const char* unit) {
  require(std::isfinite(value) && value > 0, "material " + in_quotes(material.name) + ": " + key +
                                                 " must be finite and positive, got " +
                                                 format_number(value) + " " + unit);
}

void require_finite(const Material& material, const char* key, double value) {
  require(std::isfinite(value), "material " + in_quotes(material.name) + ": " + key +
                                    " must be finite, got " + format_number(value));
}

// Paper Table 1 (E-Glass/MY750), read with ERRATA §2: the fifth constant is nu12 = nu13.
Material eglass_my750() {
  Material m;
  m.name = "eglass-my750";
  m.E1 = 45.6e9;
  m.E2 = 16.2e9;
  m.G12 = 5.83e9;
  m.nu12 = 0.278;
  m.nu23 = 0.4;
  m.density = 2000.0;
  // WWFE-I (Soden, Hinton & Kaddour 1998, Table 1 of that paper; DAMAGE_NOTES §1). No fracture
  // energies are given there: softening needs them from a material file.
  m.strength.XT = 1280e6;
  m.strength.XC = 800e6;
  m.strength.YT = 40e6;
  m.strength.YC = 145e6;
  m.strength.S12 = 73e6;
  // WWFE-I (Soden et al. 1998, Table 1): alpha1 = 8.6e-6 /K, alpha2 = 26.4e-6 /K.
  m.alpha1 = 8.6e-6;
  m.alpha2 = 26.4e-6;
  m.thermal_expansion_given = true;
  return m;
}

// WWFE-I carbon/epoxy plies (Soden, Hinton & Kaddour 1998, Table 1): the most used composites,
// E1/E2 of 11-13 and G12 near E2/2, which is where a particle model's calibration is hardest. WWFE
// gives no density; 1550 and 1580 kg/m^3 are typical of 60% fibre volume (they only set the
// explicit solver's mass and time step).
Material t300_914c() {
  Material m;
  m.name = "t300-914c";
  m.E1 = 138e9;
  m.E2 = 11e9;
  m.G12 = 5.5e9;
  m.nu12 = 0.28;
  m.nu23 = 0.4;
  m.density = 1550.0;
  m.strength.XT = 1500e6;
  m.strength.XC = 900e6;
  m.strength.YT = 27e6;
  m.strength.YC = 200e6;
  m.strength.S12 = 80e6;
  return m;
}

Material as4_3501_6() {
  Material m;
  m.name = "as4-3501-6";
  m.E1 = 126e9;
  m.E2 = 11e9;
  m.G12 = 6.6e9;
  m.nu12 = 0.28;
  m.nu23 = 0.4;
  m.density = 1580.0;
  m.strength.XT = 1950e6;
  m.strength.XC = 1480e6;
  m.strength.YT = 48e6;
  m.strength.YC = 200e6;
  m.strength.S12 = 79e6;
  return m;
}

struct BuiltinMaterial {
  std::string_view name;
  Material (*make)();
};

constexpr BuiltinMaterial kBuiltinMaterials[] = {
    {"eglass-my750", eglass_my750}, {"t300-914c", t300_914c}, {"as4-3501-6", as4_3501_6}};

std::string builtin_list() {
  std::string list;
  for (const auto& name : builtin_material_names()) {
    if (!list.empty()) list += ", ";
    list += name;
  }
  return list;
}

constexpr std::string_view kNumberKeys[] = {
    "E1", "E2", "G12", "nu12", "nu23",    "density",  "XT",
    "XC", "YT", "YC",  "S12",  "G_fibre", "G_matrix", "weibull_modulus"};

// The optional strength entries, by key.
double* strength_entry(LaminaStrength& s, std::string_view key) {
  if (key == "XT") return &s.XT;
  if (key == "XC") return &s.XC;
  if (key == "YT") return &s.YT;
  if (key == "YC") return &s.YC;
  if (key == "S12") return &s.S12;
  if (key == "G_fibre") return &s.G_fibre;
  if (key == "G_matrix") return &s.G_matrix;
  if (key == "weibull_modulus") return &s.weibull_modulus;
  return nullptr;
}

// Keys that are not numbers among the strengths: the failure model, the shear curve and Puck's
// inclination parameters.
constexpr std::string_view kOtherKeys[] = {
    "failure_criterion",    "shear_curve", "puck_p12_tension",
    "puck_p12_compression", "alpha1",      "alpha2"};

bool is_known_key(std::string_view key) {
  if (key == "name") return true;
  for (auto known : kOtherKeys) {
    if (key == known) return true;
  }
  for (auto known : kNumberKeys) {
    if (key == known) return true;
  }
  return false;
}

std::string known_keys_list() {
  std::string list = "name";
  for (auto known : kNumberKeys) list += ", " + std::string(known);
  for (auto known : kOtherKeys) list += ", " + std::string(known);
  return list;
}

// A required or optional number; TOML integers are accepted (E1 = 45600000000 is a fine modulus).
std::optional<double> read_number(const toml::table& table, std::string_view key,
                                  const std::string& file, bool required) {
  const toml::node* node = table.get(key);
  if (node == nullptr) {
    require(!required, "material file " + in_quotes(file) + ": missing key " + in_quotes(key));
    return std::nullopt;
  }
  if (const std::optional<double> value = toml_number(*node)) return value;
  std::ostringstream type;
  type << node->type();
  throw Error("material file " + in_quotes(file) + ": key " + in_quotes(key) +
              " must be a number, got a " + type.str());
}

// failure_criterion, Puck's inclination parameters and shear_curve (validated with the rest by
// validate()).
void read_failure_model(const toml::table& table, const std::string& file, Material& m) {
  if (const toml::node* node = table.get("failure_criterion")) {
    const auto* name = node->as_string();
    require(name != nullptr, "material file " + in_quotes(file) +
                                 ": key 'failure_criterion' must be a string (one of " +
                                 failure_model_names() + ")");
    try {
      m.failure_criterion = failure_model_named(name->get());
    } catch (const Error& e) {
      throw Error("material file " + in_quotes(file) + ": " + e.what());
    }
  }
  if (auto p = read_number(table, "puck_p12_tension", file, false)) {
    m.strength.puck_p12_tension = *p;
  }
  if (auto p = read_number(table, "puck_p12_compression", file, false)) {
    m.strength.puck_p12_compression = *p;
  }
  const toml::node* curve = table.get("shear_curve");
  if (curve == nullptr) return;
  const std::string what = "material file " + in_quotes(file) + ": shear_curve";
  const auto* points = curve->as_array();
  require(points != nullptr && !points->empty(),
          what + " must be a non-empty list of [gamma12, tau12 in Pa] points");
  for (const toml::node& point : *points) {
    const auto* pair = point.as_array();
    require(pair != nullptr && pair->size() == 2,
            what + ": every point must be a pair [gamma12, tau12 in Pa]");
    const std::optional<double> strain = toml_number(*pair->get(0));
    const std::optional<double> stress = toml_number(*pair->get(1));
    require(strain && stress, what + ": every point must be two numbers [gamma12, tau12 in Pa]");
    m.shear_curve.push_back({*strain, *stress});
  }
}

// `text` is the file's content when given, else the file is read.
Material parse_material_file(const std::string& file, const std::string* text = nullptr) {
  const auto syntax_error = [&file](const TomlSyntaxError& e) {
    return "material file " + in_quotes(file) + ": TOML syntax error at line " +
           std::to_string(e.line) + ", column " + std::to_string(e.column) + ": " +
           std::string(e.description);
  };
  const toml::table table =
      text ? parse_toml(*text, file, syntax_error) : parse_toml_file(file, syntax_error);

  // Unknown keys are errors, not warnings: a typo such as "nu21" for "nu12" would otherwise leave
  // the intended constant missing or, worse, silently use a different one.
  for (const auto& [key, node] : table) {
    require(is_known_key(key.str()), "material file " + in_quotes(file) + ": unknown key " +
                                         in_quotes(key.str()) + " (expected " + known_keys_list() +
                                         ")");
  }

  Material m;
  const toml::node* name = table.get("name");
  require(name != nullptr, "material file " + in_quotes(file) + ": missing key 'name'");
  const auto* name_string = name->as_string();
  require(name_string != nullptr,
          "material file " + in_quotes(file) + ": key 'name' must be a string");
  m.name = name_string->get();

  m.E1 = *read_number(table, "E1", file, true);
  m.E2 = *read_number(table, "E2", file, true);
  m.G12 = *read_number(table, "G12", file, true);
  m.nu12 = *read_number(table, "nu12", file, true);
  m.nu23 = *read_number(table, "nu23", file, true);
  if (auto density = read_number(table, "density", file, false)) m.density = *density;
  for (auto key : kNumberKeys) {
    double* entry = strength_entry(m.strength, key);
    if (entry == nullptr) continue;
    if (auto value = read_number(table, key, file, false)) {
      // 0 means "not given" inside; a file that writes 0 (or less) means something else.
      require(*value > 0 && std::isfinite(*value),
              "material file " + in_quotes(file) + ": " + std::string(key) +
                  " must be finite and positive, got " + format_number(*value) +
                  " (leave the key out for a material without it)");
      *entry = *value;
    }
  }
  read_failure_model(table, file, m);
  const std::optional<double> alpha1 = read_number(table, "alpha1", file, false);
  const std::optional<double> alpha2 = read_number(table, "alpha2", file, false);
  require(alpha1.has_value() == alpha2.has_value(),
          "material file " + in_quotes(file) +
              ": give both alpha1 and alpha2 (the thermal expansion along and across the fibre, "
              "1/K) or neither");
  if (alpha1) {
    m.alpha1 = *alpha1;
    m.alpha2 = *alpha2;
    m.thermal_expansion_given = true;
  }
  return m;
}

// Puck's inclination parameters lie in [0, 1); the shear curve starts above zero, rises strictly in
// strain and stress, and never lies above the linear response G12 gamma (a secant modulus above
// G12 is not a softening curve; 0.1% of slack for digitised data).
void validate_failure_model(const Material& material) {
  const std::string who = "material " + in_quotes(material.name);
  for (const auto& [key, p] :
       {std::pair{"puck_p12_tension", material.strength.puck_p12_tension},
        std::pair{"puck_p12_compression", material.strength.puck_p12_compression}}) {
    require(std::isfinite(p) && p >= 0 && p < 1,
            who + ": " + key + " must lie in [0, 1), got " + format_number(p));
  }
  ShearCurvePoint previous{0, 0};
  for (std::size_t i = 0; i < material.shear_curve.size(); ++i) {
    const ShearCurvePoint& q = material.shear_curve[i];
    const std::string point = fmt::format("shear_curve point {} [{}, {} Pa]", i + 1,
                                          format_number(q.strain), format_number(q.stress));
    require(std::isfinite(q.strain) && std::isfinite(q.stress) && q.strain > 0 && q.stress > 0,
            who + ": " + point + ": gamma12 and tau12 must be finite and positive");
    require(q.strain > previous.strain && q.stress > previous.stress,
            who + ": " + point +
                ": the shear curve must rise strictly in both gamma12 and tau12 (it is not "
                "monotonic after the point before it)");
    require(q.stress <= material.G12 * q.strain * (1 + 1e-3),
            who + ": " + point + " lies above the linear response G12 gamma12 = " +
                format_number(material.G12 * q.strain) +
                " Pa: a measured shear curve softens from G12, it cannot be stiffer");
    previous = q;
  }
}

}  // namespace

void validate(const Material& material) {
  require_finite_positive(material, "E1", material.E1, "Pa");
  require_finite_positive(material, "E2", material.E2, "Pa");
  require_finite_positive(material, "G12", material.G12, "Pa");
  require_finite(material, "nu12", material.nu12);
  require_finite(material, "nu23", material.nu23);
  require_finite_positive(material, "density", material.density, "kg/m^3");
  // Thermal expansion: any sign (carbon fibres contract along their length as they warm), but a
  // strain of a percent over 100 K is no solid's.
  for (const auto& [key, alpha] :
       {std::pair{"alpha1", material.alpha1}, std::pair{"alpha2", material.alpha2}}) {
    require(std::isfinite(alpha) && std::abs(alpha) < 1e-4,
            "material " + in_quotes(material.name) + ": " + key +
                " must be a finite thermal expansion below 1e-4 1/K in magnitude, got " +
                format_number(alpha));
  }
  {
    LaminaStrength copy = material.strength;
    for (auto key : kNumberKeys) {
      const double* entry = strength_entry(copy, key);
      if (entry == nullptr) continue;
      const bool energy = key.front() == 'G';
      const bool modulus = key == "weibull_modulus";
      require(std::isfinite(*entry) && *entry >= 0,
              "material " + in_quotes(material.name) + ": " + std::string(key) +
                  " must be finite and positive (0 = not given), got " + format_number(*entry) +
                  (modulus ? "" : (energy ? " J/m^2" : " Pa")));
    }
  }

  validate_failure_model(material);

  // Scaled by E2 so the test sees numbers of order one; positive definiteness is scale-free.
  if (is_positive_definite(compliance_3d(material) * material.E2)) return;

  std::string constants =
      "(E1=" + format_number(material.E1) + ", E2=" + format_number(material.E2) +
      ", G12=" + format_number(material.G12) + ", nu12=" + format_number(material.nu12) +
      ", nu23=" + format_number(material.nu23) + ")";
  // With E1, E2, G12 > 0 the compliance is positive definite iff -1 < nu23 < 1 (transverse block
  // and G23 > 0) and delta = 1 - nu23 - 2 nu12^2 E2/E1 > 0 (the determinant; eq. (23)'s delta).
  std::string hint;
  if (!(material.nu23 > -1.0 && material.nu23 < 1.0)) {
    hint = "check nu23 (must satisfy -1 < nu23 < 1)";
  } else {
    const double bound = material.E1 / material.E2 * (1.0 - material.nu23) / 2.0;
    hint = "check nu12 (must satisfy nu12^2 < E1/E2 * (1-nu23)/2 = " + format_number(bound) +
           ", i.e. |nu12| < " + format_number(std::sqrt(bound)) + ")";
  }
  throw Error("material " + in_quotes(material.name) +
              ": the 3D compliance is not positive definite " + constants +
              ": no elastic solid has these constants; " + hint);
}

void require_strengths(const Material& material, const std::string& purpose, bool softening) {
  require(material.failure_criterion == PlyFailureModel::kBond,
          "material " + in_quotes(material.name) + " asks for failure_criterion = " +
              in_quotes(failure_model_name(material.failure_criterion)) + ", but " + purpose +
              " breaks bonds one by one with the parallel-bond law: failure decided at the "
              "material point is not in the engine yet except in plydem strength (set "
              "failure_criterion = \"bond\" or leave the key out here)");
  const LaminaStrength& s = material.strength;
  std::string missing;
  auto need = [&](const char* key, double value) {
    if (value > 0) return;
    if (!missing.empty()) missing += ", ";
    missing += key;
  };
  need("XT", s.XT);
  need("YT", s.YT);
  need("S12", s.S12);
  if (softening) {
    need("G_fibre", s.G_fibre);
    need("G_matrix", s.G_matrix);
  }
  require(missing.empty(), "material " + in_quotes(material.name) + " has no " + missing + ": " +
                               purpose +
                               " needs them (add them to the material file: XT, YT, S12 in Pa" +
                               (softening ? ", G_fibre and G_matrix in J/m^2" : "") + ")");
}

namespace {
struct FailureModelName {
  PlyFailureModel model;
  std::string_view name;
};
constexpr FailureModelName kFailureModelNames[] = {{PlyFailureModel::kBond, "bond"},
                                                   {PlyFailureModel::kHashin, "hashin"},
                                                   {PlyFailureModel::kPuck, "puck"},
                                                   {PlyFailureModel::kMaxStress, "max-stress"},
                                                   {PlyFailureModel::kTsaiWu, "tsai-wu"}};
}  // namespace

const char* failure_model_name(PlyFailureModel model) {
  for (const FailureModelName& n : kFailureModelNames) {
    if (n.model == model) return n.name.data();
  }
  return "unknown";
}

std::optional<PlyFailureModel> failure_model_from_name(std::string_view name) {
  for (const FailureModelName& n : kFailureModelNames) {
    if (n.name == name) return n.model;
  }
  return std::nullopt;
}

PlyFailureModel failure_model_named(std::string_view name) {
  const std::optional<PlyFailureModel> model = failure_model_from_name(name);
  require(model.has_value(), "unknown failure_criterion " + in_quotes(name) + " (expected one of " +
                                 failure_model_names() + ")");
  return *model;
}

std::string failure_model_names() {
  std::string list;
  for (const FailureModelName& n : kFailureModelNames) {
    if (!list.empty()) list += ", ";
    list += n.name;
  }
  return list;
}

std::vector<std::string> builtin_material_names() {
  std::vector<std::string> names;
  for (const BuiltinMaterial& builtin : kBuiltinMaterials) names.emplace_back(builtin.name);
  return names;
}

Material load_material(const std::string& name_or_file) {
  // A built-in name wins over a file of the same name in the working directory.
  for (const BuiltinMaterial& builtin : kBuiltinMaterials) {
    if (name_or_file == builtin.name) {
      Material m = builtin.make();
      validate(m);
      return m;
    }
  }

  std::error_code ec;
  const std::filesystem::path path(name_or_file);
  if (!std::filesystem::exists(path, ec)) {
    throw Error("unknown material " + in_quotes(name_or_file) + ": not a built-in (" +
                builtin_list() + ") and no such file");
  }
  require(std::filesystem::is_regular_file(path, ec),
          "material file " + in_quotes(name_or_file) + ": not a regular file");

  Material m = parse_material_file(name_or_file);
  try {
    validate(m);
  } catch (const Error& e) {
    throw Error("material file " + in_quotes(name_or_file) + ": " + e.what());
  }
  return m;
}

Material parse_material(const std::string& text, const std::string& origin) {
  Material m = parse_material_file(origin, &text);
  try {
    validate(m);
  } catch (const Error& e) {
    throw Error("material file " + in_quotes(origin) + ": " + e.what());
  }
  return m;
}

}  // namespace plydem
