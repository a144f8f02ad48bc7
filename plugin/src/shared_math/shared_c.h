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

/* A vector of three lane values (one scalar per lane: several candidates at once) named Name, with its
   constructor fn(x, y, z) and fn_sub, fn_cross and fn_dot, in the operation order both sides keep; defined
   once for each lane type (triangle_lanes.h: double lanes, triangle_pretest.h: float lanes). */
#define GPUCOL_LANE_VECTOR(Name, fn, T)                                                      \
  typedef struct Name {                                                                      \
    T x, y, z;                                                                               \
  } Name;                                                                                    \
  GPUCOL_SHARED_FORCE_INLINE Name fn(T x, T y, T z) {                                        \
    Name r;                                                                                  \
    r.x = x;                                                                                 \
    r.y = y;                                                                                 \
    r.z = z;                                                                                 \
    return r;                                                                                \
  }                                                                                          \
  GPUCOL_SHARED_FORCE_INLINE Name fn##_sub(Name a, Name b) {                                 \
    return fn(a.x - b.x, a.y - b.y, a.z - b.z);                                              \
  }                                                                                          \
  GPUCOL_SHARED_FORCE_INLINE Name fn##_cross(Name a, Name b) {                               \
    return fn(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);          \
  }                                                                                          \
  GPUCOL_SHARED_FORCE_INLINE T fn##_dot(Name a, Name b) {                                    \
    return (a.x * b.x + a.y * b.y) + a.z * b.z;                                              \
  }

/* std::min and std::max of C++: the first argument where the comparison fails (equal values, NaN). */
GPUCOL_SHARED_INLINE double gpucol_min_d(double a, double b) {
  return b < a ? b : a;
}
GPUCOL_SHARED_INLINE double gpucol_max_d(double a, double b) {
  return a < b ? b : a;
}

#endif /* GPUCOL_SHARED_MATH_SHARED_C_H */
