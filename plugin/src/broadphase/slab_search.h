#pragma once
// The CPU finder's full search of a dense grid, one slab at a time (stages 3-9 of grid_pair_finder.h).
//
// The grid is cut across its longest axis into slabs of whole cell layers holding about the same number of
// boxes. Each box is listed in every slab its cell range reaches; one thread bins a slab's boxes into the
// slab's cells (a counting sort of its own, with no atomics) and tests each cell's boxes pairwise with
// stage 9's rule. Each pair is then reported by one slab: the one that holds the cell of the overlap's min
// corner, which lies in both boxes' ranges.
//
// Why slabs: a slab's box copies, cells and entries fit in a core's cache, and they are the only
// per-box working memory besides the slab lists. The whole-grid search holds about 100 bytes per box of
// such memory for the whole scene, more than the boxes themselves (docs/measured-results.md, "Broad phase").
//
// The whole-grid search numbers every candidate and finds its pair through the mapping function (paper
// §3.2), which is what spreads cells over GPU threads. A slab's thread walks its cells' candidates in
// order, so it needs no numbering. The bit-mask output (§3.4) is indexed by that numbering, so it always
// uses the whole-grid search. A grid kept for stage 11 is binned whole by the finder after the slabs.
//
// By home cell (boxes of about one size): on a grid whose cells are as large as
// the largest box, a box spans at most two cells per axis, so two boxes that overlap have home cells (the
// cells of their min corners) at most one apart on every axis: cellOf is monotone, and a.lo <= b.hi gives
// cellOf(a.lo) <= cellOf(b.hi) <= cellOf(b.lo) + 1. Each box then goes into its home cell alone, one entry
// instead of up to eight, and each cell's boxes are tested against the later ones of the cell and those of
// its 13 neighbours that come after it (a half shell), each pair of cells once, with no stage 9 rule. The
// slabs cut the same way; a slab owns the pairs whose later home layer along its axis it holds (the layer of
// the overlap's min corner, as in the other search), and so also holds, as a layer below its own, the boxes
// that start one layer below it and reach into it. A box that still spans three cells on an axis (one of the
// few larger boxes, or by rounding) is kept out of the cells and, as a huge box is, tested against the boxes
// of the cells around its range, with that rule.
#include <tbb/enumerable_thread_specific.h>

#include <cstddef>
#include <cstdint>
#include <vector>

#include "broadphase/grid_choice.h"
#include "broadphase/grid_pair_finder.h"
#include "broadphase/local_box.h"
#include "broadphase/pair_buckets.h"
#include "memory/exact_vector.h"

namespace gpucol {

/// Counts of one slab search (PairFinderStats).
struct SlabSearchCounts {
  /// (cell, box) entries over all slabs: each is in one slab, so this is the whole grid's count (by home
  /// cell: one per box in each slab that lists it).
  std::uint64_t keys = 0;
  /// Candidate pairs tested: pairs of boxes sharing a cell, and huge boxes against binned ones.
  std::uint64_t candidates = 0;
  /// Search by home cell: boxes spanning three or more cells on an axis (once per slab that lists them).
  std::uint64_t wide = 0;
};

/// Plans and runs slab searches; keeps its working memory between them until release().
class SlabSearch {
 public:
  /// Boxes per slab aimed at, at least. Each thread holds the working memory of the largest slab it took, so
  /// in a small scene it is the slabs' size that sets the peak per proxy: at 1,000 boxes with copies, slabs
  /// aimed at 256 boxes peaked at 125-133 bytes per proxy and at 64 boxes at 101-111, in steps within the
  /// noise of the machine (measurement history).
  static constexpr std::uint64_t kMinSlabBoxes = 64;

