#include "bvh/tree_traversal.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <limits>
#include <memory>
#include <utility>

#include "bvh/avx2_clones.h"
#include "bvh/prefetch.h"
#include "shared_math/box_carry.h"
#include "sorting/radix_sort.h"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

/// Where a node descends, its two children are carried into the other tree's frame together, one per half of
/// an 8-float vector (GCC/Clang vector extensions: one AVX instruction per step in the AVX2 clone, two SSE
/// ones in the baseline clone).
/// __builtin_shufflevector is Clang's and GCC's from version 12; older compilers carry the children one by
/// one.
#if defined(__SSE2__) && (defined(__clang__) || (defined(__GNUC__) && __GNUC__ >= 12))
#define GPUCOL_PAIRED_CARRY 1
#else
#define GPUCOL_PAIRED_CARRY 0
#endif

namespace gpucol {
namespace {

/// A box of B carried into A's frame. Lane 3 of each corner is padding, so that a corner is one 4-float load.
struct CarriedBox {
  float min[4];
  float max[4];
};

#if GPUCOL_PAIRED_CARRY
using Float4 = float __attribute__((vector_size(16)));
using Float8 = float __attribute__((vector_size(32)));
using Int8 = std::int32_t __attribute__((vector_size(32)));

/// Four floats from memory (no alignment needed).
inline Float4 load4(const float* p) {
  Float4 v;
  std::memcpy(&v, p, sizeof v);
  return v;
}

/// Two boxes carried into the other tree's frame: the first in lanes 0-3 of each corner, the second in lanes
/// 4-7 (lanes 3 and 7 are padding).
struct CarriedBoxPair {
  Float8 min;
  Float8 max;

