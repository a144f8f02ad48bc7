#pragma once
// A binned box as the CPU grid searches copy it (next to its grid neighbours, with its filter) and the tests
// of stages 8-9 (grid_pair_finder.h) on such copies, shared by the whole-grid search and the slab search.
#include <algorithm>
#include <cstdint>
#include <cstring>
#include <limits>
#include <vector>

#include "broadphase/grid_choice.h"
#include "broadphase/grid_pair_finder.h"

namespace gpucol {

/// Runs of kLocalRunMin to kLocalRunMax boxes are tested four candidates at a time (forEachOverlapInRun).
constexpr std::uint32_t kLocalRunMin = 8;
constexpr std::uint32_t kLocalRunMax = 64;
/// Four floats, and the four lanes of a comparison of two (-1 true, 0 false): GCC/Clang vector extensions,
/// which compile to SSE on x86-64 and to scalar code where there is no vector unit.
using Float4 = float __attribute__((vector_size(16)));
using Int4 = std::int32_t __attribute__((vector_size(16)));

/// Cell ranges [lo, hi] of one box on the three axes.
struct CellRange {
  std::uint32_t lo[3];
  std::uint32_t hi[3];
  std::uint64_t count() const {
    return std::uint64_t(hi[0] - lo[0] + 1) * (hi[1] - lo[1] + 1) * (hi[2] - lo[2] + 1);
  }
};

/// A binned box copied next to its grid neighbours, with its filter, so the candidate tests read nearby
/// memory instead of nine scattered SoA arrays per proxy (perf showed the
/// filter's loads by slot, cache misses, taking about 45% of the candidate tests at 1M boxes).
struct LocalBox {
  float lo[3];
  float hi[3];
  std::uint32_t slot;
  std::int32_t group;
  std::int32_t mask;
  std::uint32_t flags;
};

/// passesFilter on local copies.
inline bool passesFilter(const LocalBox& a, const LocalBox& b) {
  return (a.group & b.mask) != 0 && (b.group & a.mask) != 0;
}

inline CellRange cellRange(const LocalBox& b, const Grid& g) {
  CellRange r;
  for (int a = 0; a < 3; ++a) {
    r.lo[a] = cellOf(b.lo[a], g.origin[a], g.invCell, g.dims[a]);
    r.hi[a] = cellOf(b.hi[a], g.origin[a], g.invCell, g.dims[a]);
  }
  return r;
}

inline LocalBox boxOf(const ProxyArrays& p, std::uint32_t s) {
  const BoxCorners b = p.box(s);
  return LocalBox{
      {b.lo[0], b.lo[1], b.lo[2]}, {b.hi[0], b.hi[1], b.hi[2]}, s, p.group[s], p.mask[s], p.flags[s]};
}

/// Touching-counts overlap of two local boxes, without short-circuit branches (see testRuns).
inline bool boxesOverlap(const LocalBox& a, const LocalBox& b) {
  return int(a.lo[0] <= b.hi[0]) & int(b.lo[0] <= a.hi[0]) & int(a.lo[1] <= b.hi[1]) &
         int(b.lo[1] <= a.hi[1]) & int(a.lo[2] <= b.hi[2]) & int(b.lo[2] <= a.hi[2]);
}

/// Stage 9: the cell that holds the min corner of the overlap of a and b.
inline std::uint32_t overlapCell(const LocalBox& a, const LocalBox& b, const Grid& g) {
  const std::uint32_t cx = cellOf(std::max(a.lo[0], b.lo[0]), g.origin[0], g.invCell, g.dims[0]);
  const std::uint32_t cy = cellOf(std::max(a.lo[1], b.lo[1]), g.origin[1], g.invCell, g.dims[1]);
  const std::uint32_t cz = cellOf(std::max(a.lo[2], b.lo[2]), g.origin[2], g.invCell, g.dims[2]);
  return std::uint32_t((std::uint64_t(cz) * g.dims[1] + cy) * g.dims[0] + cx);
}

/// f(cell index, x, y, z) for every cell of `r` in a grid of `dims` cells (whose count fits 32 bits), x
/// fastest.
template <typename F>
inline void forEachCellOf(const CellRange& r, const std::uint32_t dims[3], F&& f) {
  for (std::uint32_t z = r.lo[2]; z <= r.hi[2]; ++z)
    for (std::uint32_t y = r.lo[1]; y <= r.hi[1]; ++y) {
      const std::uint32_t row = (z * dims[1] + y) * dims[0];
      for (std::uint32_t x = r.lo[0]; x <= r.hi[0]; ++x) f(row + x, x, y, z);
    }
}

/// A box's cells on a dense grid in 8 bytes: the number of its first cell and its extra cells per axis (hi -
/// lo, up to 255; a box that spans more is marked and walked from its CellRange instead).
struct PackedCells {
  std::uint32_t first;
  std::uint8_t span[3];
  std::uint8_t wide;  // 1: a span did not fit 8 bits

