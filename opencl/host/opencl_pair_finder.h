#pragma once

#include <cstdint>
#include <memory>

#include "broadphase/grid_choice.h"
#include "broadphase/grid_pair_finder.h"
#include "gpucol/config.h"

namespace gpucol::opencl {

/// Launch shapes and buffer policy of the OpenCL pair finder; the defaults are chosen from the device. Tests
/// set them to run the GPU shapes on a CPU device and the other way round.
struct OpenClPairFinderTuning {
  /// Candidates each work-item of grid_test_candidates takes; 0: 1 on a GPU, a long run on a CPU device.
  std::uint32_t candidatesPerItem = 0;
  /// Whether the device buffers a search needs only while it runs are freed as soon as it is done with
  /// them: binning's intermediates before the candidates are tested, the rest after the search, and the
  /// boxes too when no grid is kept for the next search (stage 11's kept grid stays). Auto: where the
  /// device's memory is the host's (OpenClContext::sharesHostMemory), so that between steps the broad phase
  /// holds about what its CPU path holds; a discrete GPU keeps and reuses them (its memory is not the
  /// host's, and allocating it afresh every step costs driver calls). The finder's host lists are freed
  /// after every search whatever this says.
  enum class BufferRelease { Auto, Always, Never };
  BufferRelease release = BufferRelease::Auto;
  /// Whether the kernels read the boxes in the caller's records (BoxRecords: GridBroadphase's proxies) where
  /// they can, instead of a copy of every box on the device: where the device's memory is the host's, and the
  /// records lie end to end (contiguousBytes) with their filters, at an address the device takes as its own
  /// (CL_DEVICE_MEM_BASE_ADDR_ALIGN). Otherwise, and always on a discrete GPU, the boxes are copied.
  bool recordsInPlace = true;
  /// Whether, on a dense grid (sortsByCounting) with at least two thirds of its cells filled, every cell is
  /// a run (empty ones have no candidates) rather than the filled cells being listed: less memory, and two
  /// passes over the cells fewer (a count of the filled cells instead of their marks, scan and list). False:
  /// always the list (the tests run both).
  bool runsAreCells = true;
};

/// Stage 5 on the device: whether the finder sorts the entries of a grid of `cells` cells holding `binned`
/// boxes by a counting sort over the cells (each cell's count, scanned, then each entry placed by an atomic
/// increment) rather than by the radix sort of (cell, slot) keys.
/// - Up to 2^19 cells, for speed: counting wins while its counters and entries stay in a CPU device's caches
///   (on PoCL it took less time at 100K and 300K boxes; measurement history).
/// - Beyond, for memory, while cells <= 1.5 x binned: at its peak counting holds 8 bytes per cell and per run
///   and 4 per entry, the radix sort 24 per entry, and there are at least as many entries as boxes and as
///   runs. At 1M boxes (about 10^6 cells) that took the OpenCL step's peak from 150 to 99 bytes per proxy,
///   in the same time (measurement history).
/// - Never past a 32-bit cell index, which the counting kernels use.
inline bool sortsByCounting(std::uint64_t cells, std::size_t binned) {
  return cells <= denseCellLimit(binned) && cells < 0xffffffffu &&
         (cells <= (std::uint64_t(1) << 19) || 2 * cells <= 3 * std::uint64_t(binned));
}

/// Stage 6 on a dense grid (sortsByCounting) of `cells` cells, `filled` of which hold an entry: whether every
/// cell is taken as a run of entries, empty ones too, rather than the filled cells being listed. Where at
/// least two thirds are filled that holds less: 4 bytes per cell for the runs' candidate counts, beside the
/// counting sort's 4 per cell that then serve as the runs' first entries, where listing holds 8 per cell and
/// 8 per run while the list is made and 12 per run after.
inline bool runsAreCells(std::uint64_t cells, std::uint64_t filled) {
  return 2 * cells <= 3 * filled;
}

/// The grid pair finder of plugin/src/broadphase/grid_pair_finder.h on an OpenCL device: the host
/// chooses the grid (stages 0–3), kernels do the rest (grid_find_pairs.cl, scan.cl, radix_sort.cl).
/// Same pairs as the CPU finder, in the same (sorted) order; keeps its grid on the device while few proxies
/// move (stage 11). Returns nullptr when OpenCL is not usable
/// (said once on stderr by OpenClContext::tryGet); throws OpenClError when setup fails on a usable device.
std::unique_ptr<PairFinder> makePairFinder(const Config& config, const OpenClPairFinderTuning& tuning = {});

}  // namespace gpucol::opencl