  /// Bits 0-2: the box [lo, hi] overlaps the first box on x, y, z; bits 4-6: the same for the second. `lo`
  /// and `hi` are 4-float readable corners as in BoxCarrier::carry; lanes 3 and 7 compare padding.
  int overlapBits(const float* lo, const float* hi) const {
    const Float4 l = load4(lo), h = load4(hi);
    const Float8 lo2 = __builtin_shufflevector(l, l, 0, 1, 2, 3, 0, 1, 2, 3);
    const Float8 hi2 = __builtin_shufflevector(h, h, 0, 1, 2, 3, 0, 1, 2, 3);
    const Int8 ok = (lo2 <= max) & (min <= hi2);
    const __m128 first = reinterpret_cast<__m128>(__builtin_shufflevector(ok, ok, 0, 1, 2, 3));
    const __m128 second = reinterpret_cast<__m128>(__builtin_shufflevector(ok, ok, 4, 5, 6, 7));
    return _mm_movemask_ps(first) | (_mm_movemask_ps(second) << 4);
  }
};
#endif

/// A pair of nodes whose boxes are already known to overlap. B's carried box is not kept: it is needed again
/// only where A alone descends, and carrying it again there (the same operations, so the same bits) costs
/// less than moving 32 more bytes through the stack for every pair.
struct NodePair {
  std::uint32_t a;
  std::uint32_t b;
};

// The box code reads a node's or a leaf entry's corner as 4 floats: min[0..2] + max[0], max[0..2] + the index
// that follows. Both reads stay inside the struct.
static_assert(offsetof(AabbNode, max) == 12 && sizeof(AabbNode) >= 28,
              "AabbNode corners must be 4-float readable");
static_assert(offsetof(AabbLeafEntry, max) == 12 && sizeof(AabbLeafEntry) >= 28,
              "AabbLeafEntry corners must be 4-float readable");

/// Front pairs per thread at which the breadth-first expansion stops and the parallel depth-first traversal
/// starts. The breadth-first levels run on one thread, so the front should be no larger than the threads need
/// to share the work out (a front of 64 beat 1024 on every armadillo of the thesis scene with 2 threads:
/// measurement history, "Figures moved from code comments"). Per thread, so a machine with more cores still
/// gets tens of start pairs per thread to balance.
constexpr std::size_t kFrontPerThread = 32;

/// Fewest triangles both meshes need for the traversal to run in parallel. A smaller pair's traversal is
/// short, and its parallel machinery (workers' stacks and lists, their sort and merge) cost more than it
/// saved; the pairs of a batch run in parallel anyway. The candidates are sorted either way, so the choice
/// changes no result.
constexpr std::size_t kParallelTriangles = 2048;

/// Front pairs per parallel_for chunk: the front is small, and one start pair's subtree can be most of the
/// work.
constexpr std::size_t kParallelGrain = 2;

/// Expansions between asking for a pair's nodes and expanding it (Traverser::run): the prefetch hides the
/// nodes' cache misses once it asks a few expansions ahead; 4 was fastest on the thesis scene (measurement
/// history, "Figures moved from code comments").
constexpr std::size_t kLookahead = 4;

#if defined(__SSE2__)
/// Lane i of v in all four lanes.
template <int i>
inline __m128 splat(__m128 v) {
  return _mm_shuffle_ps(v, v, _MM_SHUFFLE(i, i, i, i));
}
#endif

/// One frame's map of one call (BoxMap), prepared once (thesis §3.3.3: with non-updated AABBs the rotation is
/// set up once for the two hierarchies and reused by every box test), with |M| and the inflation.
///
/// With SSE (every x86-64 CPU) a box is carried as three column products of 4 lanes, in the scalar code's
/// order (GPUCOL_CARRY_ROW of shared_math/box_carry.h, as the device does it), so both give the same bits.
class BoxCarrier {
 public:
  explicit BoxCarrier(const BoxMap& boxMap) {
    const AffineMap& map = boxMap.map;
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) {
        m_m[i][j] = map.linear(i, j);
        m_abs[i][j] = std::fabs(map.linear(i, j));
      }
      m_t[i] = map.translation(i);
      m_inflation[i] = boxMap.inflation(i);
    }
#if defined(__SSE2__)
    for (int j = 0; j < 3; ++j) {
      m_column[j] = _mm_setr_ps(m_m[0][j], m_m[1][j], m_m[2][j], 0.0f);
      m_absColumn[j] = _mm_setr_ps(m_abs[0][j], m_abs[1][j], m_abs[2][j], 0.0f);
    }
    m_translation = _mm_setr_ps(m_t[0], m_t[1], m_t[2], 0.0f);
    m_inflationLanes = _mm_setr_ps(m_inflation[0], m_inflation[1], m_inflation[2], 0.0f);
#endif
#if GPUCOL_PAIRED_CARRY
    for (int j = 0; j < 3; ++j) {
      m_column2[j] = Float8{m_m[0][j], m_m[1][j], m_m[2][j], 0.0f, m_m[0][j], m_m[1][j], m_m[2][j], 0.0f};
      m_absColumn2[j] =
          Float8{m_abs[0][j], m_abs[1][j], m_abs[2][j], 0.0f, m_abs[0][j], m_abs[1][j], m_abs[2][j], 0.0f};
    }
    m_translation2 = Float8{m_t[0], m_t[1], m_t[2], 0.0f, m_t[0], m_t[1], m_t[2], 0.0f};
    m_inflation2 = Float8{m_inflation[0], m_inflation[1], m_inflation[2], 0.0f,
                          m_inflation[0], m_inflation[1], m_inflation[2], 0.0f};
#endif
  }

#if GPUCOL_PAIRED_CARRY
  /// carry() of two nodes at once, lane for lane the same operations in the same order, so the same bits.
  CarriedBoxPair carryPair(const AabbNode& first, const AabbNode& second) const {
    const Int8 keepXyz = {-1, -1, -1, 0, -1, -1, -1, 0};
    const Float8 l =
        reinterpret_cast<Float8>(reinterpret_cast<Int8>(__builtin_shufflevector(
                                     load4(first.min), load4(second.min), 0, 1, 2, 3, 4, 5, 6, 7)) &
                                 keepXyz);
    const Float8 h =
        reinterpret_cast<Float8>(reinterpret_cast<Int8>(__builtin_shufflevector(
                                     load4(first.max), load4(second.max), 0, 1, 2, 3, 4, 5, 6, 7)) &
                                 keepXyz);
    const Float8 c = (l + h) * 0.5f;
    const Float8 e = (h - l) * 0.5f;
    const Float8 centre = GPUCOL_CARRY_ROW(
        m_column2[0], m_column2[1], m_column2[2], __builtin_shufflevector(c, c, 0, 0, 0, 0, 4, 4, 4, 4),
        __builtin_shufflevector(c, c, 1, 1, 1, 1, 5, 5, 5, 5),
        __builtin_shufflevector(c, c, 2, 2, 2, 2, 6, 6, 6, 6), m_translation2);
    const Float8 extent =
        GPUCOL_CARRY_ROW(m_absColumn2[0], m_absColumn2[1], m_absColumn2[2],
                         __builtin_shufflevector(e, e, 0, 0, 0, 0, 4, 4, 4, 4),
                         __builtin_shufflevector(e, e, 1, 1, 1, 1, 5, 5, 5, 5),
                         __builtin_shufflevector(e, e, 2, 2, 2, 2, 6, 6, 6, 6), m_inflation2);
    return {centre - extent, centre + extent};
  }
#endif

