#include "broadphase/quiet_boxes.h"

#include <algorithm>

#include "broadphase/grown_box_pairs.h"
#include "broadphase/query_grid.h"

namespace gpucol {

void QuietBoxes::takeSlacks(const std::vector<std::uint32_t>& slots, const std::int32_t* group,
                            const std::int32_t* mask, std::uint32_t hugeCellLimit) {
  m_buildScratch = 0;
  if (slots.empty()) return;
  // The cap: half the box's growth. Two boxes whose grown boxes both miss the other are apart by more than
  // the larger growth on some axis, so their two slacks together never close the gap.
  for (std::uint32_t s : slots) m_slack[s] = 0.5f * (grownBox(m_boxes[s]).hi[0] - m_boxes[s].hi[0]);
  // The query grid reads the boxes where they are kept, as records of one block.
  const unsigned char* block = reinterpret_cast<const unsigned char*>(m_boxes.data());
  ProxyArrays p;
  p.count = std::uint32_t(m_boxes.size());
  p.records.blocks = &block;
  p.records.blockBits = 31;
  p.records.stride = sizeof(BoxCorners);
  p.records.minOffset = offsetof(BoxCorners, lo);
  p.records.maxOffset = offsetof(BoxCorners, hi);
  QueryGrid grid;
  grid.build(p, slots, hugeCellLimit);
  std::vector<std::uint32_t> near;
  std::size_t nearBytes = 0;
  bool named = true;
  for (std::uint32_t s : slots) {
    const BoxCorners g = grownBox(m_boxes[s]);
    near.clear();
    if (!grid.boxCandidates(g.lo, g.hi, slots.size(), near)) {
      named = false;  // a region of more cells than boxes: the grid cannot name this box's neighbours
      break;
    }
    nearBytes = std::max(nearBytes, near.capacity() * sizeof(std::uint32_t));
    const BoxCorners& a = m_boxes[s];
    for (std::uint32_t t : near) {
      // Both boxes of a pair take its margin, from either side: a smaller box's grown box may miss the other.
      if (t == s || (group[s] & mask[t]) == 0 || (group[t] & mask[s]) == 0) continue;
      const BoxCorners& b = m_boxes[t];
      bool overlap = true;
      for (int axis = 0; axis < 3; ++axis)
        overlap = overlap && a.lo[axis] <= b.hi[axis] && b.lo[axis] <= a.hi[axis];
      const float slack = pairSlack(a, b, overlap);
      m_slack[s] = std::min(m_slack[s], slack);
      m_slack[t] = std::min(m_slack[t], slack);
    }
  }
  m_buildScratch = std::max(grid.buildPeakBytes(), grid.memoryBytes() + nearBytes);
  if (!named) {
    m_buildScratch += bytes();  // freed here, but there at the peak
    clear();
    return;
  }
  m_kept = true;
}

bool QuietBoxes::holds(std::uint32_t s, const float lo[3], const float hi[3]) const {
  if (s >= m_slack.size()) return false;
  const BoxCorners now{{lo[0], lo[1], lo[2]}, {hi[0], hi[1], hi[2]}};
  return cornerMove(now, m_boxes[s]) < m_slack[s];  // false for a slot not taken (slack -1) and for NaN
}

void QuietBoxes::clear() {
  m_kept = false;
  std::vector<BoxCorners>().swap(m_boxes);
  std::vector<float>().swap(m_slack);
}

std::size_t QuietBoxes::bytes() const {
  return m_boxes.capacity() * sizeof(BoxCorners) + m_slack.capacity() * sizeof(float);
}

}  // namespace gpucol
