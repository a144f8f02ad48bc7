#pragma once
// The pair-finding stage of the grid broad phase (Avril et al. 2012, §3–§4) on plain types: AABBs in,
// the sorted list of overlapping proxy pairs out. GridBroadphase (plugin/src/bullet) owns the Bullet side;
// this file is the seam where the CPU implementation and the OpenCL one (opencl/host, built in with
// GPUCOL_WITH_OPENCL) plug in, and the contract both must meet bit for bit.
//
// The stages, which the OpenCL kernels mirror one to one:
//  0. Active proxies: slots with kProxyActive set; the rest are holes left by destroyed proxies.
//  1. Path choice: fewer than Options::bruteForceBelow active proxies → every pair of the active list goes
//     through the mapping function (pair_mapping.h) with no grid (paper §3, Table 7).
//  2. Cell size (§4.1): CellSizeRule::Size = kSizeFactor × median of the objects' largest extent;
//     CellSizeRule::Density = cbrt(kObjectsPerCell × volume of the scene / count), the paper's rule. Cells
//     are cubes; the grid's origin is the min corner of all boxes. When a grid would need more than 2^21
//     cells along an axis or 2^32 cells in all, the cell is enlarged (coarser, never inexact).
//  3. Huge objects: a box that covers more than Options::hugeCellLimit cells stays out of the grid and is
//     tested against every other active proxy (brute force), so one huge ground box does not fill the grid.
//  4. Keys (§4.2): each other box goes into every cell it overlaps; cell coordinate of x on an axis is
//     cellOf(x) = clamp(floor((x - origin) * invCell), 0, dim-1) in float, a monotone function, and the cell
//     index is cx + dimX*(cy + dimY*cz). One 64-bit key per (cell, proxy): (cell << 32) | proxy. Count
//     first (cells per box, exclusive prefix sum), then allocate and fill: no capacity to overflow.
//  5. Sort the keys by cell: a parallel counting sort over cells when the grid is dense (cells <= 8 × boxes
//     + 1024), else tbb::parallel_sort of (cell, proxy) keys. Equal cells become runs; the order inside a
//     run does not matter (pairs are keyed by slot and sorted in stage 10).
//  6. Per-cell counts: a run of m proxies holds m(m-1)/2 candidate pairs; an exclusive prefix sum over the
//     runs numbers every candidate globally, k in [0, total).
//  7. Mapping function: candidate k → its run (binary search in the prefix sum) → local index → (i, j) in
//     the run by gpucol_pair_from_index (on the CPU once per chunk, then stepped; on a GPU once per item).
//  8. AABB test + filter: overlap on all three axes with touching counting (min <= other max);
//     (groupA & maskB) && (groupB & maskA), Bullet's default test (the caller gives masks of -1 where a cache's
//     own filter decides).
//  9. Dedupe: two boxes share every cell around their overlap; the pair is reported only by the run whose
//     cell holds the overlap's min corner, i.e. cellOf(max(minA, minB)) on each axis == the run's cell.
// 10. Output: set bits in a bit mask over the candidates (§3.4) or append to per-chunk lists (compacted);
//     either way the pair keys are gathered and sorted, so the order never depends on threads or device.
//
// The CPU finder runs stages 3-9 of a full search slab by slab (slab_search.h, with the same pairs); the
// stages above describe the whole-grid search that the OpenCL finder mirrors. Its stage 3 and the grid's
// bounds may come from the caller's own pass over the boxes (ProxyArrays::survey).
//
// 11. Resting proxies (both finders, "skip what a scene does not need"; the OpenCL one keeps its grid on the
//     device): when ProxyArrays::moved says which slots changed since this finder's previous search and few
//     did, the grid of that search is kept:
//     proxies unchanged since it was built (static or sleeping) are not re-binned and not tested among
//     themselves (their pairs are carried over from the previous result, the caller's copy when
//     ProxyArrays::lastPairs gives it); only moved proxies are binned (on the kept grid) and tested against
//     the kept cells, the kept huge boxes and each other. Same pairs, same order.
//
// Pair key: (std::uint64_t(lower slot) << 32) | higher slot. Slots are the indices into ProxyArrays.
#include <cstdint>
#include <cstring>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "broadphase/packed_pairs.h"
#include "gpucol/config.h"

