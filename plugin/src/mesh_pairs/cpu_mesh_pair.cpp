// One mesh pair on the CPU: middle phase (tree vs tree), near phase (Möller's test and contact generation,
// thesis §5.3.4) and contact reduction (6-D binning, §5.3.5); the hits of either path into the pair's result.
#include "mesh_pairs/cpu_mesh_pair.h"

#include <tbb/parallel_for.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>

#include "bvh/aabb_tree.h"
#include "bvh/avx2_clones.h"
#include "bvh/prefetch.h"
#include "bvh/tree_traversal.h"
#include "gpucol/mesh_shape.h"
#include "mesh_pairs/candidate_cache.h"
#include "mesh_pairs/stage_clock.h"
#include "narrowphase/contact_reduction.h"
#include "narrowphase/contact_rows.h"
#include "narrowphase/triangle_contact.h"
#include "narrowphase/triangle_intersection.h"
#include "narrowphase/triangle_plane.h"
#include "narrowphase/triangle_proximity.h"
#include "shared_math/box_carry.h"

namespace gpucol {
namespace {

bool isFinite(const btTransform& t) {
  for (int r = 0; r < 3; ++r) {
    if (!std::isfinite(t.getOrigin()[r])) return false;
    for (int c = 0; c < 3; ++c) {
      if (!std::isfinite(t.getBasis()[r][c])) return false;
    }
  }
  return true;
}

// One candidate pair whose triangles intersect, by its index among the candidates, with its contact if one is
// kept.
struct NearHit {
  std::size_t candidate;
  bool hasContact;
  TriangleContact contact;
};

// The contact of a hit that has none: zeroed, so that copying the hit reads no uninitialised floats (Eigen's
// vectors start uninitialised, TriangleContact{} included).
TriangleContact noContact() {
  TriangleContact contact;
  contact.point.setZero();
  contact.normalOnB.setZero();
  contact.depth = 0;
  return contact;
}

// A contact of a candidate whose triangles do not cross but come within the pair's reach (the shapes' margins
// and the speculative reach).
struct NearbyHit {
  std::size_t candidate;
  TriangleContact contact;
};

// Candidates per task of the near phase: enough to amortise a task, small enough to balance two to eight
// cores.
constexpr std::size_t kNearChunk = 512;

// How far ahead the near phase prefetches the triangles of both meshes, in candidates. Once the double test
// ran four pairs per vector, the near phase waited on B's soup more than it computed; 32 ahead was as fast as
// any on the largest mesh (measurement history, "Figures moved from code comments").
constexpr std::size_t kSoupAhead = 32;

// Distance in floats between two coordinates' rows of ChunkTriangles: not a power of two, so that the 18 rows
// written together do not all fall into the same few sets of the L1 cache (a 2 KiB stride put 9 rows per
// set).
constexpr std::size_t kNearRow = kNearChunk + 16;

// The two triangles of column j of a chunk's rows (the layout of ChunkTriangles, below), read from a plain
// pointer so that the row loops that use it stay vector code. Forced inline: GCC had made the constructor a
// call, which left the plane and interval pre-test loops scalar.
struct RowTriangles {
  __attribute__((always_inline)) RowTriangles(const float* rows, std::size_t j)
      : a0(rows[j], rows[kNearRow + j], rows[2 * kNearRow + j]),
        a1(rows[3 * kNearRow + j], rows[4 * kNearRow + j], rows[5 * kNearRow + j]),
        a2(rows[6 * kNearRow + j], rows[7 * kNearRow + j], rows[8 * kNearRow + j]),
        b0(rows[9 * kNearRow + j], rows[10 * kNearRow + j], rows[11 * kNearRow + j]),
        b1(rows[12 * kNearRow + j], rows[13 * kNearRow + j], rows[14 * kNearRow + j]),
        b2(rows[15 * kNearRow + j], rows[16 * kNearRow + j], rows[17 * kNearRow + j]) {}
  Eigen::Vector3f a0, a1, a2, b0, b1, b2;
};

// One chunk's triangles, coordinate by coordinate (structure of arrays): value k (0..8 A's vertices, 9..17
// B's, x y z per vertex) of the chunk's j-th candidate is at [k * kNearRow + j], so the float pre-test runs
// over the chunk as vector code.
class ChunkTriangles {
 public:
  // Left uninitialised: every value is written before it is read, and zeroing 38 KB per chunk was measured.
  ChunkTriangles() : m_values(new float[18 * kNearRow]) {}

  void load(std::size_t j, Eigen::Vector3f (&a)[3], Eigen::Vector3f (&b)[3]) const {
    const RowTriangles t(m_values.get(), j);
    a[0] = t.a0, a[1] = t.a1, a[2] = t.a2;
    b[0] = t.b0, b[1] = t.b1, b[2] = t.b2;
  }

  const float* data() const { return m_values.get(); }
  float* values() { return m_values.get(); }