  /// centre' = M c + t, extents' = |M| e + inflation: contains every point of the box mapped by M, t.
  /// `lo` and `hi` point at the corners of an AabbNode or AabbLeafEntry (4 floats readable from each).
  CarriedBox carry(const float* lo, const float* hi) const {
    CarriedBox out;
#if defined(__SSE2__)
    // Lane 3 holds the next field (max[0], or an index whose bits may read as a denormal float, slow to add):
    // it is cleared before any arithmetic.
    const __m128 keepXyz = _mm_castsi128_ps(_mm_setr_epi32(-1, -1, -1, 0));
    const __m128 l = _mm_and_ps(_mm_loadu_ps(lo), keepXyz);
    const __m128 h = _mm_and_ps(_mm_loadu_ps(hi), keepXyz);
    const __m128 half = _mm_set1_ps(0.5f);
    const __m128 c = _mm_mul_ps(_mm_add_ps(l, h), half);
    const __m128 e = _mm_mul_ps(_mm_sub_ps(h, l), half);
    // GCC's and Clang's __m128 take arithmetic operators (the same mulps and addps as the intrinsics).
    const __m128 centre = GPUCOL_CARRY_ROW(m_column[0], m_column[1], m_column[2], splat<0>(c), splat<1>(c),
                                           splat<2>(c), m_translation);
    const __m128 extent = GPUCOL_CARRY_ROW(m_absColumn[0], m_absColumn[1], m_absColumn[2], splat<0>(e),
                                           splat<1>(e), splat<2>(e), m_inflationLanes);
    _mm_storeu_ps(out.min, _mm_sub_ps(centre, extent));
    _mm_storeu_ps(out.max, _mm_add_ps(centre, extent));
#else
    float c[3], e[3];
    for (int j = 0; j < 3; ++j) {
      c[j] = (lo[j] + hi[j]) * 0.5f;
      e[j] = (hi[j] - lo[j]) * 0.5f;
    }
    for (int i = 0; i < 3; ++i) {
      const float ci = GPUCOL_CARRY_ROW(m_m[i][0], m_m[i][1], m_m[i][2], c[0], c[1], c[2], m_t[i]);
      const float ei =
          GPUCOL_CARRY_ROW(m_abs[i][0], m_abs[i][1], m_abs[i][2], e[0], e[1], e[2], m_inflation[i]);
      out.min[i] = ci - ei;
      out.max[i] = ci + ei;
    }
    out.min[3] = out.max[3] = 0.0f;
#endif
    return out;
  }

 private:
  float m_m[3][3];
  float m_abs[3][3];
  float m_t[3];
  float m_inflation[3];
#if defined(__SSE2__)
  __m128 m_column[3];
  __m128 m_absColumn[3];
  __m128 m_translation;
  __m128 m_inflationLanes;
#endif
#if GPUCOL_PAIRED_CARRY
  Float8 m_column2[3];
  Float8 m_absColumn2[3];
  Float8 m_translation2;
  Float8 m_inflation2;
#endif
};

/// Touching counts as overlapping: the comparisons are exact on float, all rounding went into the inflation.
/// `lo` and `hi` are 4-float readable corners as in BoxCarrier::carry. Free of branches (with SSE one compare
/// per corner, else `&` rather than `&&`): the result feeds a branch-free push (Traverser::expand), and the
/// tests come out about half and half, so a branch would be mispredicted half the time.
inline bool overlaps(const float* lo, const float* hi, const CarriedBox& b) {
#if defined(__SSE2__)
  // Lane 3 compares padding and is ignored; comparisons take any bits without a slow path.
  const __m128 ok = _mm_and_ps(_mm_cmple_ps(_mm_loadu_ps(lo), _mm_loadu_ps(b.max)),
                               _mm_cmple_ps(_mm_loadu_ps(b.min), _mm_loadu_ps(hi)));
  return (_mm_movemask_ps(ok) & 7) == 7;
#else
  return GPUCOL_BOXES_OVERLAP(lo, hi, b.min, b.max);
#endif
}

/// Stack entries a plain depth-first descent below one start pair can need: each expansion pops one pair and
/// pushes at most four, and descends at least one of the trees by a level, so at most depthA + depthB
/// expansions lie on one path and the stack never holds more than 3 per expansion on the path, plus the start
/// pair. The stack starts with this many entries; Traverser::run's lookahead may need more, and grows it.
std::size_t stackBound(const AabbTree& a, const AabbTree& b) {
  return 3 * (static_cast<std::size_t>(a.depth()) + static_cast<std::size_t>(b.depth())) + 1;
}

/// Traverser::expand is inlined into both of its loops (the depth-first run and the breadth-first levels)
/// whatever the compiler's size estimate says: called, it saved and restored six registers per expansion, and
/// inlining took 0.87M of 14.7M instructions off one query of the thesis scene (armadillo-27674, one thread,
/// valgrind).
#if defined(__GNUC__)
#define GPUCOL_TRAVERSAL_INLINE inline __attribute__((always_inline))
#else
#define GPUCOL_TRAVERSAL_INLINE inline
#endif

