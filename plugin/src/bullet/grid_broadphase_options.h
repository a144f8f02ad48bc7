#pragma once
// The grid broad phase's internal options, set by tests and gpucol-bench, never by users: what the paper
// describes and only a GPU can judge (the bit mask of §3.4, the Newton root of §3.3, the density cell size of
// §4.1), the huge-box limit, and the query index, which gpucol-bench queries compares with scans.
#include <cstdint>

#include "broadphase/grid_pair_finder.h"
#include "gpucol/grid_broadphase.h"

namespace gpucol {

/// Internal options of a GridBroadphase; the defaults are what every user gets.
struct GridBroadphaseOptions {
  /// Cell size from the density rule of Avril et al. §4.1 instead of the objects' median size.
  bool densityCellSize = false;
  /// CPU path: candidates written to the §3.4 bit mask (the grid then searched whole) instead of compacted
  /// lists; the OpenCL finder always compacts.
  bool bitMaskOutput = false;
  /// The mapping function's first guess by the Newton/"magic constant" square root of §3.3.
  bool newtonSqrt = false;
  /// A box covering more cells than this is tested against all instead of being put in the grid.
  std::uint32_t hugeCellLimit = kHugeCellLimit;
  /// Let rayTest and aabbTest build and use the query index; false: every query tests every proxy.
  bool queryIndex = true;
};

namespace detail {
/// The way in to a GridBroadphase's internal options.
struct GridBroadphaseAccess {
  /// Sets `broadphase`'s options: the next calculateOverlappingPairs is a full search, and a query index is
  /// built again with them.
  static void setOptions(GridBroadphase& broadphase, const GridBroadphaseOptions& options);
};
}  // namespace detail

}  // namespace gpucol
