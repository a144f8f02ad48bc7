#pragma once

#include <cstddef>  // defines __GLIBC__ on glibc

/// GPUCOL_AVX2_CLONES before a hot function compiles it twice, for AVX2 and for any x86-64, and the loader
/// picks the one the CPU runs (GCC/Clang `target_clones`, an ifunc of glibc), so one binary serves every
/// x86-64 CPU and uses the wider vectors where they exist. Inline code the function calls is compiled into
/// each clone; a call it does not inline runs the baseline code. AVX2 alone brings no fused multiply-add
/// (that is FMA's flag, not given), so both clones round alike and give the same bits. Elsewhere the macro is
/// empty.
///
/// Where it is used: the traversal's loops, the near phase's per-chunk work and its double test over columns
/// of pairs (narrowphase/contact_rows.cpp), which take most of a mesh pair query's time.
#if defined(__x86_64__) && defined(__GLIBC__) && defined(__has_attribute)
#if __has_attribute(target_clones)
#define GPUCOL_AVX2_CLONES __attribute__((target_clones("avx2", "default")))
#endif
#endif
#ifndef GPUCOL_AVX2_CLONES
#define GPUCOL_AVX2_CLONES
#endif
