// The pair-index mapping function of Avril et al. 2012, §3.2 (eq. 1–2): item k of the n(n-1)/2 pairs of
// n objects → the pair (a, b), a < b, with no table in memory. Written in plain C arithmetic so that the
// same text compiles as C++ (host, CPU path) and as OpenCL C (opencl/kernels include this file), and both
// sides compute bit-identical answers.
//
// Numbering (0-based, row-major over the strict upper triangle, paper Table 1 shifted to 0):
//   row a holds the pairs (a, a+1) … (a, n-1); its first index is S(a) = a(2n-a-1)/2;
//   k → a = the largest a with S(a) <= k, b = a + 1 + (k - S(a)).
// Solving S(a) = k for a gives a = ((2n-1) - sqrt((2n-1)^2 - 8k)) / 2 (the paper's eq. 1 rewritten for
// 0-based rows). A float or double square root of a value near 4n^2 can be off by more than one unit in
// the last place — the paper's §3.3 characterises those errors for the Newton/"magic constant" root and
// patches the two wrong cases it saw. We do not rely on any accuracy of the root: it only gives a first
// guess, and an exact integer correction step (compare S(a) and S(a+1) with k in 64-bit integers, move a
// by one until S(a) <= k < S(a+1)) makes the result exact for every k, whatever square root was used. The
// correction moves a by at most a few steps (tests count it: tests/broadphase/pair_mapping_test.cpp).
//
// Limits: S(a) is computed in 64 bits as a*(2n-a-1)/2, exact while n < 2^31 (a*(2n) < 2^63).
#ifndef GPUCOL_SHARED_MATH_PAIR_MAPPING_H
#define GPUCOL_SHARED_MATH_PAIR_MAPPING_H

#ifdef __OPENCL_VERSION__
typedef ulong gpucol_u64;
typedef uint gpucol_u32;
/* OpenCL C >= 1.2 allows static helper functions; static avoids C99 inline's external-definition rule. */
#define GPUCOL_MAPPING_INLINE static inline
#else
#include <math.h>
#include <stdint.h>
#include <string.h>
typedef uint64_t gpucol_u64;
typedef uint32_t gpucol_u32;
#define GPUCOL_MAPPING_INLINE static inline
#endif

/* First pair index of row a for n objects: S(a) = a(2n-a-1)/2. One of a and (2n-1-a) is even, so the
   product is even and the division exact. */
GPUCOL_MAPPING_INLINE gpucol_u64 gpucol_pair_row_start(gpucol_u64 n, gpucol_u64 a) {
  return (a * (2u * n - a - 1u)) / 2u;
}

/* Number of pairs of n objects, n(n-1)/2. */
GPUCOL_MAPPING_INLINE gpucol_u64 gpucol_pair_count(gpucol_u64 n) {
  return n < 2u ? 0u : (n * (n - 1u)) / 2u;
}

/* The exact correction of §3.3 done in integers: move the guessed row a until S(a) <= k < S(a+1).
   `guess` may be anything in [0, n-2] (it is clamped); each step moves by one row. */
GPUCOL_MAPPING_INLINE gpucol_u64 gpucol_pair_fix_row(gpucol_u64 n, gpucol_u64 k, gpucol_u64 guess) {
  gpucol_u64 a = guess > n - 2u ? n - 2u : guess;
  while (a > 0u && gpucol_pair_row_start(n, a) > k) --a;
  while (a + 2u < n && gpucol_pair_row_start(n, a + 1u) <= k) ++a;
  return a;
}

/* Row guess from a double-precision square root (eq. 1). The discriminant (2n-1)^2 - 8k is formed in
   64-bit integers (exact) before the conversion, so only the root itself rounds. */
#if !defined(__OPENCL_VERSION__) || defined(cl_khr_fp64)
GPUCOL_MAPPING_INLINE gpucol_u64 gpucol_pair_row_guess_double(gpucol_u64 n, gpucol_u64 k) {
  gpucol_u64 m = 2u * n - 1u;
  gpucol_u64 disc = m * m - 8u * k;
  double r = sqrt((double)disc);
  double a = ((double)m - r) * 0.5;
  return a <= 0.0 ? 0u : (gpucol_u64)a;
}
#endif

/* Row guess from a single-precision "magic constant" inverse square root with `steps` Newton steps (paper
   §3.3, Lomont's constant 0x5f375a86). Cheaper on some GPUs, less accurate: the integer fix-up above absorbs
   the error. The discriminant is rounded to float first, which is where most of the error comes from.
   `gpucol-bench accuracy` measures how often each number of steps guesses the wrong row. */
GPUCOL_MAPPING_INLINE gpucol_u64 gpucol_pair_row_guess_newton_steps(gpucol_u64 n, gpucol_u64 k, int steps) {
  gpucol_u64 m = 2u * n - 1u;
  float d = (float)(m * m - 8u * k);
  if (d <= 0.0f) return n - 2u;
#ifdef __OPENCL_VERSION__
  gpucol_u32 bits = as_uint(d);
  float y = as_float((gpucol_u32)0x5f375a86u - (bits >> 1));
#else
  gpucol_u32 bits;
  memcpy(&bits, &d, sizeof bits);
  bits = (gpucol_u32)0x5f375a86u - (bits >> 1);
  float y;
  memcpy(&y, &bits, sizeof y);
#endif
  float halfD = 0.5f * d;
  for (int i = 0; i < steps; ++i) y = y * (1.5f - halfD * y * y);
  float r = d * y; /* sqrt(d) = d / sqrt(d) */
  float a = ((float)m - r) * 0.5f;
  return a <= 0.0f ? 0u : (gpucol_u64)a;
}

/* The guess the pair finders use: three Newton steps (measured in `gpucol-bench accuracy`: fewer steps leave
   more guesses for the fix-up to move). */
GPUCOL_MAPPING_INLINE gpucol_u64 gpucol_pair_row_guess_newton(gpucol_u64 n, gpucol_u64 k) {
  return gpucol_pair_row_guess_newton_steps(n, k, 3);
}

/* Pair index k (0 <= k < n(n-1)/2, n >= 2) → (a, b), a < b < n, exact for every k (eq. 1 guess + fix). */
#if !defined(__OPENCL_VERSION__) || defined(cl_khr_fp64)
GPUCOL_MAPPING_INLINE void gpucol_pair_from_index(gpucol_u64 n, gpucol_u64 k, gpucol_u64* a, gpucol_u64* b) {
  gpucol_u64 row = gpucol_pair_fix_row(n, k, gpucol_pair_row_guess_double(n, k));
  *a = row;
  *b = row + 1u + (k - gpucol_pair_row_start(n, row));
}
#endif

/* The same with the Newton/magic-constant guess (paper §3.3); identical results, different speed. */
GPUCOL_MAPPING_INLINE void gpucol_pair_from_index_newton(gpucol_u64 n, gpucol_u64 k, gpucol_u64* a,
                                                         gpucol_u64* b) {
  gpucol_u64 row = gpucol_pair_fix_row(n, k, gpucol_pair_row_guess_newton(n, k));
  *a = row;
  *b = row + 1u + (k - gpucol_pair_row_start(n, row));
}

/* Pair index of (a, b), a < b < n: the inverse, S(a) + b - a - 1 (eq. 2 solved for k). */
GPUCOL_MAPPING_INLINE gpucol_u64 gpucol_pair_index(gpucol_u64 n, gpucol_u64 a, gpucol_u64 b) {
  return gpucol_pair_row_start(n, a) + (b - a - 1u);
}

#endif /* GPUCOL_SHARED_MATH_PAIR_MAPPING_H */
