/* What every header of plugin/src/shared_math needs: the mathematics that the CPU code and the OpenCL kernels
   both run lives there once, in plain C that compiles as C++ (the plugin includes these headers) and as
   OpenCL C (cmake/GpucolEmbedKernels.cmake pastes them into the programs). A fix made there is made for both.
   Rules for these headers: static inline functions, no templates, no Eigen, fixed-size arrays; the same
   operations in the same order on both sides (the kernels turn contraction off, the host has no FMA in its
   targets), so CPU and device give the same bits. */
#ifndef GPUCOL_SHARED_MATH_SHARED_C_H
#define GPUCOL_SHARED_MATH_SHARED_C_H

#ifdef __OPENCL_VERSION__
/* Both sides round every operation: no fused multiply-adds (the host's targets have none). */
#pragma OPENCL FP_CONTRACT OFF
#define GPUCOL_SHARED_INLINE static inline
#define GPUCOL_SHARED_FORCE_INLINE static inline __attribute__((always_inline))
#else
#include <math.h>
#define GPUCOL_SHARED_INLINE static inline
#if defined(__GNUC__)
#define GPUCOL_SHARED_FORCE_INLINE static inline __attribute__((always_inline))
#else
#define GPUCOL_SHARED_FORCE_INLINE static inline
#endif
#endif

/* std::min and std::max of C++: the first argument where the comparison fails (equal values, NaN). */
GPUCOL_SHARED_INLINE double gpucol_min_d(double a, double b) {
  return b < a ? b : a;
}
GPUCOL_SHARED_INLINE double gpucol_max_d(double a, double b) {
  return a < b ? b : a;
}

#endif /* GPUCOL_SHARED_MATH_SHARED_C_H */