  /// Range `r` of a grid of `dims` cells (whose count fits 32 bits).
  static PackedCells of(const CellRange& r, const std::uint32_t dims[3]) {
    PackedCells p{
        std::uint32_t((std::uint64_t(r.lo[2]) * dims[1] + r.lo[1]) * dims[0] + r.lo[0]), {0, 0, 0}, 0};
    for (int a = 0; a < 3; ++a) {
      const std::uint32_t d = r.hi[a] - r.lo[a];
      p.wide |= std::uint8_t(d > 255);
      p.span[a] = std::uint8_t(d);
    }
    return p;
  }
  bool fits() const { return wide == 0; }
  /// f(cell, first) for every cell, in the order forEachCellOf visits them; `first` has bit a set when the
  /// cell is the range's first on axis a.
  template <typename F>
  void forEach(const std::uint32_t dims[3], F&& f) const {
    const std::uint32_t dx = dims[0], dxy = dims[0] * dims[1];
    for (std::uint32_t z = 0, zc = first; z <= span[2]; ++z, zc += dxy)
      for (std::uint32_t y = 0, yc = zc; y <= span[1]; ++y, yc += dx)
        for (std::uint32_t x = 0; x <= span[0]; ++x)
          f(yc + x, std::uint32_t(x == 0) | std::uint32_t(y == 0) << 1 | std::uint32_t(z == 0) << 2);
  }
};

/// Stage 3 among the huge boxes: huge[i] against each later one (so each pair is tested once), into `out`.
/// Returns the candidates tested.
inline std::uint64_t hugeAgainstLaterHuge(const ProxyArrays& p, const std::vector<std::uint32_t>& huge,
                                          std::size_t i, std::vector<std::uint64_t>& out) {
  const LocalBox a = boxOf(p, huge[i]);
  for (std::size_t j = i + 1; j < huge.size(); ++j) {
    const LocalBox b = boxOf(p, huge[j]);
    if (boxesOverlap(a, b) && passesFilter(a, b)) out.push_back(makePairKey(a.slot, b.slot));
  }
  return huge.size() - i - 1;
}

/// Stage 8 for a whole run of kLocalRunMin to kLocalRunMax boxes (dense piles such as the falling column have
/// runs of about 20): a structure-of-arrays copy of its boxes, padded with boxes that overlap nothing, and
/// each row tested four candidates at a time in vector code; hit(i, j), i < j, for the few overlapping pairs
/// (the caller then checks stage 9 and the filter).
template <class BoxAt, class Hit>
void forEachOverlapInRun(std::uint32_t m, BoxAt&& boxAt, Hit&& hit) {
  alignas(16) float lo[3][kLocalRunMax + 4], hi[3][kLocalRunMax + 4];
  for (std::uint32_t e = 0; e < m; ++e) {
    const LocalBox& b = boxAt(e);
    for (int a = 0; a < 3; ++a) lo[a][e] = b.lo[a], hi[a][e] = b.hi[a];
  }
  for (std::uint32_t e = m; e < m + 4; ++e)
    for (int a = 0; a < 3; ++a)
      lo[a][e] = std::numeric_limits<float>::infinity(), hi[a][e] = -std::numeric_limits<float>::infinity();
  auto load = [](const float* p) {
    Float4 v;
    std::memcpy(&v, p, sizeof v);
    return v;
  };
  for (std::uint32_t i = 0; i + 1 < m; ++i) {
    const Float4 alx = Float4{} + lo[0][i], aly = Float4{} + lo[1][i], alz = Float4{} + lo[2][i];
    const Float4 ahx = Float4{} + hi[0][i], ahy = Float4{} + hi[1][i], ahz = Float4{} + hi[2][i];
    for (std::uint32_t j = i + 1; j < m; j += 4) {
      const Int4 lanes = (alx <= load(&hi[0][j])) & (load(&lo[0][j]) <= ahx) & (aly <= load(&hi[1][j])) &
                         (load(&lo[1][j]) <= ahy) & (alz <= load(&hi[2][j])) & (load(&lo[2][j]) <= ahz);
      if ((lanes[0] | lanes[1] | lanes[2] | lanes[3]) == 0) continue;
      for (std::uint32_t l = 0; l < 4 && j + l < m; ++l)
        if (lanes[l]) hit(i, j + l);
    }
  }
}

}  // namespace gpucol