namespace gpucol {

/// Flag bit of ProxyArrays::flags: the slot holds a live proxy.
constexpr std::uint8_t kProxyActive = 1u;
/// Flag bit of ProxyArrays::flags: the proxy has Bullet's static group (counted; its pairs follow the masks alone).
constexpr std::uint8_t kProxyStatic = 2u;

/// The min and max corners of one box.
struct BoxCorners {
  float lo[3];
  float hi[3];
};

/// BoxRecords offset of a field the records do not hold.
constexpr std::uint32_t kNoRecordField = ~std::uint32_t(0);

/// Boxes kept in the caller's own records instead of six arrays (GridBroadphase's proxies, so that no copy of
/// every box is made for the CPU finder): slot s's record starts at blocks[s >> blockBits] + (s mod
/// 2^blockBits) * stride bytes and holds the min corner as three floats at byte minOffset and the max corner
/// at maxOffset.
struct BoxRecords {
  const unsigned char* const* blocks = nullptr;
  std::uint32_t blockBits = 0;  // below 32
  std::uint32_t stride = 0;
  std::uint32_t minOffset = 0;
  std::uint32_t maxOffset = 0;
  /// Optional: where the record holds the slot's filter group and mask as int32 (the same values as
  /// ProxyArrays::group and mask); kNoRecordField where it does not.
  std::uint32_t groupOffset = kNoRecordField;
  std::uint32_t maskOffset = kNoRecordField;
  /// Optional: the bytes from blocks[0] over which the blocks lie end to end (block i starts at blocks[0] + i
  /// * (stride << blockBits) for every block that starts below it); 0 where unknown. A device that shares the
  /// host's memory reads the records there in place.
  std::size_t contiguousBytes = 0;
};

/// Boxes ahead of the one read whose record is prefetched (ProxyArrays::prefetchBox) where slots are read
/// far apart (a slab's boxes in Bullet's proxies). Walks over every slot in order gained nothing from it.
constexpr std::size_t kBoxPrefetchAhead = 16;

struct BoxSurvey;  // grid_choice.h

/// Structure-of-arrays view of every proxy slot, the boxes in six arrays or in the caller's records (the pair
/// finder reads it, never writes it, but for taking a survey's arrays).
struct ProxyArrays {
  /// Number of slots (live proxies and holes); every array below has this many entries.
  std::uint32_t count = 0;
  /// AABB min corner per axis.
  const float* minX = nullptr;
  /// AABB min corner, y.
  const float* minY = nullptr;
  /// AABB min corner, z.
  const float* minZ = nullptr;
  /// AABB max corner, x.
  const float* maxX = nullptr;
  /// AABB max corner, y.
  const float* maxY = nullptr;
  /// AABB max corner, z.
  const float* maxZ = nullptr;
  /// Collision filter group (Bullet's m_collisionFilterGroup).
  const std::int32_t* group = nullptr;
  /// Collision filter mask (Bullet's m_collisionFilterMask).
  const std::int32_t* mask = nullptr;
  /// kProxyActive | kProxyStatic bits per slot.
  const std::uint8_t* flags = nullptr;
  /// Optional: nonzero for a slot whose box, filter or flags changed (or that is new) since the previous
  /// findPairs call on the same finder. nullptr: anything may have changed (a full search).
  const std::uint8_t* moved = nullptr;
  /// Optional: the pair keys that the same finder returned from its previous findPairs call, kept coded and
  /// unchanged by the caller (GridBroadphase keeps them for its diff with the pair cache). Given, a finder
  /// that carries pairs over (stage 11) reads them here and keeps no copy of its own until the next call;
  /// a later call without them is then a full search. nullptr: the finder keeps what it needs itself.
  const PackedPairs* lastPairs = nullptr;
  /// Optional, in place of minX..maxZ (then nullptr): the boxes in the caller's records. Only a finder whose
  /// readsBoxRecords() is true accepts them.
  BoxRecords records;
  /// Optional: what the caller's own pass over every box found for the grid choice, asked for with
  /// PairFinder::surveyWanted. The finder may take its arrays (they are then left empty).
  BoxSurvey* survey = nullptr;