 private:
  std::unique_ptr<float[]> m_values;
};

// The rows one thread works in: the chunk's triangles, the survivors of the plane test, and the candidates
// the proximity pre-test leaves.
struct ChunkBuffers {
  ChunkTriangles triangles;
  ChunkTriangles crossing;
  ChunkTriangles nearby;
  // The contacts of the pairs the pre-tests left (detail::generateContactRows), and their outcomes.
  std::unique_ptr<float[]> contacts{new float[detail::kContactRowValues * kNearRow]};
  std::unique_ptr<std::uint32_t[]> outcome{new std::uint32_t[kNearChunk]};
};

// The frame applied to a chunk's rows in place: A's vertices (values 0..8) times A's scale, B's (9..17)
// carried into A's scaled frame (PairFrame) by gpucol_carry_point (shared_math/box_carry.h, Eigen's order of
// `bLinear * p + bTranslation`, as the device does it); written over whole rows the loops are vector code.
GPUCOL_AVX2_CLONES void transformRows(float* rows, std::size_t count, const PairFrame& frame) {
  constexpr std::size_t n = kNearRow;
  for (int v = 0; v < 3; ++v) {
    for (int c = 0; c < 3; ++c) {
      float* const row = rows + (3 * v + c) * n;
      const float scale = frame.scaleA[c];
      for (std::size_t j = 0; j < count; ++j) row[j] *= scale;
    }
  }
  const Eigen::Matrix3f& m = frame.bLinear;
  const Eigen::Vector3f& t = frame.bTranslation;
  for (int v = 0; v < 3; ++v) {
    float* const x = rows + (9 + 3 * v) * n;
    float* const y = x + n;
    float* const z = y + n;
    for (std::size_t j = 0; j < count; ++j) {
      const float px = x[j], py = y[j], pz = z[j];
      x[j] = gpucol_carry_point(m(0, 0), m(0, 1), m(0, 2), px, py, pz, t.x());
      y[j] = gpucol_carry_point(m(1, 0), m(1, 1), m(1, 2), px, py, pz, t.y());
      z[j] = gpucol_carry_point(m(2, 0), m(2, 1), m(2, 2), px, py, pz, t.z());
    }
  }
}

// Copies column `fromColumn` of rows `from` (a candidate's 18 values, ChunkTriangles' layout) to column
// `toColumn` of rows `to`: how the passes below gather the candidates they keep.
inline void copyColumn(const float* from, std::size_t fromColumn, float* to, std::size_t toColumn) {
  for (std::size_t k = 0; k < 18; ++k) to[k * kNearRow + toColumn] = from[k * kNearRow + fromColumn];
}

// The triangles of candidates begin .. begin + count into `rows` (ChunkTriangles' layout), in A's scaled
// frame.
inline void fetchChunkRows(const MeshShape& shapeA, const MeshShape& shapeB, const PairFrame& frame,
                           const std::vector<TrianglePair>& candidates, std::size_t begin, std::size_t count,
                           float* rows) {
  // The mesh coordinates are copied into the rows as they are, and the frame (A's scale, B's map into A's
  // frame) is applied afterwards, row by row, as vector code (transformRows): per candidate, through Eigen
  // vectors, the near phase took 5.85M instructions per query of the thesis scene (armadillo-27674, one
  // thread, valgrind), this way 4.97M. A mirroring scale swaps which rows vertices 1 and 2 go to, to keep
  // the winding outward.
  constexpr std::size_t n = kNearRow;
  const std::size_t rowA[3] = {0, frame.flipA ? 2u : 1u, frame.flipA ? 1u : 2u};
  const std::size_t rowB[3] = {3, frame.flipB ? 5u : 4u, frame.flipB ? 4u : 5u};
  // B's triangles are read in no useful order. They come from the shapes' triangle soups (MeshShape::
  // triangleSoup): one contiguous 36-byte read per triangle, prefetched kSoupAhead candidates ahead, where
  // the mesh's index and vertex arrays cost a load of the indices and then, depending on it, three vertex
  // loads.
  const float* const soupA = shapeA.triangleSoup();
  const float* const soupB = shapeB.triangleSoup();
  float a[9] = {};
  for (std::size_t j = 0; j < count; ++j) {
    const std::size_t i = begin + j;
    if (i + kSoupAhead < candidates.size()) {
      // B's triangle, and A's too: A's come in ascending order but far apart, and perf showed the first
      // load of each new A triangle as the near phase's largest stall once B's were prefetched.
      const TrianglePair& ahead = candidates[i + kSoupAhead];
      const float* aheadB = soupB + 9 * std::size_t(ahead.triangleB);
      const float* aheadA = soupA + 9 * std::size_t(ahead.triangleA);
      prefetch(aheadB);
      prefetch(aheadB + 8);  // the last coordinate, on the next cache line when the triangle straddles two
      prefetch(aheadA);
      prefetch(aheadA + 8);
    }
    const TrianglePair& pair = candidates[i];
    if (j == 0 || pair.triangleA != candidates[i - 1].triangleA) {
      const float* p = soupA + 9 * std::size_t(pair.triangleA);
      for (int v = 0; v < 3; ++v) {
        for (int c = 0; c < 3; ++c) a[3 * rowA[v] + c] = p[3 * v + c];
      }
    }
    for (std::size_t k = 0; k < 9; ++k) rows[k * n + j] = a[k];
    const float* p = soupB + 9 * std::size_t(pair.triangleB);
    for (int v = 0; v < 3; ++v) {
      for (int c = 0; c < 3; ++c) rows[(3 * rowB[v] + c) * n + j] = p[3 * v + c];
    }
  }
  transformRows(rows, count, frame);
}

// The calling thread's ChunkBuffers, kept from pair to pair and step to step: a chunk's rows are written
// before they are read, and runNearChunk starts no parallel work, so a thread is in one chunk at a time.
ChunkBuffers& threadChunkBuffers() {
  thread_local ChunkBuffers buffers;
  return buffers;
}

// Marks in `empty` the columns of `rows` that proximityCertainlyEmptyBranchFree proves have no proximity
// contact; a loop of vector code over the chunk, compiled for AVX2 too.
GPUCOL_AVX2_CLONES void markProximityEmpty(const float* rows, std::size_t count, float reach,
                                           std::uint8_t* empty) {
  for (std::size_t j = 0; j < count; ++j) {
    const RowTriangles t(rows, j);
    empty[j] = static_cast<std::uint8_t>(
        proximityCertainlyEmptyBranchFree(t.a0, t.a1, t.a2, t.b0, t.b1, t.b2, reach));
  }
}

// Copies the columns of `rows` that the proximity pre-test leaves into `kept`'s first columns; their indices
// go to `index`. Returns how many.
std::size_t keepProximityCandidates(const float* rows, std::size_t count, float reach, float* kept,
                                    std::uint16_t* index) {
  std::uint8_t empty[kNearChunk];
  markProximityEmpty(rows, count, reach, empty);
  std::size_t left = 0;
  for (std::size_t j = 0; j < count; ++j) {
    if (empty[j]) continue;
    index[left] = static_cast<std::uint16_t>(j);
    copyColumn(rows, j, kept, left);
    ++left;
  }
  return left;
}

// Wing i (MeshShape::edgeWings) of a triangle whose vertices went into the rows as fetchChunkRows puts them,
// in the pair's frame: A's scaled, B's carried into A's. A mirroring scale swaps vertices 1 and 2, so the
// rows' edge i is the mesh's edge 2 - i.
Eigen::Vector3f pairFrameWing(const MeshShape& shape, std::uint32_t triangle, bool isA,
                              const PairFrame& frame, int i) {
  const int k = (isA ? frame.flipA : frame.flipB) ? 2 - i : i;
  const float* w = shape.edgeWings() + 9 * std::size_t(triangle) + 3 * k;
  const Eigen::Vector3f p(w[0], w[1], w[2]);
  return isA ? Eigen::Vector3f(p.cwiseProduct(frame.scaleA))
             : Eigen::Vector3f(frame.bLinear * p + frame.bTranslation);
}

// The three wings of a triangle in the pair's frame (pairFrameWing).
EdgeWings pairFrameWings(const MeshShape& shape, std::uint32_t triangle, bool isA, const PairFrame& frame) {
  EdgeWings out;
  for (int i = 0; i < 3; ++i) out.across[i] = pairFrameWing(shape, triangle, isA, frame, i);
  return out;
}

// The triangles of one candidate in A's scaled frame, bit for bit as fetchChunkRows puts them in its rows.
void loadPairTriangles(const MeshShape& shapeA, const MeshShape& shapeB, const PairFrame& frame,
                       const TrianglePair& pair, Eigen::Vector3f (&a)[3], Eigen::Vector3f (&b)[3]) {
  const float* pa = shapeA.triangleSoup() + 9 * std::size_t(pair.triangleA);
  const float* pb = shapeB.triangleSoup() + 9 * std::size_t(pair.triangleB);
  const int rowA[3] = {0, frame.flipA ? 2 : 1, frame.flipA ? 1 : 2};
  const int rowB[3] = {0, frame.flipB ? 2 : 1, frame.flipB ? 1 : 2};
  const Eigen::Matrix3f& m = frame.bLinear;
  const Eigen::Vector3f& t = frame.bTranslation;
  for (int v = 0; v < 3; ++v) {
    for (int c = 0; c < 3; ++c) a[rowA[v]][c] = pa[3 * v + c] * frame.scaleA[c];
    const float x = pb[3 * v], y = pb[3 * v + 1], z = pb[3 * v + 2];
    for (int r = 0; r < 3; ++r) b[rowB[v]][r] = gpucol_carry_point(m(r, 0), m(r, 1), m(r, 2), x, y, z, t[r]);
  }
}

// The wings (pairFrameWings) of a triangle's edges, split by MeshShape::flatDiagonals: those of its flat
// diagonals in `flat`, the others in `other`, NaN in the other one.
void splitWings(const MeshShape& shape, std::uint32_t triangle, bool isA, const PairFrame& frame, EdgeWings& flat,
                EdgeWings& other) {
  const std::uint8_t flatBits = shape.flatDiagonals()[triangle];
  const bool flip = isA ? frame.flipA : frame.flipB;
  const EdgeWings wings = pairFrameWings(shape, triangle, isA, frame);
  const Eigen::Vector3f none = Eigen::Vector3f::Constant(std::numeric_limits<float>::quiet_NaN());
  for (int i = 0; i < 3; ++i) {
    const bool flatEdge = flatBits & (1u << (flip ? 2 - i : i));
    flat.across[i] = flatEdge ? wings.across[i] : none;
    other.across[i] = flatEdge ? none : wings.across[i];
  }
}

// clipContactToOverlap of a candidate's contact (a and b: its triangles in the pair's frame), over the flat
// diagonals and bounded by the convex edges of the triangle its moving triangle leaves (B's when A moves);
// returns how many contacts at the overlap's other corners it wrote to `corners`.
int clipToOverlap(const MeshShape& shapeA, const MeshShape& shapeB, const PairFrame& frame,
                  const TrianglePair& pair, const Eigen::Vector3f (&a)[3], const Eigen::Vector3f (&b)[3],
                  TriangleContact& contact, TriangleContact (&corners)[kMaxOverlapCorners]) {
  if (!(contact.depth < 0)) return 0;
  EdgeWings flatWings, otherWings;
  if (contact.onFaceOfB) {
    splitWings(shapeB, pair.triangleB, false, frame, flatWings, otherWings);
  } else {
    splitWings(shapeA, pair.triangleA, true, frame, flatWings, otherWings);
  }
  return clipContactToOverlap(a, b, flatWings, otherWings, contact, corners);
}

// A hit with a contact, of a candidate `pair` whose triangles in the pair's frame are a and b, appended to
// `hits` with its contact clipped to their overlap (clipToOverlap), then a copy per other corner of the
// overlap with that corner's contact. Serves the CPU's hits (NearHit) and the device's (DeviceNearHit). Out
// of line: inlined, its code made the near phase's vector loops over the chunk slower.
template <class Hit>
[[gnu::noinline]] void pushOverlapHits(const MeshShape& shapeA, const MeshShape& shapeB,
                                       const PairFrame& frame, const TrianglePair& pair,
                                       const Eigen::Vector3f (&a)[3], const Eigen::Vector3f (&b)[3],
                                       const Hit& hit, std::vector<Hit>& hits) {
  TriangleContact contact = hit.contact;
  TriangleContact corners[kMaxOverlapCorners];
  const int more = clipToOverlap(shapeA, shapeB, frame, pair, a, b, contact, corners);
  hits.push_back(hit);
  hits.back().contact = contact;
  for (int k = 0; k < more; ++k) {
    hits.push_back(hit);
    hits.back().contact = corners[k];
  }
}

// B's faces and edge wings of one chunk's proximity tests, by B's triangle, in a small direct-mapped cache:
// after the first run of candidates sharing A's triangle, the next runs meet mostly the same triangles of B.
class RecentFacesB {
 public:
  struct Slot {
    ProximityFace face;
    EdgeWings wings;
    std::uint32_t triangle = 0;
    bool filled = false;
  };