/// Depth-first simultaneous descent from a set of overlapping node pairs (thesis Alg. 5.1), with an explicit
/// stack.
///
/// The stack is a plain array (of stackBound() entries to begin with), and children are pushed without a
/// branch: the entry is written at the top in any case and the top moves up by the outcome of the box test.
/// The tests come out about half and half, so a branch per test is mispredicted about half the time, which
/// cost more than the test itself.
class Traverser {
 public:
  Traverser(const AabbTree& a, const AabbTree& b, const BoxCarrier& intoA, const BoxCarrier& intoB)
      : m_nodesA(a.nodes().data()),
        m_nodesB(b.nodes().data()),
        m_entriesA(a.leafEntries().data()),
        m_entriesB(b.leafEntries().data()),
        m_intoA(intoA),
        m_intoB(intoB) {}

  /// Expands one overlapping pair by one level: children pairs that overlap are written from `top` on (room
  /// for four is needed), leaf pairs go to `out`. Returns the new top.
  GPUCOL_TRAVERSAL_INLINE NodePair* expand(const NodePair& pair, NodePair* top,
                                           std::vector<TrianglePair>& out, std::uint64_t& tests) const {
    const AabbNode& na = m_nodesA[pair.a];
    const AabbNode& nb = m_nodesB[pair.b];
    const bool leafA = na.isLeaf();
    const bool leafB = nb.isLeaf();
    if (!leafA && !leafB) {
      // Node against node: both descend at once, four tests (thesis Alg. 5.1); each of B's children is
      // carried once for two tests. "Descend the larger box" (thesis §3.3.2) was measured on the thesis scene
      // (armadillo-27674 twice, 0.3 x size apart, 0.5 rad): 92485 tests against 87657 for simultaneous
      // descent, and no faster, since it pays a size comparison per pair and carries a child of B for each
      // single test where B descends, while here each carried child serves two tests.
      const std::uint32_t a0 = pair.a + 1, a1 = na.first;
      const AabbNode& childA0 = m_nodesA[a0];
      const AabbNode& childA1 = m_nodesA[a1];
      const std::uint32_t childrenB[2] = {pair.b + 1, nb.first};
      // The children's far children (the near one is the next node in the array) are what the pairs pushed
      // now will read when popped; asking for them now overlaps those cache misses with this expansion. For a
      // leaf child `first` is a triangle index and the hint reads an unrelated node: harmless, it never
      // faults.
      const AabbNode& childB0 = m_nodesB[childrenB[0]];
      const AabbNode& childB1 = m_nodesB[childrenB[1]];
      prefetch(m_nodesA + childA0.first);
      prefetch(m_nodesA + childA1.first);
      prefetch(m_nodesB + childB0.first);
      prefetch(m_nodesB + childB1.first);
#if GPUCOL_PAIRED_CARRY
      // In A's frame B's children are carried together: with0 holds A0 against B0 (bits 0-2) and B1 (bits
      // 4-6). In B's frame A's children are: inB0 holds A0 (bits 0-2) and A1 (bits 4-6) against B0. Each
      // pair's bits in A's frame are kept where its bits in B's frame are set too.
      const CarriedBoxPair boxesB = m_intoA.carryPair(childB0, childB1);
      const CarriedBoxPair boxesA = m_intoB.carryPair(childA0, childA1);
      const int inB0 = boxesA.overlapBits(childB0.min, childB0.max);
      const int inB1 = boxesA.overlapBits(childB1.min, childB1.max);
      const int with0 = boxesB.overlapBits(childA0.min, childA0.max) & ((inB0 & 0x07) | ((inB1 & 0x07) << 4));
      const int with1 = boxesB.overlapBits(childA1.min, childA1.max) & (((inB0 >> 4) & 0x07) | (inB1 & 0x70));
      *top = {a0, childrenB[0]};
      top += (with0 & 0x07) == 0x07;
      *top = {a1, childrenB[0]};
      top += (with1 & 0x07) == 0x07;
      *top = {a0, childrenB[1]};
      top += (with0 & 0x70) == 0x70;
      *top = {a1, childrenB[1]};
      top += (with1 & 0x70) == 0x70;
#else
      const CarriedBox boxA0 = m_intoB.carry(childA0.min, childA0.max);
      const CarriedBox boxA1 = m_intoB.carry(childA1.min, childA1.max);
      for (std::uint32_t cb : childrenB) {
        const AabbNode& childB = m_nodesB[cb];
        const CarriedBox boxB = m_intoA.carry(childB.min, childB.max);
        *top = {a0, cb};
        top += overlaps(childA0.min, childA0.max, boxB) & overlaps(childB.min, childB.max, boxA0);
        *top = {a1, cb};
        top += overlaps(childA1.min, childA1.max, boxB) & overlaps(childB.min, childB.max, boxA1);
      }
#endif
      tests += 4;
      return top;
    }
    if (leafA && leafB) {
      emitLeafPair(na, nb, out, tests);
      return top;
    }
    if (leafA) {
      // Leaf against node: two tests, B's children carried into A's frame and A's leaf into B's.
      const std::uint32_t childrenB[2] = {pair.b + 1, nb.first};
      const AabbNode& childB0 = m_nodesB[childrenB[0]];
      const AabbNode& childB1 = m_nodesB[childrenB[1]];
      const CarriedBox boxA = m_intoB.carry(na.min, na.max);
#if GPUCOL_PAIRED_CARRY
      const int with = m_intoA.carryPair(childB0, childB1).overlapBits(na.min, na.max);
      *top = {pair.a, childrenB[0]};
      top += ((with & 0x07) == 0x07) & overlaps(childB0.min, childB0.max, boxA);
      *top = {pair.a, childrenB[1]};
      top += ((with & 0x70) == 0x70) & overlaps(childB1.min, childB1.max, boxA);
#else
      for (std::uint32_t cb : childrenB) {
        const AabbNode& childB = m_nodesB[cb];
        const CarriedBox boxB = m_intoA.carry(childB.min, childB.max);
        *top = {pair.a, cb};
        top += overlaps(na.min, na.max, boxB) & overlaps(childB.min, childB.max, boxA);
      }
#endif
      tests += 2;
      return top;
    }
    // Node against leaf: two tests, B's leaf carried into A's frame and A's children into B's.
    const std::uint32_t childrenA[2] = {pair.a + 1, na.first};
    const CarriedBox boxB = m_intoA.carry(nb.min, nb.max);
#if GPUCOL_PAIRED_CARRY
    const AabbNode& childA0 = m_nodesA[childrenA[0]];
    const AabbNode& childA1 = m_nodesA[childrenA[1]];
    const int inB = m_intoB.carryPair(childA0, childA1).overlapBits(nb.min, nb.max);
    *top = {childrenA[0], pair.b};
    top += overlaps(childA0.min, childA0.max, boxB) & ((inB & 0x07) == 0x07);
    *top = {childrenA[1], pair.b};
    top += overlaps(childA1.min, childA1.max, boxB) & ((inB & 0x70) == 0x70);
#else
    for (std::uint32_t ca : childrenA) {
      const AabbNode& childA = m_nodesA[ca];
      *top = {ca, pair.b};
      top += overlaps(childA.min, childA.max, boxB) &
             overlaps(nb.min, nb.max, m_intoB.carry(childA.min, childA.max));
    }
#endif
    tests += 2;
    return top;
  }

