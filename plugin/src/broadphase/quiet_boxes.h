#pragma once
// A larger scene's steps skipped while no pair can have changed: the boxes of the last search, each with a
// slack, half the smallest margin by which it overlaps or misses a box near it (within its growth, as
// GrownBoxPairs grows boxes, grown_box_pairs.h), found through a query grid of those boxes (query_grid.h). A
// box whose grown box misses another is apart from it by more than twice its slack's cap. While every box
// stays within its slack of its box at the search, no pair's overlap can have changed, and a step keeps the
// last search's pairs without searching (btDbvtBroadphase's fattened leaves absorb small moves the same way).
#include <cstddef>
#include <cstdint>
#include <vector>

#include "broadphase/grid_pair_finder.h"

namespace gpucol {

/// The boxes of one search with their slacks, and the test of a later box against them.
class QuietBoxes {
 public:
  /// Takes the boxes boxOf(s) of `slots` (ascending, each below `count`) and their slacks; a pair counts only
  /// where group[s] & mask[t] and group[t] & mask[s] are both nonzero, as in the search.
  template <class BoxOf>
  void build(std::uint32_t count, const std::vector<std::uint32_t>& slots, BoxOf&& boxOf,
             const std::int32_t* group, const std::int32_t* mask, std::uint32_t hugeCellLimit) {
    clear();
    m_boxes.assign(count, BoxCorners{});
    m_slack.assign(count, -1.0f);
    for (std::uint32_t s : slots) m_boxes[s] = boxOf(s);
    takeSlacks(slots, group, mask, hugeCellLimit);
  }
  /// Forgets the boxes: a proxy came or went, a filter changed, or a box left its slack.
  void clear();
  /// True while boxes are kept.
  bool kept() const { return m_kept; }
  /// True when the box [lo, hi] lies within slot s's slack of its box at the build (false for a slot the
  /// build did not take, or a NaN).
  bool holds(std::uint32_t s, const float lo[3], const float hi[3]) const;
  /// Bytes held.
  std::size_t bytes() const;
  /// Bytes the last build held at its peak beyond bytes() (its query grid and lists).
  std::size_t buildScratchBytes() const { return m_buildScratch; }

 private:
  void takeSlacks(const std::vector<std::uint32_t>& slots, const std::int32_t* group, const std::int32_t* mask,
                  std::uint32_t hugeCellLimit);

  bool m_kept = false;
  std::vector<BoxCorners> m_boxes;  // per slot: its box at the build
  std::vector<float> m_slack;       // per slot: how far a corner may move from m_boxes (-1: not taken)
  std::size_t m_buildScratch = 0;
};

}  // namespace gpucol
