#include "narrowphase/contact_rows.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "bvh/avx2_clones.h"
#include "narrowphase/triangle_plane.h"

// The helpers below take and return 32-byte vectors, and all are always inlined (GPUCOL_FORCE_INLINE, also at
// -O0; no lambdas, which would not be): a helper called rather than inlined would be compiled once, for the
// baseline target, and the AVX2 clone would pass it its vectors in other registers (a debug build with a
// lambda crashed so). So no call ever passes one, and the compiler's note about that ABI does not apply.
#if defined(__GNUC__)
#pragma GCC diagnostic ignored "-Wpsabi"
#endif

#include "shared_math/triangle_lanes.h"

namespace gpucol::detail {
namespace {

// generateContactAndTest's steps on four pairs at once, one per lane of a vector of doubles: the shared
// gpucol_triangle_contact4 (shared_math/triangle_lanes.h; GCC/Clang vector extensions, one AVX instruction
// per step in the AVX2 clone, two SSE ones in the baseline clone), between loads from the rows and stores
// back.

constexpr std::size_t kLanes = 4;
using Floats = float __attribute__((vector_size(16)));
using Words = std::uint32_t __attribute__((vector_size(16)));

/// One row's values of four neighbouring pairs, read as doubles; and four results written back as floats.
GPUCOL_FORCE_INLINE gpucol_d4 loadLanes(const float* p) {
  Floats v;
  std::memcpy(&v, p, sizeof v);
  return __builtin_convertvector(v, gpucol_d4);
}
GPUCOL_FORCE_INLINE void storeLanes(float* p, gpucol_d4 v) {
  const Floats f = __builtin_convertvector(v, Floats);
  std::memcpy(p, &f, sizeof f);
}

/// A pair's vertex v (0-2 A's, 3-5 B's) from the rows, four pairs from `triangles` on.
GPUCOL_FORCE_INLINE GpucolVec4 loadVertex(const float* triangles, std::size_t stride, int v) {
  const float* p = triangles + 3 * v * stride;
  return gpucol_vec4(loadLanes(p), loadLanes(p + stride), loadLanes(p + 2 * stride));
}

/// `word` in the lanes where m holds, 0 elsewhere.
GPUCOL_FORCE_INLINE gpucol_m4 wordWhere(gpucol_m4 m, std::uint32_t word) {
  return m & gpucol_m4{word, word, word, word};
}

/// The four pairs whose values start at `triangles` (generateContactRows' layout); results at `contacts` and
/// `outcome`.
GPUCOL_FORCE_INLINE void fourPairs(const float* triangles, std::size_t stride, float* contacts,
                                   std::uint32_t* outcome) {
  GpucolVec4 t[6];
  for (int v = 0; v < 6; ++v) t[v] = loadVertex(triangles, stride, v);
  const GpucolContact4 r = gpucol_triangle_contact4(t);
  const gpucol_d4 rows[kContactRowValues] = {r.point.x,  r.point.y, r.point.z,   r.normal.x,  r.normal.y,
                                             r.normal.z, r.depth,   r.deepest.x, r.deepest.y, r.deepest.z};
  for (std::size_t k = 0; k < kContactRowValues; ++k) storeLanes(contacts + k * stride, rows[k]);
  // The outcome word, from the masks (all bits set where true).
  const gpucol_m4 found = wordWhere(r.onePair, kRowOnePair) |
                          wordWhere(r.intersects & ~r.contact, kRowIntersectsNoContact) |
                          wordWhere(r.contact, kRowContact) | wordWhere(r.onFaceOfB, kRowOnFaceOfB) |
                          wordWhere(r.sameFacing, kRowSameFacing);
  const Words words = __builtin_convertvector(found, Words);
  std::memcpy(outcome, &words, sizeof words);
}

}  // namespace

GPUCOL_AVX2_CLONES void generateContactRows(const float* triangles, std::size_t stride, std::size_t count,
                                            float* contacts, std::uint32_t* outcome) {
  std::size_t t = 0;
  for (; t + kLanes <= count; t += kLanes) fourPairs(triangles + t, stride, contacts + t, outcome + t);
  if (t == count) return;
  // The last one to three pairs: copied into columns of their own, the free lanes filled with the last pair
  // (a real pair, so no lane computes on garbage), and only their own results copied back.
  float tail[18 * kLanes];
  float tailContacts[kContactRowValues * kLanes];
  std::uint32_t tailOutcome[kLanes];
  for (std::size_t k = 0; k < 18; ++k) {
    for (std::size_t lane = 0; lane < kLanes; ++lane) {
      tail[k * kLanes + lane] = triangles[k * stride + std::min(t + lane, count - 1)];
    }
  }
  fourPairs(tail, kLanes, tailContacts, tailOutcome);
  for (std::size_t lane = 0; t + lane < count; ++lane) {
    for (std::size_t k = 0; k < kContactRowValues; ++k) {
      contacts[k * stride + t + lane] = tailContacts[k * kLanes + lane];
    }
    outcome[t + lane] = tailOutcome[lane];
  }
}

}  // namespace gpucol::detail