  /// Asks for the two nodes of `pair` to be brought into the cache.
  void prefetchPair(const NodePair& pair) const {
    prefetch(m_nodesA + pair.a);
    prefetch(m_nodesB + pair.b);
  }

  /// Runs the depth-first descent below `start` (already known to overlap) to the end. `stack` starts with
  /// stackBound() entries or more and grows if the lookahead needs more.
  ///
  /// The descent reads nodes in a data-dependent order, and a node popped right after it was pushed had had
  /// no time to arrive: the loads of the two nodes and their far children were the traversal's largest cost.
  /// So a popped pair first waits in a small ring of kLookahead pairs, its nodes asked for when it enters,
  /// and is expanded when it leaves, kLookahead expansions later. The order of the expansions changes, not
  /// the set of pairs tested, and the candidates are sorted at the end.
  GPUCOL_AVX2_CLONES void run(const NodePair& start, std::vector<NodePair>& stack,
                              std::vector<TrianglePair>& out, std::uint64_t& tests) const {
    NodePair ring[kLookahead];
    std::size_t head = 0, waiting = 0;
    if (stack.size() < 5) stack.resize(5);
    NodePair* base = stack.data();
    NodePair* top = base;
    // The last position from which four more entries fit; kept in a register with the count of tests, where
    // the vector's size and the caller's counter would be loaded from memory again after every store.
    NodePair* roomForFour = base + (stack.size() - 4);
    std::uint64_t localTests = 0;
    *top++ = start;
    for (;;) {
      while (waiting < kLookahead && top != base) {
        const NodePair entering = *--top;
        prefetchPair(entering);
        ring[(head + waiting) % kLookahead] = entering;
        ++waiting;
      }
      if (waiting == 0) break;
      const NodePair pair = ring[head];
      head = (head + 1) % kLookahead;
      --waiting;
      // With pairs waiting in the ring the descent follows several paths at once, so stackBound() no longer
      // bounds the stack: it grows (doubling) when four more entries might not fit.
      if (top > roomForFour) {
        const std::size_t used = static_cast<std::size_t>(top - base);
        stack.resize(2 * stack.size());
        base = stack.data();
        top = base + used;
        roomForFour = base + (stack.size() - 4);
      }
      top = expand(pair, top, out, localTests);
    }
    tests += localTests;
  }