  /// Cuts grid `g` of the `binned` slots into slabs of about `slabBoxes` boxes each (0: the scene's count
  /// over kSlabsAimed, and at least kMinSlabBoxes), and lists each binned slot in every slab it reaches.
  /// Returns false, with nothing planned, when fewer than `minSlabs` slabs come out. `reading` says how
  /// search() will read the boxes (readsInPlace() for Auto's choice). `kept`, when its axis
  /// is the one the slabs cut (axis()), gives the binned boxes' extents along it (by binned index, or by
  /// slot for all of `p`'s slots), which are then not read from `p`; they are freed (or taken over) as soon
  /// as the plan no longer needs them.
  /// `homeCells`: search() pairs the boxes by home cell (the grid is then the home grid of chooseGrid, and the
  /// boxes are always copied).
  bool plan(const ProxyArrays& p, const std::vector<std::uint32_t>& binned, const Grid& g,
            std::uint32_t slabBoxes, std::uint32_t minSlabs, SlabBoxReading reading,
            AxisExtents* kept = nullptr, bool homeCells = false);
  /// The axis the last plan cut (the one with most cells), also after release(): a guess for the next.
  int axis() const { return m_axis; }
  /// Whether the last plan took its extents from `kept`.
  bool tookKeptExtents() const { return m_tookKept; }
  /// Whether search() reads the planned boxes in place instead of copying each slab's.
  bool readsInPlace() const { return m_inPlace; }
  /// Whether search() pairs the planned boxes by home cell.
  bool byHomeCell() const { return m_home; }
  /// Slabs of the last plan.
  std::size_t slabs() const { return m_firstLayer.empty() ? 0 : m_firstLayer.size() - 1; }
  /// Output lists search() fills: one per slab, one per huge box.
  std::size_t outputs(std::size_t hugeCount) const { return slabs() + hugeCount; }
  /// Finds the planned boxes' pairs and those of the `huge` slots with each other and with binned boxes, into
  /// out[first], ..., out[first + outputs(huge.size()) - 1] (unsorted keys, each pair once), or when
  /// `buckets` is given into its pieces 0, ..., outputs(huge.size()) - 1 (out is then not touched).
  SlabSearchCounts search(const ProxyArrays& p, const std::vector<std::uint32_t>& huge, const Grid& g,
                          std::vector<std::vector<std::uint64_t>>& out, std::size_t first,
                          PairBuckets* buckets = nullptr);
  /// Bytes of working memory held (capacities).
  std::size_t bytes() const;
  /// Frees all working memory.
  void release();

 private:
  /// One thread's working memory for the slab it is searching.
  struct Scratch {
    std::vector<LocalBox> box;             // the slab's boxes, in slab-list order (unless read in place)
    std::vector<PackedCells> cells;        // their cells in slab coordinates
    std::vector<std::uint32_t> cellStart;  // first entry per slab cell (+1 sentinel)
    std::vector<std::uint32_t> entries;    // box indices by cell, with start bits (by home cell: each box's cell)
    std::vector<LocalBox> sorted;          // by home cell: the boxes in cell order
    std::vector<std::uint32_t> wide;       // by home cell: the boxes that span three or more cells on an axis
    std::vector<std::uint64_t> pairs;      // the pairs of the slab being searched
    std::size_t growthBytes = 0;           // the most it held while its pair list grew (old and new arrays)
  };

  /// Searches slab `slab` with t's memory; its pairs are left in t.pairs, all of them, or with `buckets`
  /// those not yet added to the buckets' piece `slab`.
  SlabSearchCounts searchSlab(std::size_t slab, const ProxyArrays& p, const std::vector<std::uint32_t>& huge,
                              const Grid& g, Scratch& t, PairBuckets* buckets);
  /// searchSlab by home cell (slab_home_cells.cpp): searchSlabByHomeCellOn for the slab axis m_axis.
  SlabSearchCounts searchSlabByHomeCell(std::size_t slab, const ProxyArrays& p,
                                        const std::vector<std::uint32_t>& huge, const Grid& g, Scratch& t,
                                        PairBuckets* buckets);
  /// searchSlabByHomeCell for slabs cut across axis A.
  template <int A>
  SlabSearchCounts searchSlabByHomeCellOn(std::size_t slab, const ProxyArrays& p,
                                          const std::vector<std::uint32_t>& huge, const Grid& g, Scratch& t,
                                          PairBuckets* buckets);
  /// Appends a pair key to t's list of slab `slab`; into `buckets`, a full list that holds a part's worth is
  /// handed over to them rather than grown.
  static void addPair(std::size_t slab, Scratch& t, PairBuckets* buckets, std::uint64_t key) {
    if (t.pairs.size() == t.pairs.capacity()) {
      if (buckets && t.pairs.size() >= buckets->partKeys()) {
        buckets->addToPiece(slab, t.pairs);
        t.pairs.clear();
      } else {
        growPairs(t);
      }
    }
    t.pairs.push_back(key);
  }
  /// Bytes of one thread's working memory (capacities).
  static std::size_t bytesOf(const Scratch& t);
  /// Doubles t's pair list by hand, so the moment it holds the old array and the new one is counted.
  static void growPairs(Scratch& t);

  int m_axis = 0;                           // the axis the slabs cut (the one with most cells)
  bool m_tookKept = false;                  // the last plan read the grid choice's kept extents
  bool m_inPlace = false;                   // search() reads boxes by slot, with no copy per slab
  bool m_home = false;                      // search() pairs boxes by home cell
  std::vector<std::uint32_t> m_firstLayer;  // per slab: its first layer along m_axis (+ the end)
  std::vector<std::uint32_t> m_layerSlab;   // per layer: its slab
  std::vector<std::size_t> m_memberStart;   // per slab: first index in m_members (+ the end)
  std::vector<std::uint32_t> m_members;     // slots by slab, ascending within a slab
  std::vector<std::uint32_t> m_boxLayers;   // planning: per binned box, its first | last layer << 16
  std::vector<std::size_t> m_chunkCount;    // counting scratch: per (chunk, slab)
  tbb::enumerable_thread_specific<Scratch> m_scratch;
};

}  // namespace gpucol