  /// The box of slot s, from the six arrays or from the records.
  BoxCorners box(std::uint32_t s) const {
    if (minX) return BoxCorners{{minX[s], minY[s], minZ[s]}, {maxX[s], maxY[s], maxZ[s]}};
    const unsigned char* r = record(s);
    // Float by float: a 12-byte copy per corner became 8 + 4-byte stores that callers then reloaded as one
    // 16-byte vector, which cannot be forwarded from the stores: every box read in place stalled (measurement
    // history).
    BoxCorners b;
    for (int a = 0; a < 3; ++a) {
      std::memcpy(&b.lo[a], r + records.minOffset + a * sizeof(float), sizeof(float));
      std::memcpy(&b.hi[a], r + records.maxOffset + a * sizeof(float), sizeof(float));
    }
    return b;
  }
  /// Asks the cache for slot s's box ahead of box(s) when it lies in a record; the six arrays, read in slot
  /// order, are followed by the hardware prefetcher already. Always inlined: GCC otherwise finds the call
  /// free of effects and deletes it.
  __attribute__((always_inline)) void prefetchBox(std::uint32_t s) const {
    if (minX) return;
    const unsigned char* r = record(s);
    __builtin_prefetch(r + records.minOffset);
    __builtin_prefetch(r + records.maxOffset + 2 * sizeof(float));
  }
  /// The start of slot s's record (with records only).
  __attribute__((always_inline)) const unsigned char* record(std::uint32_t s) const {
    return records.blocks[s >> records.blockBits] +
           std::size_t(s & ((1u << records.blockBits) - 1)) * records.stride;
  }
};

/// How the grid's cell size is chosen (paper §4.1 and the alternative it is measured against).
enum class CellSizeRule { Size, Density };

/// How candidate results are written before the final sort (paper §3.4 bit mask, or a compacted list).
enum class PairOutput { BitMask, Compacted };

/// Square root used for the mapping function's first guess (paper §3.3); results are identical.
enum class MappingSqrt { Double, Newton };

/// Whether the CPU finder searches a dense grid slab by slab (slab_search.h); results are identical.
/// Auto: full searches with compacted output, of at most kMaxSlabBoxes binned boxes, when the grid cuts into
/// at least kMinSlabs slabs (any number in a scene of fewer than kAnySlabsBelow binned boxes); a grid kept
/// for stage 11 is then binned after the search (its cells and entries only). AnySize: as Auto with no limit
/// on the boxes (less memory at the peak than the whole-grid search; GridBroadphase asks for it where it
/// reads the boxes in Bullet's proxies). Always: every full search of a dense grid with compacted output
/// (tests). Off: never (tests: the whole-grid search, which sparse grids and the bit mask take anyway).
enum class SlabTiling { Auto, AnySize, Always, Off };

/// How a slab search's thread reads the boxes of its slab (slab_search.h); results are identical. Copy: into
/// an array of LocalBox in slab order (each slab's boxes together; the scene's proxies do not stay in the
/// cache of a large scene). InPlace: where they are, by slot (no copy). Auto: in place in a scene of a few
/// thousand boxes (whose proxies stay in the cache anyway) when the copies that the threads' largest slabs
/// would hold at once come to more than a few bytes per binned box.
enum class SlabBoxReading { Auto, Copy, InPlace };

/// A box covering more cells than this is tested against all instead of being binned (stage 3; chosen in
/// docs/measured-results.md, "Grid choice").
constexpr std::uint32_t kHugeCellLimit = 64;

/// Knobs of one pair search.
struct PairFinderOptions {
  /// Below this many active proxies all pairs are tested without a grid (Config::bruteForceBelow).
  std::uint32_t bruteForceBelow = 128;
  /// Cell size rule of the grid.
  CellSizeRule cellSizeRule = CellSizeRule::Size;
  /// Output form of the candidate tests.
  PairOutput output = PairOutput::Compacted;
  /// Square root of the mapping function's guess.
  MappingSqrt mappingSqrt = MappingSqrt::Double;
  /// A box covering more cells than this is tested against all instead of being binned.
  std::uint32_t hugeCellLimit = kHugeCellLimit;
  /// CPU finder: slab tiling of full searches.
  SlabTiling slabTiling = SlabTiling::Auto;
  /// CPU finder: boxes per slab aimed at (0: automatic, slab_search.cpp).
  std::uint32_t slabBoxes = 0;
  /// CPU finder: how a slab search reads its boxes.
  SlabBoxReading slabBoxReading = SlabBoxReading::Auto;
};

/// What one search did (for benchmarks, tests and printStats).
struct PairFinderStats {
  /// True when the grid was used, false for the brute-force path.
  bool usedGrid = false;
  /// Cell edge length used (0 without grid).
  float cellSize = 0.0f;
  /// Cells per axis.
  std::uint32_t dims[3] = {0, 0, 0};
  /// (cell, proxy) keys written.
  std::uint64_t keys = 0;
  /// Candidate pairs tested through the mapping function (grid or brute force).
  std::uint64_t candidates = 0;
  /// Proxies kept out of the grid as huge.
  std::uint32_t hugeProxies = 0;
  /// Bytes the finder keeps after the search (until the next one).
  std::size_t scratchBytes = 0;
  /// Bytes of the finder's memory at its high-water mark in the search, before it released its scratch (0:
  /// not known; then scratchBytes is all there was).
  std::size_t peakScratchBytes = 0;
  /// True when peakScratchBytes also counts the output list (findPairs' `pairs`) as it stood at that mark:
  /// the finder's memory and its output together. False: the output is not in it, and may add its whole size.
  bool peakIncludesOutput = false;
  /// Slabs of a slab search (slab_search.h); 0 when the grid was searched whole.
  std::uint32_t slabs = 0;
  /// True when the slab plan took the binned boxes' extents along its axis from the grid choice's pass (boxes
  /// read in place, the slab axis as guessed from the last plan) instead of reading the boxes again.
  bool slabAxisKept = false;
  /// True when the slab search read its boxes in place (SlabBoxReading) instead of copying them.
  bool slabBoxesInPlace = false;
  /// True when an OpenCL finder's kernels read the boxes in ProxyArrays::records in place, with no copy of
  /// them on the device.
  bool recordsReadInPlace = false;
  /// True when an OpenCL finder's full search took every cell of its dense grid as a run of entries, empty
  /// cells too, rather than listing the filled ones (OpenClPairFinderTuning::runsAreCells).
  bool runsAreCells = false;
  /// True when the slab search paired boxes by home cell (boxes of about one size) on a grid of its own
  /// (cellSize and dims give that grid's).
  bool homeCells = false;
  /// Boxes of a search by home cell that spanned three or more of its cells on an axis and were tested, as
  /// huge boxes are, through the cells around them (counted once per slab that lists them).
  std::uint32_t wideBoxes = 0;
  /// True when the grid choice took ProxyArrays::survey (no box was read for stage 3 and the bounds).
  bool surveyTaken = false;
  /// True when the search kept the last grid and binned only moved proxies (stage 11).
  bool incremental = false;
  /// Active proxies neither re-binned nor tested among themselves in this search (stage 11).
  std::uint32_t restingProxies = 0;
  /// Active proxies binned (or, when huge, tested against all) in this search.
  std::uint32_t rebinnedProxies = 0;
  /// Wall-clock milliseconds of the stages of a full grid search (0 in an incremental one): stages 2-3
  /// (cell size, huge split), 4-6 (binning, sort by cell, runs), 7-9 (candidate tests),
  /// 3 (huge boxes against the rest) and 10 (gather and sort of the pair keys). A slab search bins and tests
  /// each slab in one go: binMs is then its planning (slab lists), testMs the slabs, huge boxes included.
  /// The OpenCL finder's are host clocks between its waits: chooseMs also holds the active list and the
  /// boxes' upload, testMs the huge boxes, sortMs the device sort, the read and the widening of the pairs.
  double chooseMs = 0, binMs = 0, testMs = 0, hugeMs = 0, sortMs = 0;
};

/// Finds every pair of active proxies whose AABBs overlap (touching counts) and pass the filters.
class PairFinder {
 public:
  virtual ~PairFinder() = default;
  /// Replaces `pairs` with the sorted, duplicate-free pair keys of `proxies`.
  virtual void findPairs(const ProxyArrays& proxies, const PairFinderOptions& options,
                         std::vector<std::uint64_t>& pairs) = 0;
  /// findPairs with the keys coded (PackedPairs, what GridBroadphase keeps). A finder whose codesPairs() is
  /// true never holds them all as 8-byte keys where it can help it; the others' default codes findPairs'
  /// list, or keeps it plain where PackedPairs::worthCoding says no (as GridBroadphase does).
  virtual void findCodedPairs(const ProxyArrays& proxies, const PairFinderOptions& options,
                              PackedPairs& pairs);
  /// True when findCodedPairs is the finder's own (its stats then count the coded list as its output).
  virtual bool codesPairs() const { return false; }
  /// Statistics of the last findPairs call.
  virtual const PairFinderStats& stats() const = 0;
  /// Short name for logs and benchmarks ("cpu", "opencl").
  virtual std::string name() const = 0;
  /// True when the search runs on a GPU (Backend::Auto hands large scenes only to such a finder).
  virtual bool runsOnGpu() const { return false; }
  /// True when the finder reads boxes from ProxyArrays::records (the six arrays may then be nullptr).
  virtual bool readsBoxRecords() const { return false; }
  /// True when the next search would take a BoxSurvey (ProxyArrays::survey) made at cell edge `cell` with
  /// `options`, with each box's extent along `axis` (-1: none); false when it has no use for one.
  virtual bool surveyWanted(const PairFinderOptions& options, float& cell, int& axis) const {
    (void)options, (void)cell, (void)axis;
    return false;
  }
};

/// The CPU implementation (oneTBB), the reference the OpenCL path must match bit for bit.
std::unique_ptr<PairFinder> makeCpuPairFinder();

/// The OpenCL pair finder for `config` (opencl/host/opencl_pair_finder.h); nullptr when gpucol was built
/// without OpenCL (GPUCOL_WITH_OPENCL) or no device is usable. Defined with the plugin's other entry into
/// the OpenCL module, bullet/opencl_backends.cpp.
std::unique_ptr<PairFinder> makeOpenClPairFinder(const Config& config);

namespace detail {
/// Fault injection for tests: the next `count` searches of OpenCL pair finders fail as a failed launch does
/// (an OpenClError), so that the broad phase's fallback to the CPU is tested where no device fails by itself.
void failNextOpenClSearches(int count);
/// Takes one injected failure (true), or says there is none left (false). Called by the OpenCL finder.
bool takeInjectedOpenClFailure();
}  // namespace detail

/// Pair key of slots a and b (either order): lower slot in the high 32 bits.
inline std::uint64_t makePairKey(std::uint32_t a, std::uint32_t b) {
  return a < b ? (std::uint64_t(a) << 32) | b : (std::uint64_t(b) << 32) | a;
}

}  // namespace gpucol