  const Slot& slot(const MeshShape& shapeB, std::uint32_t triangle, const Eigen::Vector3f (&vertices)[3],
                   const PairFrame& frame) {
    Slot& slot = m_slots[triangle % kSlots];
    if (!slot.filled || slot.triangle != triangle) {
      slot.face = proximityFace(vertices);
      slot.wings = pairFrameWings(shapeB, triangle, false, frame);
      slot.triangle = triangle;
      slot.filled = true;
    }
    return slot;
  }

 private:
  static constexpr std::uint32_t kSlots = 64;
  Slot m_slots[kSlots];
};

// The proximity contacts of the kept candidates (keepProximityCandidates) whose triangles do not cross, in
// their order, appended to `out`; candidate index(i) is kept column i. Candidates come sorted by triangleA,
// so A's face is made once per run of equal triangleA; B's come from RecentFacesB.
template <class CandidateOf, class Crosses>
void proximityOfKept(const MeshShape& shapeA, const MeshShape& shapeB, const ChunkTriangles& kept,
                     std::size_t count, CandidateOf candidateOf, Crosses crosses,
                     const std::vector<TrianglePair>& candidates, const PairFrame& frame,
                     std::vector<NearbyHit>& out) {
  ProximityFace faceA;
  EdgeWings wingsA;
  std::size_t faceOf = std::numeric_limits<std::size_t>::max();
  RecentFacesB facesB;
  for (std::size_t i = 0; i < count; ++i) {
    const std::size_t candidate = candidateOf(i);
    if (crosses(i)) continue;
    Eigen::Vector3f a[3], b[3];
    kept.load(i, a, b);
    if (faceOf == std::numeric_limits<std::size_t>::max() ||
        candidates[faceOf].triangleA != candidates[candidate].triangleA) {
      faceA = proximityFace(a);
      wingsA = pairFrameWings(shapeA, candidates[candidate].triangleA, true, frame);
      faceOf = candidate;
    }
    const RecentFacesB::Slot& slotB = facesB.slot(shapeB, candidates[candidate].triangleB, b, frame);
    TriangleContact found[kMaxProximityContacts];
    const int made =
        proximityContacts(faceA, slotB.face, frame.reach, found, frame.marginReach, &wingsA, &slotB.wings);
    for (int k = 0; k < made; ++k) out.push_back({candidate, found[k]});
  }
}

// One chunk of the near phase: the candidates from `begin` on (at most kNearChunk), their hits appended to `hits`
// and, when the pair has a reach, the proximity contacts of those that do not cross to `nearby`. Its passes: fetch
// the triangles into rows (A's once per run of equal triangleA: candidates come sorted by it) and apply the pair's
// frame; keep aside the candidates the proximity pre-test cannot rule out; leave out those whose triangles' boxes
// miss; run the float plane pre-test of triangle_plane.h over the rest without branches; gather the pairs it could
// not reject and run the float interval pre-test over those; then run the double test and the contact generation
// on the pairs left; last, the proximity contacts of the kept candidates that do not cross. The pre-tests only
// reject what the double tests reject, so the result is the double tests'; the plane test removes about two thirds
// of the candidates of the thesis scene, and without a branch per pair (its outcome is close to a coin toss).
// Compiled for AVX2 and baseline x86-64 (bvh/avx2_clones.h): with AVX2 the row loops below run on 8 lanes instead
// of 4, and the results are the same bits.
GPUCOL_AVX2_CLONES void runNearChunk(const MeshShape& shapeA, const MeshShape& shapeB, const PairFrame& frame,
                                     const std::vector<TrianglePair>& candidates, std::size_t begin,
                                     ChunkBuffers& buffers, std::vector<NearHit>& hits,
                                     std::vector<NearbyHit>& nearby) {
  const std::size_t count = std::min(candidates.size(), begin + kNearChunk) - begin;
  ChunkTriangles& triangles = buffers.triangles;
  ChunkTriangles& crossing = buffers.crossing;
  float* const rows = triangles.values();
  constexpr std::size_t n = kNearRow;
  fetchChunkRows(shapeA, shapeB, frame, candidates, begin, count, rows);
  // Kept before the passes below overwrite the rows with their survivors.
  std::uint16_t nearIndex[kNearChunk];
  const std::size_t nearCount =
      frame.reach > 0 ? keepProximityCandidates(rows, count, frame.reach, buffers.nearby.values(), nearIndex)
                      : 0;
  // Candidates whose two triangles' boxes miss each other cannot cross: most of those of a pair with a reach,
  // whose search widened every box. Min and max round nothing, so this leaves out only pairs the tests below
  // reject. The rest are gathered to the front of the rows; boxed[k] is column k's place in the chunk.
  std::uint8_t meet[kNearChunk];
  for (std::size_t j = 0; j < count; ++j) {
    bool boxesMeet = true;
    for (std::size_t c = 0; c < 3; ++c) {
      const float a0 = rows[c * n + j], a1 = rows[(3 + c) * n + j], a2 = rows[(6 + c) * n + j];
      const float b0 = rows[(9 + c) * n + j], b1 = rows[(12 + c) * n + j], b2 = rows[(15 + c) * n + j];
      const float aLow = std::min(a0, std::min(a1, a2)), aHigh = std::max(a0, std::max(a1, a2));
      const float bLow = std::min(b0, std::min(b1, b2)), bHigh = std::max(b0, std::max(b1, b2));
      boxesMeet = boxesMeet & (aLow <= bHigh) & (bLow <= aHigh);
    }
    meet[j] = static_cast<std::uint8_t>(boxesMeet);
  }
  std::uint16_t boxed[kNearChunk];
  std::size_t meeting = 0;
  for (std::size_t j = 0; j < count; ++j) {
    if (!meet[j]) continue;
    if (meeting != j) copyColumn(rows, j, rows, meeting);
    boxed[meeting++] = static_cast<std::uint16_t>(j);
  }
  // Plain pointers, loaded once: the stores into `apart` could alias the vector's own fields otherwise, and
  // the compiler would give up on vector code.
  const float* const v = triangles.data();
  std::uint8_t apart[kNearChunk];
  for (std::size_t j = 0; j < meeting; ++j) {
    const RowTriangles t(v, j);
    apart[j] =
        static_cast<std::uint8_t>(detail::floatCertainlyApartBranchFree(t.a0, t.a1, t.a2, t.b0, t.b1, t.b2));
  }
  // The pairs left go through the float interval stage, gathered into rows of their own so that its loop is
  // vector code too; it rejects about two thirds of them, the pairs whose triangles cross each other's
  // planes but not each other.
  std::uint16_t survivor[kNearChunk];
  std::size_t survivors = 0;
  for (std::size_t j = 0; j < meeting; ++j) {
    survivor[survivors] = static_cast<std::uint16_t>(j);
    survivors += !apart[j];
  }
  float* const w = crossing.values();
  for (std::size_t s = 0; s < survivors; ++s) {
    copyColumn(v, survivor[s], w, s);
  }
  for (std::size_t s = 0; s < survivors; ++s) {
    const RowTriangles t(w, s);
    apart[s] =
        static_cast<std::uint8_t>(detail::floatIntervalsApartBranchFree(t.a0, t.a1, t.a2, t.b0, t.b1, t.b2));
  }
  // The pairs left, gathered again into the first rows (free now), go through the double test and the
  // contact generation as columns (detail::generateContactRows: four pairs per vector, the answers chosen by
  // masks); a coplanar pair goes to the one-pair function.
  std::uint16_t tested[kNearChunk];
  std::size_t testedCount = 0;
  for (std::size_t s = 0; s < survivors; ++s) {
    if (apart[s]) continue;
    tested[testedCount] = survivor[s];
    copyColumn(w, s, rows, testedCount);
    ++testedCount;
  }
  float* const c = buffers.contacts.get();
  std::uint32_t* const outcome = buffers.outcome.get();
  detail::generateContactRows(rows, n, testedCount, c, outcome);
  const std::size_t firstHit = hits.size();
  for (std::size_t t = 0; t < testedCount; ++t) {
    const std::size_t j = boxed[tested[t]];
    switch (outcome[t] & detail::kRowOutcomeMask) {
      case detail::kRowApart:
        break;
      case detail::kRowIntersectsNoContact:
        hits.push_back({begin + j, false, noContact()});
        break;
      case detail::kRowContact: {
        TriangleContact contact;
        contact.point = Eigen::Vector3f(c[t], c[n + t], c[2 * n + t]);
        contact.normalOnB = Eigen::Vector3f(c[3 * n + t], c[4 * n + t], c[5 * n + t]);
        contact.depth = c[6 * n + t];
        contact.onFaceOfB = (outcome[t] & detail::kRowOnFaceOfB) != 0;
        contact.sameFacing = (outcome[t] & detail::kRowSameFacing) != 0;
        contact.deepestPoint = Eigen::Vector3f(c[7 * n + t], c[8 * n + t], c[9 * n + t]);
        Eigen::Vector3f a[3], b[3];
        triangles.load(t, a, b);
        pushOverlapHits(shapeA, shapeB, frame, candidates[begin + j], a, b, NearHit{begin + j, true, contact},
                        hits);
        break;
      }
      default: {
        Eigen::Vector3f a[3], b[3];
        triangles.load(t, a, b);
        bool intersects = false;
        const std::optional<TriangleContact> contact = detail::generateContactAndTest(a, b, intersects);
        if (contact) {
          pushOverlapHits(shapeA, shapeB, frame, candidates[begin + j], a, b,
                          NearHit{begin + j, true, *contact}, hits);
        } else if (intersects) {
          hits.push_back({begin + j, false, noContact()});
        }
      }
    }
  }
  if (nearCount == 0) return;
  std::uint8_t crosses[kNearChunk] = {};
  for (std::size_t h = firstHit; h < hits.size(); ++h) crosses[hits[h].candidate - begin] = 1;
  proximityOfKept(
      shapeA, shapeB, buffers.nearby, nearCount, [&](std::size_t i) { return begin + nearIndex[i]; },
      [&](std::size_t i) { return crosses[nearIndex[i]] != 0; }, candidates, frame, nearby);
}

// The near phase's hits and the proximity contacts of one pair.
struct NearPhaseResult {
  std::vector<NearHit> hits;
  std::vector<NearbyHit> nearby;
};

// Joins per-chunk lists in chunk order.
template <class T>
std::vector<T> joinChunks(const std::vector<std::vector<T>>& chunks) {
  std::size_t total = 0;
  for (const std::vector<T>& chunk : chunks) total += chunk.size();
  std::vector<T> joined;
  joined.reserve(total);
  for (const std::vector<T>& chunk : chunks) joined.insert(joined.end(), chunk.begin(), chunk.end());
  return joined;
}

// Exact test and contact generation for every candidate (thesis §5.3.4: the cheap test first, contacts only
// for intersecting pairs), and the proximity contacts of those that do not cross, in parallel. Each chunk of
// candidates keeps its own hits, and the chunks are joined in order, so the output follows the candidates'
// order whatever the threads do. The work of a chunk is runNearChunk's.
NearPhaseResult runNearPhase(const MeshShape& shapeA, const MeshShape& shapeB, const PairFrame& frame,
                             const std::vector<TrianglePair>& candidates) {
  const std::size_t chunks = (candidates.size() + kNearChunk - 1) / kNearChunk;
  if (chunks <= 1) {
    // Most pairs of a pile: one chunk, run here, its hits straight into the result.
    NearPhaseResult result;
    if (chunks == 1) {
      runNearChunk(shapeA, shapeB, frame, candidates, 0, threadChunkBuffers(), result.hits, result.nearby);
    }
    return result;
  }
  std::vector<std::vector<NearHit>> chunkHits(chunks);
  std::vector<std::vector<NearbyHit>> chunkNearby(chunks);
  tbb::parallel_for(std::size_t(0), chunks, [&](std::size_t chunk) {
    runNearChunk(shapeA, shapeB, frame, candidates, chunk * kNearChunk, threadChunkBuffers(),
                 chunkHits[chunk], chunkNearby[chunk]);
  });
  return {joinChunks(chunkHits), joinChunks(chunkNearby)};
}

// The proximity contacts of every candidate that does not cross, in candidate order, in parallel, for the
// device's near phase (the CPU's finds them in runNearChunk); `crossing[i]` is set for the candidates the
// near phase found intersecting.
std::vector<NearbyHit> runProximityPass(const MeshShape& shapeA, const MeshShape& shapeB,
                                        const PairFrame& frame, const std::vector<TrianglePair>& candidates,
                                        const std::vector<std::uint8_t>& crossing) {
  const std::size_t chunks = (candidates.size() + kNearChunk - 1) / kNearChunk;
  std::vector<std::vector<NearbyHit>> chunkHits(chunks);
  tbb::parallel_for(std::size_t(0), chunks, [&](std::size_t chunk) {
    const std::size_t begin = chunk * kNearChunk;
    const std::size_t count = std::min(candidates.size(), begin + kNearChunk) - begin;
    // The chunk's triangles, and those the proximity pre-test leaves.
    ChunkBuffers& buffers = threadChunkBuffers();
    ChunkTriangles& rows = buffers.triangles;
    ChunkTriangles& kept = buffers.nearby;
    fetchChunkRows(shapeA, shapeB, frame, candidates, begin, count, rows.values());
    std::uint16_t nearIndex[kNearChunk];
    const std::size_t nearCount =
        keepProximityCandidates(rows.data(), count, frame.reach, kept.values(), nearIndex);
    proximityOfKept(
        shapeA, shapeB, kept, nearCount, [&](std::size_t i) { return begin + nearIndex[i]; },
        [&](std::size_t i) { return crossing[begin + nearIndex[i]] != 0; }, candidates, frame,
        chunkHits[chunk]);
  });
  return joinChunks(chunkHits);
}

MeshContact toWorld(const TrianglePair& pair, const TriangleContact& contact, const btTransform& worldFromA) {
  MeshContact out;
  out.triangleA = pair.triangleA;
  out.triangleB = pair.triangleB;
  out.pointWorld = worldFromA * btVector3(contact.point.x(), contact.point.y(), contact.point.z());
  out.normalWorldOnB =
      worldFromA.getBasis() * btVector3(contact.normalOnB.x(), contact.normalOnB.y(), contact.normalOnB.z());
  out.depth = contact.depth;
  // Bullet's pair of points: the moving triangle's deepest vertex on its own body, and that vertex moved out
  // by the depth on the other (pointOnA = pointOnB + normal * depth).
  const btVector3 deepest =
      worldFromA * btVector3(contact.deepestPoint.x(), contact.deepestPoint.y(), contact.deepestPoint.z());
  out.pointOnBWorld = contact.onFaceOfB ? deepest - out.normalWorldOnB * out.depth : deepest;
  return out;
}

// The near phase's hits (NearHit here, DeviceNearHit from the device; both in candidate order) into the
// result's intersecting pairs and contacts, then the proximity contacts (`nearby`, in candidate order), then
// the contact reduction. Shared by both paths, so the same-facing rule, the world conversion and the
// reduction cannot drift apart.
template <class Hit>
void assembleResult(const std::vector<Hit>& hits, const std::vector<NearbyHit>& nearby,
                    const PairFrame& frame, const Config& config, MeshPairResult& result) {
  result.stats.triangleTests = result.candidatePairs.size();
  std::vector<ReductionInput> localContacts;
  result.intersectingPairs.reserve(hits.size());
  result.contacts.reserve(hits.size());
  localContacts.reserve(hits.size());
  // Same-facing contacts count only when the pair has no other (TriangleContact::sameFacing).
  const bool anyFacingEachOther = std::any_of(
      hits.begin(), hits.end(), [](const Hit& hit) { return hit.hasContact && !hit.contact.sameFacing; });
  for (std::size_t h = 0; h < hits.size(); ++h) {
    const Hit& hit = hits[h];
    const TrianglePair& pair = result.candidatePairs[hit.candidate];
    // A pair's contacts at the other corners of its overlap follow its first hit.
    if (h == 0 || hits[h - 1].candidate != hit.candidate) result.intersectingPairs.push_back(pair);
    if (!hit.hasContact || (anyFacingEachOther && hit.contact.sameFacing)) continue;
    result.contacts.push_back(toWorld(pair, hit.contact, frame.worldFromA));
    localContacts.push_back({hit.contact.point, hit.contact.normalOnB, hit.contact.depth});
  }
  for (const NearbyHit& hit : nearby) {
    result.contacts.push_back(toWorld(result.candidatePairs[hit.candidate], hit.contact, frame.worldFromA));
    localContacts.push_back({hit.contact.point, hit.contact.normalOnB, hit.contact.depth});
  }

  const auto start = Clock::now();
  // Binning runs in A's scaled frame: positions are scaled to the contacts' own box, so the frame only has
  // to be the same for all contacts of the pair.
  for (std::uint32_t kept : reduceContacts(localContacts, config.reductionResolution)) {
    result.reducedContacts.push_back(result.contacts[kept]);
  }
  result.stats.reductionMs = millisecondsSince(start);
}

}  // namespace

// The device's hits, their contacts clipped to the triangles' overlap as the CPU's are (runNearChunk), and
// the proximity contacts of the candidates that do not cross (found here, on the CPU), as the CPU path's own.
template <class Hit>
void collectHits(const std::vector<Hit>& deviceHits, const MeshShape& shapeA, const MeshShape& shapeB,
                 const PairFrame& frame, const Config& config, MeshPairResult& result) {
  std::vector<Hit> hits;
  hits.reserve(deviceHits.size());
  for (const Hit& deviceHit : deviceHits) {
    if (!deviceHit.hasContact) {
      hits.push_back(deviceHit);
      continue;
    }
    const TrianglePair& pair = result.candidatePairs[deviceHit.candidate];
    Eigen::Vector3f a[3], b[3];
    loadPairTriangles(shapeA, shapeB, frame, pair, a, b);
    pushOverlapHits(shapeA, shapeB, frame, pair, a, b, deviceHit, hits);
  }
  std::vector<NearbyHit> nearby;
  if (frame.reach > 0) {
    std::vector<std::uint8_t> crossing(result.candidatePairs.size(), 0);
    for (const Hit& hit : hits) crossing[hit.candidate] = 1;
    nearby = runProximityPass(shapeA, shapeB, frame, result.candidatePairs, crossing);
  }
  assembleResult(hits, nearby, frame, config, result);
}

void requireFinite(const btTransform& transformA, const btTransform& transformB) {
  if (!isFinite(transformA) || !isFinite(transformB)) {
    throw std::invalid_argument("collideMeshes: the transform of shape " +
                                std::string(isFinite(transformA) ? "B" : "A") +
                                " has a NaN or infinite component");
  }
}

MeshPairResult collidePairOnCpu(const MeshPairQuery& query, const Config& config, CandidateCache* cache) {
  requireFinite(query.transformA, query.transformB);
  const MeshShape& shapeA = *query.shapeA;
  const MeshShape& shapeB = *query.shapeB;
  MeshPairResult result;
  result.stats.backendUsed = Backend::Cpu;
  const PairFrame frame = makePairFrame(shapeA, query.transformA, shapeB, query.transformB,
                                        query.speculativeMotion, query.speculativeDistance);

  auto start = Clock::now();
  // Root boxes first: a pair whose meshes' boxes miss costs one box test (DESIGN.md, "skip what a scene does
  // not need").
  result.stats.nodeTests = 1;
  if (!rootBoxesOverlap(shapeA.tree(), shapeB.tree(), frame.treeMap, frame.candidateReach)) {
    result.stats.rootBoxesMissed = true;
    result.stats.middlePhaseMs = millisecondsSince(start);
    return result;
  }
  if (cache != nullptr && query.speculativeMotion.isZero() && query.speculativeDistance == 0) {
    // A pair without a speculative reach may be at rest: its kept candidates, when they still cover it.
    std::uint64_t nodeTests = 0;
    result.candidatePairs = cache->candidates(shapeA, shapeB, frame, nodeTests);
    if (nodeTests != 0) result.stats.nodeTests = nodeTests;  // a traversal ran, its root test included
  } else {
    TraversalStats traversal;
    findCandidatePairs(shapeA.tree(), shapeB.tree(), frame.treeMap, result.candidatePairs, &traversal, true,
                       frame.candidateReach);
    result.stats.nodeTests = traversal.nodeTests;
  }
  result.stats.middlePhaseMs = millisecondsSince(start);

  start = Clock::now();
  const NearPhaseResult near = runNearPhase(shapeA, shapeB, frame, result.candidatePairs);
  assembleResult(near.hits, near.nearby, frame, config, result);
  result.stats.nearPhaseMs = millisecondsSince(start) - result.stats.reductionMs;
  return result;
}

// The device's hits go through the same function (mesh_batch.cpp).
template void collectHits<DeviceNearHit>(const std::vector<DeviceNearHit>& hits, const MeshShape& shapeA,
                                         const MeshShape& shapeB, const PairFrame& frame,
                                         const Config& config, MeshPairResult& result);

}  // namespace gpucol