 private:
  /// Two overlapping leaves. Leaves of one triangle are the thesis's case: the leaf box is the triangle box,
  /// so the pair is a candidate. Leaves of several triangles test their triangles' boxes, so that every leaf
  /// size gives the same candidates as one triangle per leaf.
  void emitLeafPair(const AabbNode& na, const AabbNode& nb, std::vector<TrianglePair>& out,
                    std::uint64_t& tests) const {
    if (na.count == 1 && nb.count == 1) {
      out.push_back({na.first, nb.first});
      return;
    }
    for (std::uint32_t j = 0; j < nb.count; ++j) {
      const LeafTriangle triangleB = leafTriangle(nb, m_entriesB, j);
      const CarriedBox boxB = m_intoA.carry(triangleB.lo, triangleB.hi);
      for (std::uint32_t i = 0; i < na.count; ++i) {
        const LeafTriangle triangleA = leafTriangle(na, m_entriesA, i);
        ++tests;
        if (overlaps(triangleA.lo, triangleA.hi, boxB) &&
            overlaps(triangleB.lo, triangleB.hi, m_intoB.carry(triangleA.lo, triangleA.hi))) {
          out.push_back({triangleA.triangle, triangleB.triangle});
        }
      }
    }
  }

  /// The box and index of the i-th triangle of a leaf: a leaf of one triangle has the triangle's box, a leaf
  /// of several an entry per triangle.
  struct LeafTriangle {
    const float* lo;
    const float* hi;
    std::uint32_t triangle;
  };
  static LeafTriangle leafTriangle(const AabbNode& leaf, const AabbLeafEntry* entries, std::uint32_t i) {
    if (leaf.count == 1) return {leaf.min, leaf.max, leaf.first};
    const AabbLeafEntry& entry = entries[leaf.first + i];
    return {entry.min, entry.max, entry.triangle};
  }

  const AabbNode* m_nodesA;
  const AabbNode* m_nodesB;
  const AabbLeafEntry* m_entriesA;
  const AabbLeafEntry* m_entriesB;
  const BoxCarrier& m_intoA;  // B's boxes into A's frame
  const BoxCarrier& m_intoB;  // A's boxes into B's frame
};

/// A growable array whose entries are left uninitialised until written: the breadth-first front (a
/// std::vector::resize zero-filled four times the front per level, about a third of the serial part) and the
/// sort's buffers.
template <class T>
class ScratchArray {
 public:
  /// Room for at least n entries; the previous contents are not kept.
  T* reserve(std::size_t n) {
    if (n > m_capacity) {
      m_data.reset(new T[n]);
      m_capacity = n;
    }
    return m_data.get();
  }
  /// The entries.
  T* data() const { return m_data.get(); }

 private:
  std::unique_ptr<T[]> m_data;
  std::size_t m_capacity = 0;
};

/// sortPairs' buffers: the packed keys, the radix sort's second array, its digit counters.
struct SortScratch {
  ScratchArray<std::uint64_t> keys, moved;
  ScratchArray<std::uint32_t> counts;
};

/// What each worker thread keeps between the front's pairs.
struct WorkerState {
  std::vector<NodePair> stack;
  std::vector<TrianglePair> out;
  std::uint64_t tests = 0;
};

/// Bits needed to write every index below `count`.
int indexBits(std::size_t count) {
  if (count <= 1) return 0;
  int bits = 0;
  while (bits < 64 && (count - 1) >> bits != 0) ++bits;
  return bits;
}

/// Widest digit of the radix sort: 8192 counters per pass (32 KB). The key's bits are split into as few
/// passes as digits of this width allow, and then into digits of even width, as narrow as those passes
/// permit: 30-bit keys (two meshes of up to 32K triangles) take three passes of 10 bits, 38-bit keys (two of
/// 400K) three of 13. A fixed width of 11 bits costs the 38-bit keys a fourth pass, a fixed 13 slows the 30-bit
/// keys (measurement history, "Figures moved from code comments").
constexpr unsigned kMaxRadixBits = 13;

/// Below this many pairs a comparison sort is cheaper than clearing the radix counters.
constexpr std::size_t kRadixMinimum = 256;

