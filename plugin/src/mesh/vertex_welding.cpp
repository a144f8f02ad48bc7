#include "mesh/vertex_welding.h"

#include <algorithm>
#include <array>
#include <cstring>

namespace gpucol {

namespace {

/// The bit pattern of a position with -0 folded onto +0, so that exactly equal coordinates compare equal.
std::array<std::uint32_t, 3> keyOf(const float* p) {
  std::array<std::uint32_t, 3> key{};
  for (int k = 0; k < 3; ++k) {
    const float v = p[k] == 0.0f ? 0.0f : p[k];
    std::memcpy(&key[std::size_t(k)], &v, sizeof v);
  }
  return key;
}

}  // namespace

std::vector<std::uint32_t> weldEqualPositions(std::vector<float>& xyz) {
  const std::size_t count = xyz.size() / 3;
  // Vertices sorted by position, then by index, so each run of equal positions starts at its first vertex.
  std::vector<std::uint32_t> order(count);
  for (std::size_t v = 0; v < count; ++v) order[v] = std::uint32_t(v);
  std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
    const auto ka = keyOf(&xyz[3 * std::size_t(a)]), kb = keyOf(&xyz[3 * std::size_t(b)]);
    return ka != kb ? ka < kb : a < b;
  });
  // first[v]: the first vertex at v's position; `order` is reused for it.
  std::vector<std::uint32_t> first(count);
  for (std::size_t k = 0; k < count; ++k) {
    const std::uint32_t v = order[k];
    const bool sameAsPrevious =
        k > 0 && keyOf(&xyz[3 * std::size_t(order[k - 1])]) == keyOf(&xyz[3 * std::size_t(v)]);
    first[v] = sameAsPrevious ? first[order[k - 1]] : v;
  }
  order.clear();
  order.shrink_to_fit();
  // New indices in the order of first appearance; a later duplicate takes its first vertex's new index.
  std::vector<std::uint32_t>& remap = first;
  std::size_t next = 0;
  for (std::size_t v = 0; v < count; ++v) {
    if (first[v] == v) {
      for (int k = 0; k < 3; ++k) xyz[3 * next + std::size_t(k)] = xyz[3 * v + std::size_t(k)];
      remap[v] = std::uint32_t(next++);
    } else {
      remap[v] = remap[first[v]];  // first[v] < v, already renumbered
    }
  }
  xyz.resize(3 * next);
  xyz.shrink_to_fit();
  return remap;
}

}  // namespace gpucol
