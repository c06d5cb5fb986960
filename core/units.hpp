#pragma once
/// \file
/// Unit conversions at the edges. plydem computes in SI (m, Pa, N/m, s); it reads and reports
/// millimetres, GPa and MPa. A value in SI times kMmPerMetre is in mm; a value in mm times
/// kMetresPerMm is in metres, and likewise for the others. Each constant is the literal it
/// names, so `x * kGPaPerPa` rounds exactly as `x * 1e-9` does.

#include <numbers>

namespace plydem {

/// One degree in radians: an angle in degrees times kDegree is in radians.
inline constexpr double kDegree = std::numbers::pi / 180.0;

inline constexpr double kMmPerMetre = 1e3;
inline constexpr double kMetresPerMm = 1e-3;

inline constexpr double kGPaPerPa = 1e-9;
inline constexpr double kPaPerGPa = 1e9;
inline constexpr double kMPaPerPa = 1e-6;
inline constexpr double kPaPerMPa = 1e6;

/// Decimal gigabytes, as the memory checks report them.
inline constexpr double kBytesPerGB = 1e9;

inline constexpr double kSecondsPerNanosecond = 1e-9;
inline constexpr double kNanosecondsPerSecond = 1e9;

}  // namespace plydem