/// Sorts pairs by (triangleA, triangleB). Each pair is packed into one integer key, triangleA above the bits
/// that triangleB needs, so the key order is the pair order; the radix sort of sorting/radix_sort.h on digits
/// of up to kMaxRadixBits then costs a few linear passes instead of n log n comparisons (the pairs of one
/// query are tens of thousands, the comparison sort was a sixth of the query).
void sortPairs(std::vector<TrianglePair>& pairs, std::size_t trianglesA, std::size_t trianglesB) {
  const std::size_t n = pairs.size();
  if (n < kRadixMinimum) {
    // Sorted as packed integers on the stack: one comparison of two words instead of two branches per pair.
    std::uint64_t keys[kRadixMinimum];
    for (std::size_t i = 0; i < n; ++i)
      keys[i] = (std::uint64_t{pairs[i].triangleA} << 32) | pairs[i].triangleB;
    std::sort(keys, keys + n);
    for (std::size_t i = 0; i < n; ++i) {
      pairs[i] = {static_cast<std::uint32_t>(keys[i] >> 32), static_cast<std::uint32_t>(keys[i])};
    }
    return;
  }
  const int bitsB = indexBits(trianglesB);
  const int totalBits = indexBits(trianglesA) + bitsB;  // at most 64: both counts fit 32 bits
  const RadixDigits digits(unsigned(totalBits), kMaxRadixBits);

  // The calling thread's buffers, kept from call to call (the sort starts no parallel work, so a thread is in
  // one sort at a time); uninitialised, every key is written before it is read.
  thread_local SortScratch scratch;
  std::uint64_t* const keyBuffer = scratch.keys.reserve(n);
  std::uint64_t* const scratchBuffer = scratch.moved.reserve(n);
  std::uint32_t* const counts = scratch.counts.reserve(digits.buckets());
  for (std::size_t i = 0; i < n; ++i) {
    keyBuffer[i] = (std::uint64_t{pairs[i].triangleA} << bitsB) | pairs[i].triangleB;
  }
  const std::uint64_t* keys = radixSort(keyBuffer, scratchBuffer, n, 0, digits, counts);
  const std::uint64_t maskB = bitsB == 0 ? 0 : (~std::uint64_t{0} >> (64 - bitsB));
  for (std::size_t i = 0; i < n; ++i) {
    pairs[i] = {static_cast<std::uint32_t>(keys[i] >> bitsB), static_cast<std::uint32_t>(keys[i] & maskB)};
  }
}

/// Merges sorted lists into `out`, which may be one of them: each list in turn into the result so far.
void mergeSorted(const std::vector<std::vector<TrianglePair>*>& lists, std::vector<TrianglePair>& out) {
  std::vector<TrianglePair> merged, next;
  for (const std::vector<TrianglePair>* list : lists) {
    next.resize(merged.size() + list->size());
    std::merge(merged.begin(), merged.end(), list->begin(), list->end(), next.begin());
    merged.swap(next);
  }
  out.swap(merged);
}

/// The traversal below the root pair (known to overlap): serial, or breadth-first until the front is large
/// enough and then in parallel. Compiled for AVX2 and baseline x86-64 (bvh/avx2_clones.h), as is
/// Traverser::run, which it calls.
GPUCOL_AVX2_CLONES void traverseFromRoot(const AabbTree& a, const AabbTree& b, const Traverser& traverser,
                                         std::vector<TrianglePair>& out, std::uint64_t& tests,
                                         bool parallel) {
  const NodePair root{0, 0};
  const std::size_t bound = stackBound(a, b);
  if (!parallel || std::min(a.triangleCount(), b.triangleCount()) < kParallelTriangles) {
    std::vector<NodePair> stack(bound);
    traverser.run(root, stack, out, tests);
  } else {
    // Breadth-first until the front holds enough independent pairs (thesis §5.4.2 expands level by level
    // too), then each worker finishes its share depth first with its own stack and output.
    ScratchArray<NodePair> frontBuffer, nextBuffer;
    frontBuffer.reserve(1)[0] = root;
    std::size_t frontSize = 1;
    const std::size_t parallelFront =
        kFrontPerThread * static_cast<std::size_t>(std::max(1, tbb::this_task_arena::max_concurrency()));
    while (frontSize != 0 && frontSize < parallelFront) {
      const NodePair* const front = frontBuffer.data();
      NodePair* const next = nextBuffer.reserve(4 * frontSize);
      NodePair* top = next;
      for (std::size_t i = 0; i < frontSize; ++i) {
        if (i + kLookahead < frontSize) traverser.prefetchPair(front[i + kLookahead]);
        top = traverser.expand(front[i], top, out, tests);
      }
      frontSize = static_cast<std::size_t>(top - next);
      std::swap(frontBuffer, nextBuffer);
    }
    const NodePair* const front = frontBuffer.data();
    if (frontSize != 0) {
      tbb::enumerable_thread_specific<WorkerState> workers;
      tbb::parallel_for(tbb::blocked_range<std::size_t>(0, frontSize, kParallelGrain),
                        [&](const tbb::blocked_range<std::size_t>& range) {
                          WorkerState& w = workers.local();
                          if (w.stack.size() < bound) w.stack.resize(bound);
                          for (std::size_t i = range.begin(); i != range.end(); ++i) {
                            traverser.run(front[i], w.stack, w.out, w.tests);
                          }
                        });
      // Each list (the breadth-first levels' and each worker's) is sorted on its own, the lists in parallel,
      // and then merged: the sort was serial with the other threads idle.
      std::vector<std::vector<TrianglePair>*> lists{&out};
      for (WorkerState& w : workers) {
        lists.push_back(&w.out);
        tests += w.tests;
      }
      tbb::parallel_for(std::size_t(0), lists.size(),
                        [&](std::size_t i) { sortPairs(*lists[i], a.triangleCount(), b.triangleCount()); });
      mergeSorted(lists, out);
      return;
    }
  }
  sortPairs(out, a.triangleCount(), b.triangleCount());
}

