#pragma once
// The index behind the broad phase's queries (rayTest and aabbTest): the boxes filed in a dense uniform grid,
// a box no larger than a cell in the cell of its min corner (queries reach back by the largest such box),
// a larger one in every cell it overlaps, as the pair search bins them (grid_pair_finder.h, stage 4; cell size and
// huge boxes by the same choice, grid_choice.h, paper §4.1). A query then visits the cells its region
// reaches instead of every proxy. The index only names candidates, a superset of the answer (with
// repeats): the caller runs its exact test on each, so the answer is exactly what testing every box gives.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "broadphase/grid_choice.h"
#include "broadphase/grid_pair_finder.h"

namespace gpucol {

/// A region swept by a box along a segment: every point q = from + t·dir, t in [0, tMax], carries the box
/// [q + castLo, q + castHi] (a ray when both are zero). Bullet's broad-phase ray test in world units.
struct QuerySweep {
  double from[3] = {0, 0, 0};
  double dir[3] = {0, 0, 0};
  double tMax = 0;
  double castLo[3] = {0, 0, 0};
  double castHi[3] = {0, 0, 0};
};

/// A test each candidate must pass before it is named, given what the index files (the slot, or whatever id
/// the caller filed). The broad phase tests the box it filed, which holds the candidate's own: a test that is
/// monotone in the box loses nothing, and the candidates a cell names in vain are dropped before they are
/// sorted and their proxies read.
struct CandidateTest {
  bool (*test)(const void* context, std::uint32_t id) = nullptr;  ///< nullptr: every candidate passes
  const void* context = nullptr;                                  ///< handed to `test`
  /// True when candidate `id` passes (or there is no test).
  bool operator()(std::uint32_t id) const { return test == nullptr || test(context, id); }
};

/// Boxes filed by cell for queries; built on demand, dropped when the boxes change (GridBroadphase decides).
class QueryGrid {
 public:
  /// Files the boxes of `slots` of `p` (not empty); boxes covering more than `hugeCellLimit` cells go to a
  /// list every query names.
  void build(const ProxyArrays& p, const std::vector<std::uint32_t>& slots, std::uint32_t hugeCellLimit);
  /// Moves `id` (a box of the last build, filed by its min corner) to the cell of its new box [lo, hi], so
  /// that the index follows a box that moved without a rebuild: into a free place of that cell's entries
  /// (one left by a box that moved out) or, when it has none, onto the cell's overflow list. Returns false,
  /// changing nothing, when it cannot: `id` was filed in every cell it overlapped, the new box is larger than
  /// the reach queries look back by, inverted or not finite, or the overflow lists already hold as many boxes
  /// as the entries.
  bool refile(std::uint32_t id, const float lo[3], const float hi[3]);
  /// Drops the index and its memory.
  void clear();
  /// True from build until clear (false after a build whose entries would not fit 32-bit starts: then
  /// every query returns false).
  bool built() const { return m_built; }
  /// Appends every filed slot whose box may overlap [lo, hi] (touching counts); repeats are possible.
  /// Returns false, leaving `out` as it was, when that would be more than `maxCandidates` slots or more
  /// cells than there are filed boxes (testing every box is then cheaper), or the region has a NaN.
  bool boxCandidates(const float lo[3], const float hi[3], std::size_t maxCandidates,
                     std::vector<std::uint32_t>& out, const CandidateTest& keep = CandidateTest()) const;
  /// Appends every filed slot whose box the sweep may touch, allowing for the float rounding of the
  /// caller's exact test; repeats are possible. Returns false, leaving `out` as it was, when that would be
  /// more than `maxCandidates` slots or more cells than there are filed boxes, or the sweep is not finite.
  bool sweepCandidates(const QuerySweep& sweep, std::size_t maxCandidates, std::vector<std::uint32_t>& out,
                       const CandidateTest& keep = CandidateTest()) const;
  /// Bytes held (capacities).
  std::size_t memoryBytes() const;
  /// Bytes the last build held at its peak, its scratch included (capacities).
  std::size_t buildPeakBytes() const { return std::max(m_buildPeak, memoryBytes()); }

 private:
  /// Index of the cell (0, y, z): the first cell of row (y, z).
  std::uint64_t rowStart(std::uint32_t y, std::uint32_t z) const;
  /// Entries in the cells x in [x0, x1] of row (y, z).
  std::size_t rowEntries(std::uint32_t x0, std::uint32_t x1, std::uint32_t y, std::uint32_t z) const;
  /// Appends the entries of the cells x in [x0, x1] of row (y, z) that pass `keep`; returns
  /// how many entries it read.
  std::size_t appendRow(std::uint32_t x0, std::uint32_t x1, std::uint32_t y, std::uint32_t z,
                        std::vector<std::uint32_t>& out, const CandidateTest& keep) const;
  /// The cell holding point x (clamped to the grid).
  std::uint64_t cellAt(const float x[3]) const;

  /// Takes `id` out of the cell it is filed in by its min corner (m_homeCell).
  void unfile(std::uint32_t id);
  /// Files `id` by its min corner in `cell`.
  void fileHome(std::uint32_t id, std::uint32_t cell);

  static constexpr std::uint32_t kNone = 0xffffffffu;

  Grid m_grid;
  float m_lo[3] = {0, 0, 0};               // min corner of the filed boxes (refiled ones may lie beyond the
  float m_hi[3] = {0, 0, 0};               // grid's cells: cellOf clamps them into its edge cells), max corner
  double m_homeReach[3] = {0, 0, 0};       // largest extent of the boxes filed only in their min corner's cell
  // Entries by cell: cell c owns [m_cellStart[c], m_cellStart[c + 1]) of m_entries, its first
  // m_cellCount[c] places in use, the rest kNone (left by boxes that moved out).
  std::vector<std::uint32_t> m_cellStart;
  std::vector<std::uint32_t> m_cellCount;
  std::vector<std::uint32_t> m_entries;
  std::vector<std::uint32_t> m_huge;       // slots named by every query
  // Per id filed by its min corner: its cell, and its place in m_entries (kNone: on the cell's overflow
  // list); kNone for the others.
  std::vector<std::uint32_t> m_homeCell;
  std::vector<std::uint32_t> m_place;
  // The overflow lists, doubly linked through the ids (made when a box first finds its new cell full):
  // first id per cell, next and previous id per id (kNone ends a list).
  std::vector<std::uint32_t> m_overflowHead;
  std::vector<std::uint32_t> m_overflowNext;
  std::vector<std::uint32_t> m_overflowPrev;
  std::size_t m_overflowed = 0;            // ids on overflow lists
  std::size_t m_buildPeak = 0;             // buildPeakBytes of the last build with boxes to file
  bool m_built = false;
};

}  // namespace gpucol
