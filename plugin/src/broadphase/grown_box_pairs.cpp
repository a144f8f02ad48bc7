#include "broadphase/grown_box_pairs.h"

#include <algorithm>
#include <limits>

namespace gpucol {

void GrownBoxPairs::build(const ProxyArrays& p) {
  m_slots.clear();
  m_grown.clear();
  m_now.clear();
  m_keys.clear(), m_first.clear(), m_second.clear(), m_overlap.clear();
  m_dense.assign(p.count, ~std::uint32_t(0));
  for (std::uint32_t s = 0; s < p.count; ++s) {
    if (!(p.flags[s] & kProxyActive)) continue;
    const BoxCorners b = p.box(s);
    const BoxCorners g = grownBox(b);
    m_dense[s] = std::uint32_t(m_slots.size());
    m_slots.push_back(s);
    m_grown.push_back(g);
    m_now.push_back(b);
  }
  for (std::uint32_t i = 0; i < m_slots.size(); ++i) {
    const std::uint32_t s = m_slots[i];
    for (std::uint32_t j = i + 1; j < m_slots.size(); ++j) {
      const std::uint32_t t = m_slots[j];
      if (overlaps(m_grown[i], m_grown[j]) && (p.group[s] & p.mask[t]) != 0 && (p.group[t] & p.mask[s]) != 0) {
        m_keys.push_back(makePairKey(s, t));
        m_first.push_back(i);
        m_second.push_back(j);
        m_overlap.push_back(overlaps(m_now[i], m_now[j]));
      }
    }
  }
  takeSlacks();
  m_kept = true;
}

bool GrownBoxPairs::retestEveryPair(std::vector<std::uint64_t>& out) {
  // Plain pointers, loaded once: the byte stores could alias the vectors' own fields otherwise.
  const BoxCorners* const now = m_now.data();
  const std::uint32_t* const first = m_first.data();
  const std::uint32_t* const second = m_second.data();
  std::uint8_t* const last = m_overlap.data();
  const std::size_t pairs = m_keys.size();
  std::uint8_t changed = 0;
  for (std::size_t k = 0; k < pairs; ++k) {
    const std::uint8_t overlap = overlaps(now[first[k]], now[second[k]]);
    changed |= std::uint8_t(overlap ^ last[k]);
    last[k] = overlap;
  }
  takeSlacks();
  if (!changed) return false;
  out.clear();
  for (std::size_t k = 0; k < pairs; ++k)
    if (last[k]) out.push_back(m_keys[k]);
  return true;
}

void GrownBoxPairs::takeSlacks() {
  m_tested = m_now;
  // Each box may move the smallest slack of its pairs.
  m_slack.assign(m_slots.size(), std::numeric_limits<float>::infinity());
  for (std::size_t k = 0; k < m_keys.size(); ++k) {
    const float slack = pairSlack(m_now[m_first[k]], m_now[m_second[k]], m_overlap[k] != 0);
    m_slack[m_first[k]] = std::min(m_slack[m_first[k]], slack);
    m_slack[m_second[k]] = std::min(m_slack[m_second[k]], slack);
  }
}

void GrownBoxPairs::clear() {
  m_kept = false;
  std::vector<std::uint32_t>().swap(m_slots);
  std::vector<std::uint32_t>().swap(m_dense);
  std::vector<BoxCorners>().swap(m_grown);
  std::vector<BoxCorners>().swap(m_now);
  std::vector<BoxCorners>().swap(m_tested);
  std::vector<float>().swap(m_slack);
  std::vector<std::uint64_t>().swap(m_keys);
  std::vector<std::uint32_t>().swap(m_first);
  std::vector<std::uint32_t>().swap(m_second);
  std::vector<std::uint8_t>().swap(m_overlap);
}

std::size_t GrownBoxPairs::bytes() const {
  return (m_slots.capacity() + m_dense.capacity() + m_first.capacity() + m_second.capacity()) *
             sizeof(std::uint32_t) +
         (m_grown.capacity() + m_now.capacity() + m_tested.capacity()) * sizeof(BoxCorners) +
         m_slack.capacity() * sizeof(float) + m_keys.capacity() * sizeof(std::uint64_t) +
         m_overlap.capacity();
}

}  // namespace gpucol
