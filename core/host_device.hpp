#pragma once
/// \file
/// What lets one function be compiled for the host and for a CUDA device (the bond law, the failure
/// law, the half-bond math: core/bond_failure_law.hpp, contacts/half_bond.hpp), as HOOMD-blue marks
/// its bond evaluators HOSTDEVICE: under nvcc PLYDEM_HOST_DEVICE is __host__ __device__, for every
/// other compiler nothing, so the host build is the plain C++ it was. Headers that use it include
/// no Eigen and no GCC vector extension, so that nvcc can compile them (solvers/cuda_backend.cu).

#if defined(__CUDACC__)
#define PLYDEM_HOST_DEVICE __host__ __device__
/// Inlined into every caller (the kernels depend on it for speed and for one instruction set).
#define PLYDEM_FORCE_INLINE __forceinline__
#else
#define PLYDEM_HOST_DEVICE
#define PLYDEM_FORCE_INLINE [[gnu::always_inline]] inline
#endif
