#include "core/failure_criteria.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/error.hpp"
#include "core/preloaded_failure.hpp"

namespace plydem {
namespace {

constexpr double kNever = std::numeric_limits<double>::infinity();

// The strength `value` named `name`, which the criterion needs for this stress: an Error if the
// material does not give it (0).
double needed(double value, const char* name, FailureCriterion criterion) {
  if (!(value > 0)) {
    throw Error(
        fmt::format("the {} criterion needs the lamina strength {} for this stress, which "
                    "the material does not give",
                    criterion_name(criterion), name));
  }
  return value;
}

// The positive root of a lambda^2 + b lambda = 1 (a >= 0): the load factor of a criterion whose
// left-hand side is a quadratic (a) plus a linear (b) form of the stress. +inf if the stress never
// reaches it (a = 0 and b <= 0).
double positive_root(double a, double b) {
  if (a > 0) {
    // Written without cancellation for b > 0: (-b + sqrt(b^2 + 4a)) / (2a) = 2 / (b + sqrt(..)).
    const double root = std::sqrt(b * b + 4 * a);
    return b >= 0 ? 2.0 / (b + root) : (root - b) / (2 * a);
  }
  return b > 0 ? 1.0 / b : kNever;
}

PlyFailureMode fibre_mode(const PlyStress& s) {
  return s.sigma1 >= 0 ? PlyFailureMode::kFibreTension : PlyFailureMode::kFibreCompression;
}
PlyFailureMode matrix_mode(const PlyStress& s) {
  return s.sigma2 >= 0 ? PlyFailureMode::kMatrixTension : PlyFailureMode::kMatrixCompression;
}

// The failure of the smaller load factor (the first of the two on a tie).
PlyFailure first_of(PlyFailure a, PlyFailure b) {
  return b.load_factor < a.load_factor ? b : a;
}

// An interactive surface's mode: the larger of its fibre and matrix parts at the load factor.
PlyFailure interactive(const PlyStress& s, double factor, double fibre_part, double matrix_part) {
  return {factor, fibre_part >= matrix_part ? fibre_mode(s) : matrix_mode(s), 0.0};
}

PlyFailure max_stress(const PlyStress& s, const LaminaStrength& x) {
  const FailureCriterion c = FailureCriterion::kMaxStress;
  PlyFailure f{kNever, matrix_mode(s), 0.0};
  if (s.sigma1 > 0) f = first_of(f, {needed(x.XT, "XT", c) / s.sigma1, fibre_mode(s), 0.0});
  if (s.sigma1 < 0) f = first_of(f, {needed(x.XC, "XC", c) / -s.sigma1, fibre_mode(s), 0.0});
  if (s.sigma2 > 0) f = first_of(f, {needed(x.YT, "YT", c) / s.sigma2, matrix_mode(s), 0.0});
  if (s.sigma2 < 0) f = first_of(f, {needed(x.YC, "YC", c) / -s.sigma2, matrix_mode(s), 0.0});
  if (s.tau12 != 0) {
    f = first_of(f, {needed(x.S12, "S12", c) / std::abs(s.tau12), matrix_mode(s), 0.0});
  }
  return f;
}

PlyFailure tsai_hill(const PlyStress& s, const LaminaStrength& x) {
  const FailureCriterion c = FailureCriterion::kTsaiHill;
  double a = 0, fibre = 0;
  if (s.sigma1 != 0) {
    const double X = s.sigma1 > 0 ? needed(x.XT, "XT", c) : needed(x.XC, "XC", c);
    a += (s.sigma1 * s.sigma1 - s.sigma1 * s.sigma2) / (X * X);
    fibre = s.sigma1 * s.sigma1 / (X * X);
  }
  const double before_matrix = a;
  if (s.sigma2 != 0) {
    const double Y = s.sigma2 > 0 ? needed(x.YT, "YT", c) : needed(x.YC, "YC", c);
    a += s.sigma2 * s.sigma2 / (Y * Y);
  }
  if (s.tau12 != 0) {
    const double S = needed(x.S12, "S12", c);
    a += s.tau12 * s.tau12 / (S * S);
  }
  // Both parts are quadratic: their order is the same at every load factor.
  return interactive(s, positive_root(a, 0.0), fibre, a - before_matrix);
}

PlyFailure tsai_wu(const PlyStress& s, const LaminaStrength& x) {
  const FailureCriterion c = FailureCriterion::kTsaiWu;
  double a = 0, b = 0;
  double f11 = 0, f22 = 0;
  double fibre_a = 0, fibre_b = 0;  // the sigma1 terms (for the mode)
  if (s.sigma1 != 0) {
    const double XT = needed(x.XT, "XT", c), XC = needed(x.XC, "XC", c);
    f11 = 1.0 / (XT * XC);
    fibre_a = f11 * s.sigma1 * s.sigma1;
    fibre_b = (1.0 / XT - 1.0 / XC) * s.sigma1;
    a += fibre_a;
    b += fibre_b;
  }
  if (s.sigma2 != 0) {
    const double YT = needed(x.YT, "YT", c), YC = needed(x.YC, "YC", c);
    f22 = 1.0 / (YT * YC);
    a += f22 * s.sigma2 * s.sigma2;
    b += (1.0 / YT - 1.0 / YC) * s.sigma2;
  }
  if (s.tau12 != 0) {
    const double S = needed(x.S12, "S12", c);
    a += s.tau12 * s.tau12 / (S * S);
  }
  const double matrix_a = a - fibre_a, matrix_b = b - fibre_b;  // the sigma2 and tau12 terms
  // F12 = F12* sqrt(F11 F22) with F12* = -1/2 (its term vanishes unless both normal stresses act).
  a += 2.0 * (-0.5 * std::sqrt(f11 * f22)) * s.sigma1 * s.sigma2;
  const double factor = positive_root(a, b);
  if (!std::isfinite(factor)) return {factor, matrix_mode(s), 0.0};
  return interactive(s, factor, (fibre_a * factor + fibre_b) * factor,
                     (matrix_a * factor + matrix_b) * factor);
}

PlyFailure hashin(const PlyStress& s, const LaminaStrength& x) {
  const FailureCriterion c = FailureCriterion::kHashin;
  const double shear = s.tau12 != 0 ? s.tau12 / needed(x.S12, "S12", c) : 0.0;
  PlyFailure fibre{0.0, fibre_mode(s), 0.0};
  // Fibre mode: tension (sigma1 >= 0) (s1/XT)^2 + (t/S12)^2 = 1; compression (s1/XC)^2 = 1.
  if (s.sigma1 >= 0) {
    const double r = s.sigma1 > 0 ? s.sigma1 / needed(x.XT, "XT", c) : 0.0;
    fibre.load_factor = positive_root(r * r + shear * shear, 0.0);
  } else {
    fibre.load_factor = needed(x.XC, "XC", c) / -s.sigma1;
  }
  // Matrix mode: tension (sigma2 >= 0) (s2/YT)^2 + (t/S12)^2 = 1; compression
  // (s2/(2 S23))^2 + [(YC/(2 S23))^2 - 1] s2/YC + (t/S12)^2 = 1 with S23 = YC/2.
  PlyFailure matrix{0.0, matrix_mode(s), 0.0};
  if (s.sigma2 >= 0) {
    const double r = s.sigma2 > 0 ? s.sigma2 / needed(x.YT, "YT", c) : 0.0;
    matrix.load_factor = positive_root(r * r + shear * shear, 0.0);
  } else {
    const double YC = needed(x.YC, "YC", c);
    const double S23 = 0.5 * YC;
    const double r = s.sigma2 / (2.0 * S23);
    const double linear = ((YC / (2.0 * S23)) * (YC / (2.0 * S23)) - 1.0) * s.sigma2 / YC;
    matrix.load_factor = positive_root(r * r + shear * shear, linear);
  }
  // A tie (pure in-plane shear, which both of Hashin's tension modes hold) is a matrix crack.
  return first_of(matrix, fibre);
}

// Puck's plane-stress inter-fibre fracture (Puck & Schuermann 2002, eqs. for modes A, B, C), with
// R23A, the fracture resistance of the action plane against its own transverse shear, and p23-
// from p12- by the consistency conditions: R23A = S12 / (2 p12-) (sqrt(1 + 2 p12- YC / S12) - 1),
// p23- = p12- R23A / S12, tau12c = S12 sqrt(1 + 2 p23-) (the shear at the mode B/C corner).
struct PuckEnvelope {
  double YT = 0, YC = 0, S12 = 0, p_tension = 0, p_compression = 0;
  double R23A = 0, p23 = 0, tau12c = 0;
};

PuckEnvelope puck_envelope(const PlyStress& s, const LaminaStrength& x) {
  const FailureCriterion c = FailureCriterion::kPuck;
  PuckEnvelope e;
  e.S12 = needed(x.S12, "S12", c);
  e.p_tension = x.puck_p12_tension;
  e.p_compression = x.puck_p12_compression;
  if (s.sigma2 >= 0) {
    if (s.sigma2 > 0) e.YT = needed(x.YT, "YT", c);
    return e;
  }
  e.YC = needed(x.YC, "YC", c);
  const double p = e.p_compression;
  e.R23A = p > 0 ? e.S12 / (2 * p) * (std::sqrt(1 + 2 * p * e.YC / e.S12) - 1) : 0.5 * e.YC;
  e.p23 = p * e.R23A / e.S12;
  e.tau12c = e.S12 * std::sqrt(1 + 2 * e.p23);
  return e;
}

PuckMode puck_mode(const PlyStress& s, const PuckEnvelope& e) {
  if (s.sigma2 >= 0) return PuckMode::kA;
  return std::abs(s.sigma2) <= e.R23A / e.tau12c * std::abs(s.tau12) ? PuckMode::kB : PuckMode::kC;
}

// Puck's stress exposure of inter-fibre fracture: homogeneous of degree one in the stress, so the
// load factor is its inverse.
double puck_matrix_exposure(const PlyStress& s, const PuckEnvelope& e) {
  const double t = s.tau12 / e.S12;
  switch (puck_mode(s, e)) {
    case PuckMode::kA: {
      const double r = s.sigma2 > 0 ? (1 - e.p_tension * e.YT / e.S12) * s.sigma2 / e.YT : 0.0;
      return std::sqrt(t * t + r * r) + e.p_tension * s.sigma2 / e.S12;
    }
    case PuckMode::kB:
      return (std::hypot(s.tau12, e.p_compression * s.sigma2) + e.p_compression * s.sigma2) / e.S12;
    case PuckMode::kC: {
      const double a = s.tau12 / (2 * (1 + e.p23) * e.S12);
      const double b = s.sigma2 / e.YC;
      return (a * a + b * b) * e.YC / -s.sigma2;
    }
  }
  return 0;
}

PlyFailure puck(const PlyStress& s, const LaminaStrength& x) {
  const FailureCriterion c = FailureCriterion::kPuck;
  PlyFailure f{kNever, fibre_mode(s), 0.0};
  if (s.sigma1 > 0) f.load_factor = needed(x.XT, "XT", c) / s.sigma1;
  if (s.sigma1 < 0) f.load_factor = needed(x.XC, "XC", c) / -s.sigma1;
  if (s.sigma2 != 0 || s.tau12 != 0) {
    const double exposure = puck_matrix_exposure(s, puck_envelope(s, x));
    if (exposure > 0) f = first_of(f, {1.0 / exposure, matrix_mode(s), 0.0});
  }
  return f;
}

}  // namespace

PlyStress to_ply_axes(double sigma_x, double sigma_y, double tau_xy, double ply_angle) {
  const double c = std::cos(ply_angle), s = std::sin(ply_angle);
  PlyStress p;
  p.sigma1 = c * c * sigma_x + s * s * sigma_y + 2 * s * c * tau_xy;
  p.sigma2 = s * s * sigma_x + c * c * sigma_y - 2 * s * c * tau_xy;
  p.tau12 = -s * c * sigma_x + s * c * sigma_y + (c * c - s * s) * tau_xy;
  return p;
}

const char* criterion_name(FailureCriterion criterion) {
  switch (criterion) {
    case FailureCriterion::kMaxStress:
      return "max_stress";
    case FailureCriterion::kTsaiHill:
      return "tsai_hill";
    case FailureCriterion::kTsaiWu:
      return "tsai_wu";
    case FailureCriterion::kHashin:
      return "hashin";
    case FailureCriterion::kPuck:
      return "puck";
  }
  return "unknown";
}

std::vector<FailureCriterion> all_criteria() {
  return {FailureCriterion::kMaxStress, FailureCriterion::kTsaiHill, FailureCriterion::kTsaiWu,
          FailureCriterion::kHashin, FailureCriterion::kPuck};
}

const char* failure_mode_name(PlyFailureMode mode) {
  switch (mode) {
    case PlyFailureMode::kFibreTension:
      return "fibre tension";
    case PlyFailureMode::kFibreCompression:
      return "fibre compression";
    case PlyFailureMode::kMatrixTension:
      return "matrix tension";
    case PlyFailureMode::kMatrixCompression:
      return "matrix compression";
  }
  return "unknown";
}

namespace {

// The criterion's load factor and mode (no fracture angle), for a finite stress.
PlyFailure criterion_failure(FailureCriterion criterion, const PlyStress& stress,
                             const LaminaStrength& strength) {
  require(
      std::isfinite(stress.sigma1) && std::isfinite(stress.sigma2) && std::isfinite(stress.tau12),
      fmt::format("the {} criterion got a non-finite stress ({}, {}, {}) Pa",
                  criterion_name(criterion), stress.sigma1, stress.sigma2, stress.tau12));
  switch (criterion) {
    case FailureCriterion::kMaxStress:
      return max_stress(stress, strength);
    case FailureCriterion::kTsaiHill:
      return tsai_hill(stress, strength);
    case FailureCriterion::kTsaiWu:
      return tsai_wu(stress, strength);
    case FailureCriterion::kHashin:
      return hashin(stress, strength);
    case FailureCriterion::kPuck:
      return puck(stress, strength);
  }
  throw Error("unknown failure criterion");
}

}  // namespace

// The load factor alone needs no fracture angle, whose Puck envelope asks for S12 and YC that a
// criterion may not need for this stress (max-stress in transverse compression: YC only).
double failure_load_factor(FailureCriterion criterion, const PlyStress& stress,
                           const LaminaStrength& strength) {
  return criterion_failure(criterion, stress, strength).load_factor;
}

PlyFailure ply_failure(FailureCriterion criterion, const PlyStress& stress,
                       const LaminaStrength& strength) {
  PlyFailure f = criterion_failure(criterion, stress, strength);
  if (f.mode == PlyFailureMode::kMatrixCompression) {
    f.fracture_angle = puck_fracture_plane(stress, strength).angle;
  }
  return f;
}

PlyFailure preloaded_ply_failure(FailureCriterion criterion, const PlyStress& preload,
                                 const PlyStress& unit, const LaminaStrength& strength) {
  auto at = [&](double lambda) {
    return PlyStress{preload.sigma1 + lambda * unit.sigma1, preload.sigma2 + lambda * unit.sigma2,
                     preload.tau12 + lambda * unit.tau12};
  };
  auto utilisation = [&](double lambda) {
    return 1.0 / failure_load_factor(criterion, at(lambda), strength);  // 0 where never
  };
  const double lambda =
      first_failure_factor(utilisation, failure_load_factor(criterion, unit, strength));
  if (!std::isfinite(lambda)) return {lambda, ply_failure(criterion, unit, strength).mode, 0.0};
  PlyFailure f = ply_failure(criterion, at(lambda), strength);
  f.load_factor = lambda;
  return f;
}

PuckFracturePlane puck_fracture_plane(const PlyStress& stress, const LaminaStrength& strength) {
  require(std::isfinite(stress.sigma2) && std::isfinite(stress.tau12),
          "puck_fracture_plane: the ply stress is not finite");
  const PuckEnvelope e = puck_envelope(stress, strength);
  PuckFracturePlane plane;
  plane.mode = puck_mode(stress, e);
  if (plane.mode == PuckMode::kC) {
    const double ratio = e.R23A / e.S12 * stress.tau12 / stress.sigma2;
    const double cos2 = (ratio * ratio + 1) / (2 * (1 + e.p23));
    plane.angle = std::acos(std::sqrt(std::min(1.0, cos2)));
  }
  return plane;
}

double off_axis_strength(FailureCriterion criterion, const LaminaStrength& strength,
                         double ply_angle) {
  require(std::isfinite(ply_angle), "off-axis strength: the ply angle is not finite");
  return failure_load_factor(criterion, to_ply_axes(1.0, 0.0, 0.0, ply_angle), strength);
}

double off_axis_compressive_strength(FailureCriterion criterion, const LaminaStrength& strength,
                                     double ply_angle) {
  require(std::isfinite(ply_angle), "off-axis strength: the ply angle is not finite");
  return failure_load_factor(criterion, to_ply_axes(-1.0, 0.0, 0.0, ply_angle), strength);
}

}  // namespace plydem
