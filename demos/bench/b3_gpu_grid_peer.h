#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "broadphase/grid_pair_finder.h"

namespace gpucol::bench {

/// Bullet3's own OpenCL grid broad phase (b3GpuGridBroadphase from Debian's libBullet3OpenCL_clew), driven
/// like the other broad phases of `gpucol-bench broadphase` so that it runs beside ours on the same device.
///
/// What the peer is, read from its source: every small box is hashed by its centre into one cell of a
/// fixed 128^3 wrapping grid and tested against the 27 cells around it, which is exact only while every
/// box is smaller than a cell; it reads at most 256 boxes per cell and drops pairs past maxPairs (it says
/// so on stderr). It ignores collision groups and masks. To be fair and exact where it can be, the peer
/// sets the cell to the largest extent of the boxes it bins and registers boxes far larger than the
/// median as its "large" proxies (tested against all); pairs() lets a benchmark count what it missed.
class B3GpuGridPeer {
 public:
  /// Sets up Bullet3's OpenCL context on the first device whose name contains `deviceFilter`
  /// (case-sensitive; empty: any device, Bullet3 prefers a GPU) and compiles its kernels (cached under
  /// the system temp folder, not the working directory). Throws std::runtime_error saying why when there
  /// is no such device or Bullet3's setup fails.
  explicit B3GpuGridPeer(const std::string& deviceFilter = {});
  ~B3GpuGridPeer();
  B3GpuGridPeer(const B3GpuGridPeer&) = delete;
  B3GpuGridPeer& operator=(const B3GpuGridPeer&) = delete;

  /// Name of the OpenCL device Bullet3 runs on.
  const std::string& deviceName() const;

  /// Gives the peer the active proxies of `proxies` (the first call, or when the active set changed,
  /// creates them; later calls only update the boxes) and uploads them: the setAabb half of a step.
  void setBoxes(const ProxyArrays& proxies);

  /// Forgets the proxies, so that the next setBoxes creates them again and re-splits small and large boxes
  /// (a new scene with the same active slots would otherwise keep the last scene's split).
  void reset();

  /// calculateOverlappingPairs: the other half of a step. Returns the number of pairs found. When the
  /// pair buffer overflowed, it is doubled and the step run again (Bullet3 itself would drop them).
  std::size_t step();

  /// The last step's pairs as sorted pair keys (lower slot << 32 | higher slot), for checking.
  std::vector<std::uint64_t> pairs() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> m_impl;
};

}  // namespace gpucol::bench
