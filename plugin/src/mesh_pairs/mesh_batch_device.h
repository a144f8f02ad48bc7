#pragma once
// The seam between the mesh pair batch (mesh_batch.cpp) and a device that runs the middle and near phases of a
// whole batch at once (opencl/host/mesh_pipeline.cpp, built in with GPUCOL_WITH_OPENCL). The batch asks
// sharedMeshBatchDevice, and takes its CPU path when it returns none. The batch prepares each pair's frame
// (pair_frame.h), the device returns candidates and hits, and the batch turns those into Bullet contacts and
// reduces them exactly as its CPU path does.
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "bvh/aabb_tree.h"
#include "gpucol/collide_meshes.h"
#include "gpucol/config.h"
#include "gpucol/triangle_mesh.h"
#include "mesh_pairs/pair_frame.h"
#include "narrowphase/triangle_contact.h"

namespace gpucol {

/// One mesh pair as the device takes it: both meshes (their shared pointers key the resident device copies)
/// and trees, and the pair's frame.
struct DeviceMeshPair {
  std::shared_ptr<const TriangleMesh> meshA;  ///< A's mesh; the device keeps a copy while it lives.
  std::shared_ptr<const TriangleMesh> meshB;  ///< B's mesh.
  const AabbTree* treeA = nullptr;            ///< A's tree (built from meshA); must outlive the call.
  const AabbTree* treeB = nullptr;            ///< B's tree.
  PairFrame frame;                            ///< The frame the pair is tested in (makePairFrame).
};

/// One candidate whose triangles intersect, by its index in DeviceMeshPairResult::candidates.
struct DeviceNearHit {
  std::uint32_t candidate = 0;  ///< Index among the pair's candidates.
  bool hasContact = false;      ///< A contact was kept (generateContact's answer was not std::nullopt).
  TriangleContact contact;      ///< The contact in A's scaled frame, when hasContact.
};

/// What the device found for one pair: the same lists, in the same order, as the CPU path's.
struct DeviceMeshPairResult {
  std::vector<TrianglePair> candidates;  ///< Sorted by (triangleA, triangleB).
  std::vector<DeviceNearHit> hits;       ///< Intersecting candidates, in candidate order.
};

/// How the device's middle phase walks the trees.
enum class MeshTraversal {
  /// One launch: each work-item takes one node pair of the front `depthFirstStartDepth` levels down and
  /// descends from it depth-first with a private stack, appending candidates at an atomic counter (the buffer
  /// grows and the pass reruns when it overflows); the sort then orders them.
  DepthFirst,
  /// The thesis's §5.4.2 reference: one level per iteration (count, scan, write), from `startDepth`.
  BreadthFirst,
};

/// Where a batch's candidates are put in order (pair, triangle A, triangle B).
enum class CandidateSort {
  /// On the device in a GPU's shape, on the host on a CPU device: each was the faster there (README, "Mesh
  /// pairs on OpenCL" and "On a GPU").
  Auto,
  /// On the device (radix sort) before the near phase.
  Device,
  /// On the host after the near phase, with a radix sort of its own, as the keys come back.
  Host,
};

/// How the device runs a batch (the measured options of the OpenCL pipeline; defaults are the chosen ones).
struct MeshBatchDeviceOptions {
  /// Middle phase walk (docs/measured-results.md, "Mesh pairs on OpenCL": depth-first was faster on PoCL at every size).
  MeshTraversal traversal = MeshTraversal::DepthFirst;
  /// Depth at which the breadth-first traversal starts (thesis §5.4.2 used 6): the first front is every node
  /// pair that many expansions below the roots whose boxes (and ancestors' boxes) overlap.
  int startDepth = 0;
  /// Depth of the depth-first traversal's start front (0..12); -1 picks the smallest depth that gives the
  /// launch as many work-items (pairs x 4^depth) as the batch's size asks for: one per 128 triangles of each
  /// pair's smaller mesh, from 256 to 4096 (measured in opencl/host/mesh_pipeline.cpp).
  int depthFirstStartDepth = -1;
  /// Run the float plane and interval tests of triangle_plane.h as a stage of their own, then the double
  /// test only on the candidates they could not prove apart (the early-out).
  bool nearPrefilter = true;
  /// Where the candidates are sorted.
  CandidateSort candidateSort = CandidateSort::Auto;
  /// Wait after the traversal too, so that the stats split its time from the near kernel's and the
  /// readback's (the time-split table of `gpucol-bench meshpair --backend opencl`). Off (the default), the
  /// depth-first traversal, the near kernel and the reads of the counters, keys and hits are one wait, and
  /// MeshBatchDeviceStats::traversalMs holds all three.
  bool splitTimes = false;
};

/// Timings and counters of the last batch (host clock around each stage; each stage ends with a wait).
struct MeshBatchDeviceStats {
  double uploadMs = 0;              ///< Mesh data (only when not yet resident) and the batch description.
  double traversalMs = 0;           ///< Box-test kernels of the middle phase, counting and writing passes.
  double scanMs = 0;                ///< Prefix sums of the middle phase (with their read of the totals).
  double sortMs = 0;                ///< Candidate sort (device or host).
  double prefilterMs = 0;           ///< Near phase: the float early-out kernel (nearPrefilter).
  double nearMs = 0;                ///< Near phase: the double test and contact kernel.
  double compactionMs = 0;          ///< Near phase: scan and gather of the early-out's survivors.
  double readbackMs = 0;            ///< Candidates and hits back, past those read with the traversal.
  std::uint64_t uploadedBytes = 0;  ///< Bytes written to the device in this batch.
  std::uint64_t nodeTests = 0;      ///< Box tests of the middle phase, start front included.
  std::vector<std::uint64_t> frontSizes;  ///< Overlapping node pairs per level (thesis Table 6.3).
  std::uint64_t candidates = 0;           ///< Candidate triangle pairs of the batch.
  std::uint64_t hits = 0;                 ///< Intersecting candidates of the batch.
  std::uint64_t traversalReruns = 0;  ///< Depth-first passes rerun because the candidate buffer overflowed.
};

/// A device that runs the middle and near phases of a batch. Thread-safe (calls are serialised).
class MeshBatchDevice {
 public:
  virtual ~MeshBatchDevice() = default;
  /// Runs every pair of `pairs` (their root boxes are known to overlap) and fills `results` (one per pair).
  /// Throws on a device failure; the caller falls back to its CPU path.
  virtual void run(const std::vector<DeviceMeshPair>& pairs, const MeshBatchDeviceOptions& options,
                   std::vector<DeviceMeshPairResult>& results, MeshBatchDeviceStats* stats = nullptr) = 0;
  /// The device's name.
  virtual std::string deviceName() const = 0;
  /// True when the device is a GPU (Backend::Auto only ever picks a GPU; see mesh_batch.cpp).
  virtual bool isGpu() const = 0;
  /// Meshes resident on the device now (expired ones are dropped at the start of each run).
  virtual std::size_t residentMeshes() const = 0;
};

/// True when gpucol was built with OpenCL (GPUCOL_WITH_OPENCL).
#ifdef GPUCOL_WITH_OPENCL
inline constexpr bool kBuiltWithOpenCl = true;
#else
inline constexpr bool kBuiltWithOpenCl = false;
#endif

/// The shared device for `config` (one per device, living until the process ends: opencl/host/
/// mesh_pipeline.h), or nullptr when there is none (it says why once on stderr) or gpucol was built without
/// OpenCL. Defined in bullet/opencl_backends.cpp.
MeshBatchDevice* sharedMeshBatchDevice(const Config& config);

}  // namespace gpucol
