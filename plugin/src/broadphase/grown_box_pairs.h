#pragma once
// A small scene's pairs between searches, as a Verlet list: the pairs of boxes grown by a share of their
// size. While each box stays inside its grown box, the pairs whose boxes overlap are among them, and a step
// re-tests those few pairs instead of searching every pair again (btDbvtBroadphase's fattened leaves serve
// the same end, but report the grown pairs; these are re-tested on the exact boxes).
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include "broadphase/grid_pair_finder.h"

namespace gpucol {

/// Share of a box's largest side that grownBox grows it by on every side: a resting box's jitter stays inside
/// for good, a falling one leaves after a few steps.
inline constexpr float kGrowShare = 0.125f;

/// The box grown by kGrowShare of its largest side on every side.
inline BoxCorners grownBox(const BoxCorners& b) {
  const float grow = kGrowShare * std::max({b.hi[0] - b.lo[0], b.hi[1] - b.lo[1], b.hi[2] - b.lo[2]});
  BoxCorners g = b;
  for (int a = 0; a < 3; ++a) g.lo[a] -= grow, g.hi[a] += grow;
  return g;
}

/// How far a box may move while the overlap of boxes a and b (`overlap`: whether they overlap now) cannot
/// change, the other moving as far: half the pair's margin (how far the boxes overlap on their least
/// overlapping axis, or how far apart they are on their most separated one), a hair less for the rounding of
/// the differences taken here and in cornerMove.
inline float pairSlack(const BoxCorners& a, const BoxCorners& b, bool overlap) {
  float margin;
  if (overlap) {
    margin = std::numeric_limits<float>::infinity();
    for (int axis = 0; axis < 3; ++axis)
      margin = std::min({margin, a.hi[axis] - b.lo[axis], b.hi[axis] - a.lo[axis]});
  } else {
    margin = 0;
    for (int axis = 0; axis < 3; ++axis)
      margin = std::max({margin, b.lo[axis] - a.hi[axis], a.lo[axis] - b.hi[axis]});
  }
  return 0.5f * margin * (1.0f - 1.0f / 1048576.0f);
}

/// The farthest any corner coordinate of box `now` lies from box `then`'s (NaN when a coordinate is NaN).
inline float cornerMove(const BoxCorners& now, const BoxCorners& then) {
  float moved = 0;
  for (int a = 0; a < 3; ++a)
    moved = std::max({moved, std::fabs(now.lo[a] - then.lo[a]), std::fabs(now.hi[a] - then.hi[a])});
  return moved;
}

/// The pairs of grown boxes of one search, and the test of a later step's boxes against them.
class GrownBoxPairs {
 public:
  /// Grows every active box of `p` and lists the pairs of grown boxes that pass p's group and mask test,
  /// with whether their boxes overlap now, replacing what was kept.
  void build(const ProxyArrays& p);
  /// Forgets the list: a proxy came or went, a filter changed, or a box left its grown box.
  void clear();
  /// True while a list is kept.
  bool kept() const { return m_kept; }
  /// True when the box [lo, hi] lies inside slot s's grown box (false for a slot the list does not know).
  bool holds(std::uint32_t s, const float lo[3], const float hi[3]) const {
    if (s >= m_dense.size() || m_dense[s] == ~std::uint32_t(0)) return false;
    const BoxCorners& g = m_grown[m_dense[s]];
    return g.lo[0] <= lo[0] && g.lo[1] <= lo[1] && g.lo[2] <= lo[2] && hi[0] <= g.hi[0] && hi[1] <= g.hi[1] &&
           hi[2] <= g.hi[2];
  }
  /// Tests the kept pairs on the boxes as they are now (boxOf(slot) gives a slot's box as BoxCorners;
  /// touching counts). Returns true when a pair's overlap changed since the last test (or the build), and
  /// then lists the overlapping ones in `out`, in key order; false leaves `out` alone.
  ///
  /// Each box has a slack: half the smallest margin by which any of its pairs overlapped or missed at the
  /// last test of every pair. While every box has moved less than its slack since that test, no pair can
  /// have changed, and the pairs are not tested at all (a pile at rest, whose boxes jiggle by less).
  template <class BoxOf>
  bool retest(BoxOf&& boxOf, std::vector<std::uint64_t>& out) {
    bool within = true;
    for (std::size_t i = 0; i < m_slots.size(); ++i) {
      m_now[i] = boxOf(m_slots[i]);
      within &= cornerMove(m_now[i], m_tested[i]) < m_slack[i];
    }
    if (within) return false;
    return retestEveryPair(out);
  }
  /// Bytes held.
  std::size_t bytes() const;

 private:
  // Without short-circuit branches: whether neighbours overlap is close to a coin toss in a pile.
  static std::uint8_t overlaps(const BoxCorners& a, const BoxCorners& b) {
    return std::uint8_t(int(a.lo[0] <= b.hi[0]) & int(b.lo[0] <= a.hi[0]) & int(a.lo[1] <= b.hi[1]) &
                        int(b.lo[1] <= a.hi[1]) & int(a.lo[2] <= b.hi[2]) & int(b.lo[2] <= a.hi[2]));
  }

  bool retestEveryPair(std::vector<std::uint64_t>& out);
  /// Sets m_tested to m_now and each box's slack from its pairs' margins there.
  void takeSlacks();

  bool m_kept = false;
  std::vector<std::uint32_t> m_slots;   // the active slots of the search, ascending
  std::vector<std::uint32_t> m_dense;   // per slot: its index in m_slots (~0: not active)
  std::vector<BoxCorners> m_grown;      // per index in m_slots
  std::vector<BoxCorners> m_now;        // per index in m_slots: this step's boxes (scratch of retest)
  std::vector<BoxCorners> m_tested;     // per index in m_slots: the boxes at the last test of every pair
  std::vector<float> m_slack;           // per index in m_slots: how far the box may move from m_tested
  std::vector<std::uint64_t> m_keys;    // the pairs, ascending
  std::vector<std::uint32_t> m_first, m_second;  // per pair: its boxes' indices in m_slots
  std::vector<std::uint8_t> m_overlap;  // per pair: its boxes overlapped at the last test
};

}  // namespace gpucol
