#pragma once
/// \file
/// The arithmetic the explicit kernels' shared code is written in, once, over a lane type T: one
/// particle (T = double: the CUDA kernel, its host emulation, the reference backend) or eight
/// particles in the lanes of a GCC vector (T = lanes::Doubles: the host's SIMD kernel, whose
/// LaneOps specialization is in contacts/bond_kernel.hpp). Code written over LaneOps<T> computes
/// the same numbers for every T, lane by lane, because every operation here is exactly rounded:
///
///  - every multiply-add is an explicit fused multiply-add (fmadd), rounded once, whatever the
///    compiler would contract by itself: GCC contracts a * b + c wherever the instruction set has
///    FMA (the host kernel's AVX2 and AVX-512 clones) and nowhere else (its baseline x86-64 code),
///    so a kernel written with plain a * b + c gave different last bits on different processors and
///    backends. Explicit fmadd is libm's fma (itself the FMA instruction where the processor has
///    one) for one particle on the host, fma() on the device, and one vfmadd per vector in the
///    host kernel's clones (contacts/bond_kernel.hpp: the one place that relies on GCC's
///    contraction, made unambiguous; the baseline x86-64 clone, for processors without FMA,
///    rounds twice there);
///  - masks select whole values (select, keep): no arithmetic on the masks' side.
///
/// Shared code must write a product that feeds a sum as fmadd, or keep the product out of any sum
/// (masked first, as keep() does), so that no compiler contraction can change it.
///
/// No Eigen and no vector extension here: nvcc compiles this header.

#include <cmath>

#include "core/host_device.hpp"

namespace plydem {

/// a * b + c, rounded once.
PLYDEM_HOST_DEVICE PLYDEM_FORCE_INLINE double fmadd(double a, double b, double c) {
#if defined(__CUDA_ARCH__)
  return ::fma(a, b, c);
#else
  return __builtin_fma(a, b, c);
#endif
}

/// The operations of the kernels' shared code on lane type T (see the file comment).
template <class T>
struct LaneOps;

/// One particle.
template <>
struct LaneOps<double> {
  using Mask = bool;
  PLYDEM_HOST_DEVICE PLYDEM_FORCE_INLINE static double fmadd(double a, double b, double c) {
    return plydem::fmadd(a, b, c);
  }
  /// `a` where `m`, else `b`.
  PLYDEM_HOST_DEVICE PLYDEM_FORCE_INLINE static double select(bool m, double a, double b) {
    return m ? a : b;
  }
  /// `x` where `m`, else +0.
  PLYDEM_HOST_DEVICE PLYDEM_FORCE_INLINE static double keep(double x, bool m) {
    return m ? x : 0.0;
  }
  /// `x` where not `m`, else +0.
  PLYDEM_HOST_DEVICE PLYDEM_FORCE_INLINE static double keep_unless(double x, bool m) {
    return m ? 0.0 : x;
  }
  PLYDEM_HOST_DEVICE PLYDEM_FORCE_INLINE static double abs(double x) { return std::fabs(x); }
  PLYDEM_HOST_DEVICE PLYDEM_FORCE_INLINE static double sqrt(double x) { return std::sqrt(x); }
  /// The magnitude `magnitude` (>= 0) with the sign of `v`, and +0 where v is zero (PFC's local
  /// damping force alpha |F| sign(v)).
  PLYDEM_HOST_DEVICE PLYDEM_FORCE_INLINE static double signed_like(double magnitude, double v) {
    return v == 0.0 ? 0.0 : std::copysign(magnitude, v);
  }
  PLYDEM_HOST_DEVICE PLYDEM_FORCE_INLINE static bool any(bool m) { return m; }
};

}  // namespace plydem