/// The roots' boxes overlap in both frames.
bool rootsOverlap(const AabbTree& a, const AabbTree& b, const BoxCarrier& intoA, const BoxCarrier& intoB) {
  const AabbNode& rootA = a.node(0);
  const AabbNode& rootB = b.node(0);
  return overlaps(rootA.min, rootA.max, intoA.carry(rootB.min, rootB.max)) &&
         overlaps(rootB.min, rootB.max, intoB.carry(rootA.min, rootA.max));
}

}  // namespace

BoxMap boxMapIntoA(const AabbTree& b, const AffineMap& bToA, const Eigen::Vector3f& reachInA) {
  return {bToA, carriedBoxInflation(b, bToA) + reachInA};
}

BoxMap boxMapIntoB(const AabbTree& a, const AffineMap& bToA, const Eigen::Vector3f& reachInB) {
  const Eigen::Matrix3d inverse = bToA.linear.cast<double>().inverse();
  BoxMap out;
  out.map.linear = inverse.cast<float>();
  out.map.translation = (-(inverse * bToA.translation.cast<double>())).cast<float>();
  out.inflation = carriedBoxInflation(a, out.map) + reachInB;
  if (!out.map.linear.allFinite() || !out.map.translation.allFinite() || !out.inflation.allFinite()) {
    out.map = AffineMap();
    out.map.linear.setZero();
    out.inflation.setConstant(std::numeric_limits<float>::infinity());
  }
  return out;
}

bool rootBoxesOverlap(const AabbTree& a, const AabbTree& b, const AffineMap& bToA, const CandidateReach& reach) {
  return rootsOverlap(a, b, BoxCarrier(boxMapIntoA(b, bToA, reach.inA)),
                      BoxCarrier(boxMapIntoB(a, bToA, reach.inB)));
}

Eigen::Vector3f carriedBoxInflation(const AabbTree& b, const AffineMap& bToA) {
  const Eigen::Vector3f rootMin = b.rootMin().cwiseAbs();
  const Eigen::Vector3f rootMax = b.rootMax().cwiseAbs();
  // Every node of B lies in the root box, so |c| + e <= R_B on each of B's axes.
  const float radius = rootMin.cwiseMax(rootMax).maxCoeff();
  const Eigen::Vector3f rowAbsSum = bToA.linear.cwiseAbs().rowwise().sum();
  return kCarryRelativeEpsilon * (rowAbsSum * radius + bToA.translation.cwiseAbs());
}

void findCandidatePairs(const AabbTree& a, const AabbTree& b, const AffineMap& bToA,
                        std::vector<TrianglePair>& out, TraversalStats* stats, bool parallel,
                        const CandidateReach& reach) {
  out.clear();
  const BoxCarrier intoA(boxMapIntoA(b, bToA, reach.inA));
  const BoxCarrier intoB(boxMapIntoB(a, bToA, reach.inB));
  const Traverser traverser(a, b, intoA, intoB);

  std::uint64_t tests = 1;
  if (!rootsOverlap(a, b, intoA, intoB)) {
    if (stats) stats->nodeTests += tests;
    return;
  }

  // Each triangle sits in exactly one leaf and each leaf pair is reached along one path, so there are no
  // duplicates; only the order depends on the traversal, and the sort in traverseFromRoot makes it
  // independent of the threads.
  traverseFromRoot(a, b, traverser, out, tests, parallel);
  if (stats) stats->nodeTests += tests;
}

}  // namespace gpucol
