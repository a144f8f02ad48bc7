// The OpenCL mesh pipeline (thesis §5.4, batched as in its §7.3): host side of mesh_middle_phase.cl and
// mesh_near_phase.cl.
#include "opencl/host/mesh_pipeline.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <iostream>
#include <map>
#include <mutex>
#include <set>
#include <stdexcept>
#include <string>

#include "gpucol_kernels/kernels.h"
#include "opencl/host/device_array.h"
#include "opencl/host/mesh_device_cache.h"
#include "opencl/host/mesh_host_sort.h"
#include "opencl/host/opencl_context.h"
#include "opencl/host/radix_sort.h"
#include "opencl/host/scan.h"
#include "opencl/shared/mesh_pipeline_types.h"

namespace gpucol::opencl {

static_assert(sizeof(GpucolBoxMap) == 24 * 4 && offsetof(GpucolBoxMap, absLinear) == 48,
              "GpucolBoxMap layout differs from the kernels'");
static_assert(sizeof(GpucolMeshPair) == 71 * 4 && offsetof(GpucolMeshPair, intoB) == 96 &&
                  offsetof(GpucolMeshPair, bLinear) == 192 && offsetof(GpucolMeshPair, scaleA) == 240 &&
                  offsetof(GpucolMeshPair, nodesA) == 252 && offsetof(GpucolMeshPair, flipB) == 280,
              "GpucolMeshPair layout differs from the kernels'");
static_assert(sizeof(GpucolFrontEntry) == 12, "GpucolFrontEntry layout differs from the kernels'");
static_assert(sizeof(GpucolNearHit) == 48 && offsetof(GpucolNearHit, point) == 8 &&
                  offsetof(GpucolNearHit, normal) == 20 && offsetof(GpucolNearHit, depth) == 32 &&
                  offsetof(GpucolNearHit, deepest) == 36,
              "GpucolNearHit layout differs from the kernels'");

namespace {

using Clock = std::chrono::steady_clock;

double millisecondsSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

/// One frame's box test (bvh/tree_traversal.h) in the kernels' layout.
void writeBoxMap(const BoxMap& in, GpucolBoxMap& out) {
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) {
      out.linear[3 * r + c] = in.map.linear(r, c);
      out.absLinear[3 * r + c] = std::fabs(in.map.linear(r, c));
    }
    out.translation[r] = in.map.translation(r);
    out.inflation[r] = in.inflation(r);
  }
}

/// Largest start depth: 4^d paths per pair must stay far below the 2^32 work-items of one launch.
constexpr int kMaxStartDepth = 12;

/// Largest work-group the pipeline launches on a GPU (OpenClMeshPipeline::groupSize): whole wavefronts, and
/// the 4096 work-items of a one-pair depth-first launch make 64 groups to spread over the compute units.
constexpr std::size_t kGroupSizeCap = 64;

/// The same on a CPU device, which runs one group at a time per thread: the smaller the group, the more
/// evenly the two threads share a small launch (armadillo-2766's traversal is 256 work-items whose work
/// differs widely; 16 beat 64 on PoCL: measurement history).
constexpr std::size_t kCpuGroupSizeCap = 16;

/// Work-groups of the depth-first traversal per compute unit on a CPU device, whose work-items take start
/// paths from a shared counter: more than one, so that a thread that is late to start still finds a group.
constexpr std::uint64_t kCpuTraversalGroupsPerUnit = 2;

/// Candidates per work-item of mesh_near_filter_test (its GPUCOL_LANES: 4, 8 or 16). 8 floats are one AVX
/// register.
constexpr std::uint64_t kPrefilterLanes = 8;

/// Work-items the depth-first traversal's automatic start depth aims for (MeshBatchDeviceOptions): the
/// batch's triangles (the smaller mesh of each pair, summed) / kTrianglesPerItem, within kDepthFirstMinItems
/// .. kDepthFirstItems. Every work-item walks again from the roots to the start front, which on a small pair
/// costs more than the balance it buys (on PoCL armadillo-2766 alone was fastest at 256, a batch of 100 of its
/// pairs at 4096: docs/measured-results.md "Mesh pairs on OpenCL"). One item per 128 triangles instead of 16:
/// the walk to a start front d levels down costs sum over levels l of (overlapping node pairs at l) x
/// 4^(d - l) box tests, about 14,700 at d = 6 on armadillo-27674 (87,657 tests in all) and 3,600 at d = 5,
/// while only 145 (d = 5) or 279 (d = 6) of the work-items reach a live node pair anyway. 128 gives d = 4, 5,
/// 6 for 27674, 99976, 399904.
constexpr std::uint64_t kDepthFirstItems = 4096;
constexpr std::uint64_t kDepthFirstMinItems = 256;
constexpr std::uint64_t kTrianglesPerItem = 128;

/// The same on a GPU, which runs one work-item per start path: a front wide enough that its live paths
/// fill every multiprocessor, start paths per compute unit. Most paths die within a level or two of the
/// roots' overlap (27674's front at depth 6 has 279 live node pairs of 4,096), so the front is made many
/// times wider than the device's lanes.
constexpr std::uint64_t kGpuStartPathsPerUnit = 1024;

/// Sums of the two trees' depths whose traversal variants (stack lengths 64, 128, 256) are built with the
/// pipeline: up to 85 levels between the two trees, more than a balanced tree of 2^40 triangles each.
constexpr int kPrebuiltTreeDepths[] = {21, 42, 85};

/// Words of the counter buffer the traversal and the near kernel share: [0] candidates appended, [1] the
/// candidate counter wrapped, [2] / [3] low / high word of the box tests (mesh_middle_phase.cl), [4] hits
/// appended by mesh_near_filter_test, [5] the next start path the depth-first traversal's work-items take;
/// the rest is padding.
constexpr std::size_t kCounterWords = 8;

class OpenClMeshPipeline final : public MeshBatchDevice {
 public:
  explicit OpenClMeshPipeline(OpenClContext& context)
      : m_context(context), m_cache(context), m_scan(context), m_sort(context) {
    translateClErrors("setting up the OpenCL mesh pipeline", [&] {
      cl::Program middle = m_context.program("mesh_middle_phase", kernels::mesh_middle_phase);
      m_frontStart = cl::Kernel(middle, "mesh_front_start");
      m_frontExpand = cl::Kernel(middle, "mesh_front_expand");
      cl::Program nearProgram = m_context.program("mesh_near_phase", kernels::mesh_near_phase,
                                                  "-DGPUCOL_LANES=" + std::to_string(kPrefilterLanes));
      m_nearFilterTest = cl::Kernel(nearProgram, "mesh_near_filter_test");
      m_nearTest = cl::Kernel(nearProgram, "mesh_near_test");
      m_nearEach = cl::Kernel(nearProgram, "mesh_near_each");
      m_counters = cl::Buffer(m_context.context(), CL_MEM_READ_WRITE, kCounterWords * sizeof(cl_uint));
      // Kernels read the leaf entry arena even when no tree has entries: give it one element.
      m_emptyEntries = cl::Buffer(m_context.context(), CL_MEM_READ_ONLY, sizeof(GpucolLeafEntry));
      m_computeUnits = std::max<cl_uint>(1, m_context.device().getInfo<CL_DEVICE_MAX_COMPUTE_UNITS>());
      // Every traversal variant a batch of ordinary trees can ask for, built now rather than inside a timed
      // call (a cold build takes seconds on a GPU's driver, and Backend::Auto times the calls).
      for (int treeDepths : kPrebuiltTreeDepths) {
        depthFirstKernel(treeDepths, !m_context.gpuShaped());
        depthFirstKernel(treeDepths, false);
      }
    });
  }

  void run(const std::vector<DeviceMeshPair>& pairs, const MeshBatchDeviceOptions& options,
           std::vector<DeviceMeshPairResult>& results, MeshBatchDeviceStats* stats) override {
    std::lock_guard<std::mutex> lock(m_mutex);
    MeshBatchDeviceStats local;
    MeshBatchDeviceStats& s = stats ? *stats : local;
    s = MeshBatchDeviceStats();
    results.assign(pairs.size(), DeviceMeshPairResult());
    if (pairs.empty()) return;
    if (options.startDepth < 0 || options.startDepth > kMaxStartDepth) {
      throw std::invalid_argument("OpenCL mesh pipeline: start depth " + std::to_string(options.startDepth) +
                                  " is outside 0.." + std::to_string(kMaxStartDepth));
    }
    if (options.depthFirstStartDepth < -1 || options.depthFirstStartDepth > kMaxStartDepth) {
      throw std::invalid_argument("OpenCL mesh pipeline: depth-first start depth " +
                                  std::to_string(options.depthFirstStartDepth) + " is outside -1.." +
                                  std::to_string(kMaxStartDepth));
    }
    translateClErrors("running the OpenCL mesh pipeline", [&] { runBatch(pairs, options, results, s); });
  }

  std::string deviceName() const override { return m_context.deviceName(); }
  bool isGpu() const override { return m_context.isGpu(); }
  std::size_t residentMeshes() const override {
    std::lock_guard<std::mutex> lock(m_mutex);
    return m_cache.size();
  }

 private:
  /// The work-group size of `kernel`: the device's largest for it, capped at kGroupSizeCap (kCpuGroupSizeCap
  /// on a CPU device). One size per kernel whatever the batch: PoCL compiles a kernel again for every new
  /// local size (a few hundred ms), and a CPU device runs one work-group per thread, so its largest group
  /// (4096) would put a whole small batch on one core; the depth-first kernel's work-items also differ widely
  /// in work.
  std::size_t groupSize(const cl::Kernel& kernel, std::uint64_t) const {
    return std::min<std::size_t>(m_context.workGroupSize(kernel),
                                 m_context.gpuShaped() ? kGroupSizeCap : kCpuGroupSizeCap);
  }

  /// The global size launch() uses for `items` work-items of `kernel`.
  std::size_t globalSize(const cl::Kernel& kernel, std::uint64_t items) const {
    const std::size_t local = groupSize(kernel, items);
    return std::size_t((items + local - 1) / local * local);
  }

  /// Enqueues `kernel` over at least `items` work-items (rounded up to whole work-groups).
  void launch(cl::Kernel& kernel, std::uint64_t items) {
    if (items == 0) return;
    m_context.queue().enqueueNDRangeKernel(kernel, cl::NullRange, cl::NDRange(globalSize(kernel, items)),
                                           cl::NDRange(groupSize(kernel, items)));
  }

  void runBatch(const std::vector<DeviceMeshPair>& pairs, const MeshBatchDeviceOptions& options,
                std::vector<DeviceMeshPairResult>& results, MeshBatchDeviceStats& s);
  std::uint64_t traverseBreadthFirst(std::size_t pairCount, const MeshBatchDeviceOptions& options,
                                     const cl::Buffer& entries, unsigned bitsA, unsigned bitsB,
                                     MeshBatchDeviceStats& s);
  std::uint64_t traverseDepthFirst(std::size_t pairCount, int treeDepths, std::uint64_t smallerTriangles,
                                   const MeshBatchDeviceOptions& options, const cl::Buffer& entries,
                                   unsigned bitsA, unsigned bitsB, bool chainNear, std::uint64_t& records,
                                   MeshBatchDeviceStats& s);
  void setNearFilterArgs(std::uint64_t capacity, unsigned bitsA, unsigned bitsB);
  /// The near phase with the early-out, in the device's shape: candidates in vector lanes on a CPU device
  /// (mesh_near_filter_test), one per work-item on a GPU (mesh_near_each).
  cl::Kernel& nearKernel() { return m_context.gpuShaped() ? m_nearEach : m_nearFilterTest; }
  /// Whether the candidates are sorted on the device (CandidateSort::Auto: in a GPU's shape; on a CPU device
  /// the host's radix sort was faster at every size measured, up to a batch of 431,257 candidates, and on the
  /// H200 the device's from about 10,000 candidates up: docs/measured-results.md, "On a GPU").
  bool sortsOnDevice(const MeshBatchDeviceOptions& options) const {
    return options.candidateSort == CandidateSort::Device ||
           (options.candidateSort == CandidateSort::Auto && m_context.gpuShaped());
  }
  /// Work-items nearKernel() takes for `candidates`.
  std::uint64_t nearItems(std::uint64_t candidates) const {
    return m_context.gpuShaped() ? candidates : (candidates + kPrefilterLanes - 1) / kPrefilterLanes;
  }
  cl::Kernel& depthFirstKernel(int treeDepths, bool fusedNear);

  OpenClContext& m_context;
  mutable std::mutex m_mutex;
  MeshDeviceCache m_cache;
  OpenClScan m_scan;
  OpenClRadixSort m_sort;
  cl::Kernel m_frontStart, m_frontExpand, m_nearFilterTest, m_nearTest, m_nearEach;
  std::map<std::pair<std::size_t, bool>, cl::Kernel> m_depthFirst;  // by stack length, near phase fused
  cl::Buffer m_emptyEntries, m_counters;
  const cl_uint m_zeroCounters[kCounterWords] = {};
  DeviceArray m_pairs, m_counts, m_front, m_next, m_keys, m_values, m_hits;
  std::vector<GpucolMeshPair> m_hostPairs;
  std::vector<std::uint64_t> m_hostKeys, m_sortedKeys;
  std::vector<std::uint32_t> m_rank, m_hitAt;
  std::vector<GpucolNearHit> m_hostHits, m_rankedHits;
  // Keys and hits already read into m_hostKeys / m_hostHits behind the kernels (the one-wait path), and the
  // last batch's counts that size those reads.
  std::uint64_t m_keysRead = 0, m_hitsRead = 0, m_lastCandidates = 0, m_lastHits = 0;
  MeshHostSort m_hostSort;
  std::uint64_t m_computeUnits = 1;
};

void OpenClMeshPipeline::runBatch(const std::vector<DeviceMeshPair>& pairs,
                                  const MeshBatchDeviceOptions& options,
                                  std::vector<DeviceMeshPairResult>& results, MeshBatchDeviceStats& s) {
  const cl::Context& ctx = m_context.context();
  cl::CommandQueue& queue = m_context.queue();

  // Upload: meshes only when not resident, then the batch description (transforms, offsets).
  auto start = Clock::now();
  std::uint64_t maxTrianglesA = 1, maxTrianglesB = 1;
  int treeDepths = 0;
  std::uint64_t smallerTriangles = 0;
  m_hostPairs.resize(pairs.size());
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    const DeviceMeshPair& in = pairs[i];
    if (!in.meshA || !in.meshB || !in.treeA || !in.treeB) {
      throw std::invalid_argument("OpenCL mesh pipeline: pair " + std::to_string(i) +
                                  " lacks a mesh or tree");
    }
    const MeshSlot slotA = m_cache.acquire(in.meshA, *in.treeA, s.uploadedBytes);
    const MeshSlot slotB = m_cache.acquire(in.meshB, *in.treeB, s.uploadedBytes);
    maxTrianglesA = std::max<std::uint64_t>(maxTrianglesA, in.meshA->triangleCount());
    maxTrianglesB = std::max<std::uint64_t>(maxTrianglesB, in.meshB->triangleCount());
    treeDepths = std::max(treeDepths, in.treeA->depth() + in.treeB->depth());
    smallerTriangles += std::min(in.meshA->triangleCount(), in.meshB->triangleCount());
    GpucolMeshPair& p = m_hostPairs[i];
    writeBoxMap(boxMapIntoA(*in.treeB, in.frame.treeMap, in.frame.candidateReach.inA), p.intoA);
    writeBoxMap(boxMapIntoB(*in.treeA, in.frame.treeMap, in.frame.candidateReach.inB), p.intoB);
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) p.bLinear[3 * r + c] = in.frame.bLinear(r, c);
      p.bTranslation[r] = in.frame.bTranslation(r);
      p.scaleA[r] = in.frame.scaleA(r);
    }
    p.nodesA = slotA.nodes;
    p.nodesB = slotB.nodes;
    p.entriesA = slotA.entries;
    p.entriesB = slotB.entries;
    p.trianglesA = slotA.triangles;
    p.trianglesB = slotB.triangles;
    p.flipA = in.frame.flipA ? 1u : 0u;
    p.flipB = in.frame.flipB ? 1u : 0u;
  }
  const unsigned bitsA = indexBits(maxTrianglesA);
  const unsigned bitsB = indexBits(maxTrianglesB);
  const unsigned keyBits = indexBits(pairs.size()) + bitsA + bitsB;
  if (keyBits > 64) {
    throw std::length_error("OpenCL mesh pipeline: pair and triangle indices need " +
                            std::to_string(keyBits) + " bits, more than a 64-bit sort key");
  }
  const std::size_t pairBytes = pairs.size() * sizeof(GpucolMeshPair);
  // Not waited for: the in-order queue runs it before the first kernel, and m_hostPairs stays untouched until
  // the next batch, which begins after this one's last wait.
  queue.enqueueWriteBuffer(m_pairs.ensure(ctx, pairBytes), CL_FALSE, 0, pairBytes, m_hostPairs.data());
  s.uploadedBytes += pairBytes;
  const cl::Buffer& entries = m_cache.entries()() ? m_cache.entries() : m_emptyEntries;
  s.uploadMs = millisecondsSince(start);

  // The depth-first traversal with the early-out and the host sort (the defaults) has the near kernel
  // enqueued right behind it, reading the candidate count on the device: one wait for both instead of a wait,
  // a second launch and a second wait (PoCL's threads went idle and woke again in between).
  const bool chainNear =
      options.traversal == MeshTraversal::DepthFirst && options.nearPrefilter && !sortsOnDevice(options);
  std::uint64_t candidateCount = 0;
  std::uint64_t records = 0;
  m_keysRead = m_hitsRead = 0;
  if (options.traversal == MeshTraversal::BreadthFirst) {
    candidateCount = traverseBreadthFirst(pairs.size(), options, entries, bitsA, bitsB, s);
  } else {
    candidateCount = traverseDepthFirst(pairs.size(), treeDepths, smallerTriangles, options, entries, bitsA,
                                        bitsB, chainNear, records, s);
  }
  s.candidates = candidateCount;
  m_lastCandidates = candidateCount;
  m_lastHits = records;
  if (candidateCount == 0) return;

  // Deterministic order: by pair, then (triangleA, triangleB), which is the CPU's order within each pair. On
  // the device before the near phase (sortsOnDevice), or on the host after it: the near phase does not care
  // about the order, and on a CPU device the host sorts the keys it reads back faster than the device's ten
  // radix passes of 4 bits for 40-bit keys.
  const bool deviceSort = sortsOnDevice(options);
  if (deviceSort) {
    start = Clock::now();
    m_sort.sort(m_keys.buffer, m_values.ensure(ctx, candidateCount * sizeof(cl_uint)), candidateCount,
                keyBits);
    queue.finish();
    s.sortMs = millisecondsSince(start);
  }

  // Near phase. With the early-out: one kernel tests every candidate in float (vector lanes) and runs the
  // double test and contact generation on the survivors, appending the intersecting ones' records in any
  // order. Without it: every candidate's record, intersecting or not, in candidate order. The host keeps the
  // intersecting records and puts them in candidate order below.
  start = Clock::now();
  if (chainNear) {
    // Done with the traversal (traverseDepthFirst timed it as nearMs).
  } else if (options.nearPrefilter) {
    // The kernel reads the candidate count from counters[0] and appends at counters[4].
    const cl_uint counters[kCounterWords] = {cl_uint(candidateCount)};
    queue.enqueueWriteBuffer(m_counters, CL_FALSE, 0, sizeof counters, counters);
    setNearFilterArgs(candidateCount, bitsA, bitsB);
    launch(nearKernel(), nearItems(candidateCount));
    cl_uint read[kCounterWords];
    queue.enqueueReadBuffer(m_counters, CL_TRUE, 0, sizeof read, read);
    records = read[4];
  } else {
    records = candidateCount;
    setKernelArgs(m_nearTest, 0, m_pairs.buffer, m_cache.triangles(), m_keys.buffer, cl_uint(candidateCount),
                  cl_uint(bitsA), cl_uint(bitsB), m_hits.ensure(ctx, candidateCount * sizeof(GpucolNearHit)));
    launch(m_nearTest, candidateCount);
    queue.finish();
  }
  if (!chainNear) s.nearMs += millisecondsSince(start);

  // What the traversal did not read with its wait (all of it but with the one-wait path).
  start = Clock::now();
  const std::uint64_t keysRead = std::min(m_keysRead, candidateCount);
  const std::uint64_t hitsRead = std::min(m_hitsRead, records);
  m_keysRead = m_hitsRead = 0;
  m_hostKeys.resize(candidateCount);
  m_hostHits.resize(records);
  bool reading = false;
  if (candidateCount > keysRead) {
    queue.enqueueReadBuffer(m_keys.buffer, CL_FALSE, keysRead * sizeof(cl_ulong),
                            (candidateCount - keysRead) * sizeof(cl_ulong), m_hostKeys.data() + keysRead);
    reading = true;
  }
  if (records > hitsRead) {
    queue.enqueueReadBuffer(m_hits.buffer, CL_FALSE, hitsRead * sizeof(GpucolNearHit),
                            (records - hitsRead) * sizeof(GpucolNearHit), m_hostHits.data() + hitsRead);
    reading = true;
  }
  if (reading) queue.finish();
  s.readbackMs = millisecondsSince(start);

  // The keys in order (deviceSort false: sorted here, and each hit's candidate index moved to its key's place
  // in that order; keys are unique, a triangle pair is found once), then the intersecting hits in candidate
  // order: the candidate indices are a permutation, so by a slot per candidate instead of a second sort.
  start = Clock::now();
  if (!deviceSort) m_hostSort.sortAndRank(m_hostKeys, keyBits, m_sortedKeys, m_rank);
  constexpr std::uint32_t kNoHit = 0xffffffffu;
  m_hitAt.assign(candidateCount, kNoHit);
  for (std::size_t i = 0; i < m_hostHits.size(); ++i) {
    if ((m_hostHits[i].flags & GPUCOL_HIT_INTERSECTS) == 0) continue;
    const std::uint32_t at = deviceSort ? m_hostHits[i].candidate : m_rank[m_hostHits[i].candidate];
    m_hostHits[i].candidate = at;
    m_hitAt[at] = std::uint32_t(i);
  }
  m_rankedHits.clear();
  for (std::uint32_t slot : m_hitAt) {
    if (slot != kNoHit) m_rankedHits.push_back(m_hostHits[slot]);
  }
  std::swap(m_hostHits, m_rankedHits);
  if (!deviceSort) std::swap(m_hostKeys, m_sortedKeys);
  s.sortMs += millisecondsSince(start);

  // Split by pair: keys are sorted by pair first, so each pair's candidates are one run, found by a binary
  // search; each pair's list is sized once and written in place. A push_back per candidate took 24 us for
  // armadillo-2766's 4,196 candidates (the thesis scene, median of 1,000 calls), this 1 us.
  const std::uint64_t maskA = (std::uint64_t(1) << bitsA) - 1, maskB = (std::uint64_t(1) << bitsB) - 1;
  std::vector<std::uint64_t> pairStart(pairs.size() + 1, 0);
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    // The last pair's run ends at the end (for it the shift below could be 64 bits).
    pairStart[i + 1] = i + 1 == pairs.size()
                           ? m_hostKeys.size()
                           : std::uint64_t(std::lower_bound(m_hostKeys.begin(), m_hostKeys.end(),
                                                            std::uint64_t(i + 1) << (bitsA + bitsB)) -
                                           m_hostKeys.begin());
    std::vector<TrianglePair>& out = results[i].candidates;
    out.resize(pairStart[i + 1] - pairStart[i]);
    const std::uint64_t* keys = m_hostKeys.data() + pairStart[i];
    for (std::size_t j = 0; j < out.size(); ++j) {
      out[j].triangleA = std::uint32_t((keys[j] >> bitsB) & maskA);
      out[j].triangleB = std::uint32_t(keys[j] & maskB);
    }
  }
  // The ranked hits are the intersecting ones only, in candidate order, so each pair's are one run as well.
  s.hits = m_hostHits.size();
  for (std::size_t first = 0, pair = 0; first < m_hostHits.size();) {
    while (m_hostHits[first].candidate >= pairStart[pair + 1]) ++pair;
    std::size_t end = first;
    while (end < m_hostHits.size() && m_hostHits[end].candidate < pairStart[pair + 1]) ++end;
    std::vector<DeviceNearHit>& out = results[pair].hits;
    out.resize(end - first);
    for (std::size_t i = first; i < end; ++i) {
      const GpucolNearHit& h = m_hostHits[i];
      DeviceNearHit& hit = out[i - first];
      hit.candidate = std::uint32_t(h.candidate - pairStart[pair]);
      hit.hasContact = (h.flags & GPUCOL_HIT_CONTACT) != 0;
      if (hit.hasContact) {
        hit.contact.point = Eigen::Vector3f(h.point[0], h.point[1], h.point[2]);
        hit.contact.normalOnB = Eigen::Vector3f(h.normal[0], h.normal[1], h.normal[2]);
        hit.contact.depth = h.depth;
        hit.contact.onFaceOfB = (h.flags & GPUCOL_HIT_ON_FACE_OF_B) != 0;
        hit.contact.sameFacing = (h.flags & GPUCOL_HIT_SAME_FACING) != 0;
        hit.contact.deepestPoint = Eigen::Vector3f(h.deepest[0], h.deepest[1], h.deepest[2]);
      }
    }
    first = end;
  }
}

std::uint64_t OpenClMeshPipeline::traverseBreadthFirst(std::size_t pairCount,
                                                       const MeshBatchDeviceOptions& options,
                                                       const cl::Buffer& entries, unsigned bitsA,
                                                       unsigned bitsB, MeshBatchDeviceStats& s) {
  const cl::Context& ctx = m_context.context();
  cl::CommandQueue& queue = m_context.queue();
  // The first front (thesis §5.4.2: optionally at depth d0), counted, scanned and written.
  const std::uint64_t paths = std::uint64_t(1) << (2 * options.startDepth);
  const std::uint64_t startItems = paths * pairCount;
  if (startItems > 0xffffffffu) {
    throw std::length_error("OpenCL mesh pipeline: start depth " + std::to_string(options.startDepth) +
                            " with " + std::to_string(pairCount) + " pairs exceeds 2^32 work-items");
  }
  auto start = Clock::now();
  setKernelArgs(m_frontStart, 0, m_pairs.buffer, m_cache.nodes(), cl_uint(pairCount),
                cl_uint(options.startDepth), cl_uint(0), m_counts.ensure(ctx, startItems * sizeof(cl_uint)),
                m_front.ensure(ctx, sizeof(GpucolFrontEntry)));
  launch(m_frontStart, startItems);
  queue.finish();
  s.traversalMs += millisecondsSince(start);
  start = Clock::now();
  std::uint32_t frontSize = m_scan.exclusiveScan(m_counts.buffer, startItems);
  s.scanMs += millisecondsSince(start);
  start = Clock::now();
  if (frontSize > 0) {
    m_frontStart.setArg(4, cl_uint(1));
    m_frontStart.setArg(6, m_front.ensure(ctx, std::size_t(frontSize) * sizeof(GpucolFrontEntry)));
    launch(m_frontStart, startItems);
    queue.finish();
  }
  s.traversalMs += millisecondsSince(start);
  // Root tests; below the roots the start kernel repeats ancestors' tests, which are not counted.
  s.nodeTests += pairCount;

  // Level by level until the front is empty; candidates are appended as sort keys (pair, triangleA,
  // triangleB).
  std::uint64_t candidateCount = 0;
  std::size_t keyCapacity = m_keys.bytes;
  while (frontSize > 0) {
    s.frontSizes.push_back(frontSize);
    const std::uint64_t n = frontSize;
    if (3 * n > 0xffffffffu)
      throw std::length_error("OpenCL mesh pipeline: the traversal front exceeds 2^32 / 3");
    start = Clock::now();
    setKernelArgs(m_frontExpand, 0, m_pairs.buffer, m_cache.nodes(), entries, m_front.buffer, cl_uint(n),
                  cl_uint(0), m_counts.ensure(ctx, 3 * n * sizeof(cl_uint)),
                  m_next.ensure(ctx, sizeof(GpucolFrontEntry)), m_keys.ensure(ctx, sizeof(cl_ulong)),
                  cl_uint(0), cl_uint(0), cl_uint(bitsA), cl_uint(bitsB));
    launch(m_frontExpand, n);
    queue.finish();
    s.traversalMs += millisecondsSince(start);

    start = Clock::now();
    const std::uint32_t total = m_scan.exclusiveScan(m_counts.buffer, 3 * n);
    cl_uint split[2] = {0, 0};
    queue.enqueueReadBuffer(m_counts.buffer, CL_FALSE, n * sizeof(cl_uint), sizeof(cl_uint), &split[0]);
    queue.enqueueReadBuffer(m_counts.buffer, CL_TRUE, 2 * n * sizeof(cl_uint), sizeof(cl_uint), &split[1]);
    s.scanMs += millisecondsSince(start);
    const std::uint32_t children = split[0];
    const std::uint32_t newCandidates = split[1] - split[0];
    s.nodeTests += total - split[1];

    start = Clock::now();
    if (candidateCount + newCandidates > 0xffffffffu) {
      throw std::length_error("OpenCL mesh pipeline: more than 2^32 - 1 candidate pairs in one batch");
    }
    if (newCandidates > 0 && (candidateCount + newCandidates) * sizeof(cl_ulong) > keyCapacity) {
      // Grown with a device-side copy of the keys so far; nothing is lost.
      const std::size_t wanted = std::max<std::size_t>(2 * keyCapacity, (candidateCount + newCandidates) * 8);
      const cl::Buffer old = m_keys.buffer;
      const std::size_t oldBytes = m_keys.bytes;
      m_keys.buffer = cl::Buffer();
      m_keys.bytes = 0;
      m_keys.ensure(ctx, wanted);
      if (candidateCount > 0 && oldBytes > 0)
        queue.enqueueCopyBuffer(old, m_keys.buffer, 0, 0, candidateCount * 8);
      keyCapacity = m_keys.bytes;
    }
    m_frontExpand.setArg(5, cl_uint(1));
    setKernelArgs(m_frontExpand, 7, m_next.ensure(ctx, std::size_t(children) * sizeof(GpucolFrontEntry)),
                  m_keys.ensure(ctx, std::max<std::size_t>(keyCapacity, 8)), cl_uint(candidateCount),
                  cl_uint(children));
    launch(m_frontExpand, n);
    queue.finish();
    s.traversalMs += millisecondsSince(start);
    candidateCount += newCandidates;
    std::swap(m_front, m_next);
    frontSize = children;
  }
  return candidateCount;
}

cl::Kernel& OpenClMeshPipeline::depthFirstKernel(int treeDepths, bool fusedNear) {
  // Each expansion pops one node pair and pushes at most four one level down, and a path has at most
  // depthA + depthB levels: 3 (depthA + depthB) + 1 entries always suffice. Rounded up to a power of two (at
  // least 64) so that few variants get built.
  std::size_t length = 64;
  while (length < 3 * std::size_t(treeDepths) + 1) length *= 2;
  const auto key = std::make_pair(length, fusedNear);
  auto found = m_depthFirst.find(key);
  if (found != m_depthFirst.end()) return found->second;
  // The CPU device's shape skips dead start paths (GPUCOL_SKIP_DEAD_PATHS: there few work-items take many
  // paths each; in a GPU's shape each path is a work-item of its own, and the skips would only add atomics).
  // The prefetch hints (GPUCOL_PREFETCH_NODE in the kernel) go only to a CPU device: a GPU's compiler refuses
  // __builtin_prefetch on a __global pointer (NVIDIA's did, with the CPU shape forced).
  std::string options = "-DGPUCOL_DFS_STACK=" + std::to_string(length);
  if (!m_context.gpuShaped()) options += " -DGPUCOL_SKIP_DEAD_PATHS";
  if (!m_context.gpuShaped() && !m_context.isGpu()) options += " -DGPUCOL_CPU_PREFETCH";
  cl::Program program;
  if (fusedNear) {
    // The near phase's functions first, then the traversal that calls them (GPUCOL_FUSED_NEAR in
    // mesh_middle_phase.cl); the shared header's include guard keeps its one copy.
    options += " -DGPUCOL_FUSED_NEAR -DGPUCOL_LANES=" + std::to_string(kPrefilterLanes);
    const std::string source = std::string(kernels::mesh_near_phase) + "\n" + kernels::mesh_middle_phase;
    program = m_context.program("mesh_traversal_with_near_phase", source.c_str(), options);
  } else {
    program = m_context.program("mesh_middle_phase", kernels::mesh_middle_phase, options);
  }
  return m_depthFirst.emplace(key, cl::Kernel(program, "mesh_traverse_depth_first")).first->second;
}

void OpenClMeshPipeline::setNearFilterArgs(std::uint64_t capacity, unsigned bitsA, unsigned bitsB) {
  const cl::Context& ctx = m_context.context();
  setKernelArgs(nearKernel(), 0, m_pairs.buffer, m_cache.triangles(), m_keys.buffer, cl_uint(capacity),
                cl_uint(bitsA), cl_uint(bitsB), m_hits.ensure(ctx, capacity * sizeof(GpucolNearHit)),
                m_counters);
}

std::uint64_t OpenClMeshPipeline::traverseDepthFirst(std::size_t pairCount, int treeDepths,
                                                     std::uint64_t smallerTriangles,
                                                     const MeshBatchDeviceOptions& options,
                                                     const cl::Buffer& entries, unsigned bitsA,
                                                     unsigned bitsB, bool chainNear, std::uint64_t& records,
                                                     MeshBatchDeviceStats& s) {
  const cl::Context& ctx = m_context.context();
  cl::CommandQueue& queue = m_context.queue();
  auto start = Clock::now();
  // The start front: deep enough for the work-items kDepthFirstItems' rule asks for (a CPU device balances
  // its threads over them), as shallow as that allows (the paths below the front's dead ends are idle
  // work-items).
  int depth = options.depthFirstStartDepth;
  if (depth < 0) {
    depth = 0;
    const std::uint64_t wanted =
        m_context.gpuShaped() ? m_computeUnits * kGpuStartPathsPerUnit
                              : std::clamp<std::uint64_t>(smallerTriangles / kTrianglesPerItem,
                                                          kDepthFirstMinItems, kDepthFirstItems);
    while (depth < kMaxStartDepth && (std::uint64_t(pairCount) << (2 * depth)) < wanted) ++depth;
  }
  const std::uint64_t items = std::uint64_t(pairCount) << (2 * depth);
  // Every work-item takes paths from counters[5] until one past the last, so the counter ends at most a
  // launch past `items`: both must stay below 2^32.
  if (items > 0x7fffffffu) {
    throw std::length_error("OpenCL mesh pipeline: depth-first start depth " + std::to_string(depth) +
                            " with " + std::to_string(pairCount) + " pairs exceeds 2^31 start paths");
  }
  // A CPU device's default path runs the near test inside the traversal (GPUCOL_FUSED_NEAR, measured there);
  // a GPU keeps them apart (not measured there: inside the traversal the near test would add to its warps'
  // divergence), and so does splitTimes, to time them.
  const bool fusedNear = chainNear && !options.splitTimes && !m_context.gpuShaped();
  cl::Kernel& kernel = depthFirstKernel(treeDepths, fusedNear);
  // A GPU runs one work-item per path; a CPU device a few work-groups per thread, whose items take the
  // paths one after another (see mesh_traverse_depth_first).
  const std::uint64_t workers =
      m_context.gpuShaped() ? items
                        : std::min<std::uint64_t>(
                              items, kCpuTraversalGroupsPerUnit * m_computeUnits * groupSize(kernel, items));
  // The key buffer keeps its size between batches; it starts at one candidate per 4 work-items.
  std::size_t capacity = std::max<std::size_t>(m_keys.bytes, items * 2) / sizeof(cl_ulong);
  cl_uint counters[kCounterWords] = {};
  double nearMs = 0;
  for (;;) {
    capacity = std::min<std::size_t>(capacity, 0xffffffffu);
    // From a host array, not waited for: the in-order queue runs it before the kernel.
    queue.enqueueWriteBuffer(m_counters, CL_FALSE, 0, sizeof m_zeroCounters, m_zeroCounters);
    setKernelArgs(kernel, 0, m_pairs.buffer, m_cache.nodes(), entries, cl_uint(pairCount), cl_uint(depth),
                  m_keys.ensure(ctx, capacity * sizeof(cl_ulong)), cl_uint(capacity), m_counters,
                  cl_uint(bitsA), cl_uint(bitsB));
    if (fusedNear) {
      setKernelArgs(kernel, 10, m_cache.triangles(), m_hits.ensure(ctx, capacity * sizeof(GpucolNearHit)));
    }
    launch(kernel, workers);
    if (chainNear) {
      // Launched over the whole capacity; the work-items past the count the kernel reads return at once. When
      // the traversal overflowed, its hits are discarded with it below.
      cl::Event traversed;
      if (!fusedNear) {
        setNearFilterArgs(capacity, bitsA, bitsB);
        if (options.splitTimes) queue.enqueueMarkerWithWaitList(nullptr, &traversed);
        launch(nearKernel(), nearItems(capacity));
      }
      if (options.splitTimes) {
        // The host waits for the traversal only to time it: the near kernel is queued behind it already.
        queue.flush();
        traversed.wait();
        s.traversalMs += millisecondsSince(start);
        start = Clock::now();
        queue.enqueueReadBuffer(m_counters, CL_TRUE, 0, sizeof counters, counters);
        nearMs += millisecondsSince(start);
        start = Clock::now();
      } else {
        // One wait for everything: the counters, and as many keys and hits as the last batch had plus an
        // eighth, are read behind the kernels; runBatch reads whatever lies past them. (Each wait on PoCL
        // costs about as much as a kernel launch.)
        queue.enqueueReadBuffer(m_counters, CL_FALSE, 0, sizeof counters, counters);
        m_keysRead = std::min<std::uint64_t>(capacity, m_lastCandidates + m_lastCandidates / 8 + 64);
        m_hitsRead = std::min<std::uint64_t>(capacity, m_lastHits + m_lastHits / 8 + 16);
        if (m_hostKeys.size() < m_keysRead) m_hostKeys.resize(m_keysRead);
        if (m_hostHits.size() < m_hitsRead) m_hostHits.resize(m_hitsRead);
        queue.enqueueReadBuffer(m_keys.buffer, CL_FALSE, 0, m_keysRead * sizeof(cl_ulong), m_hostKeys.data());
        queue.enqueueReadBuffer(m_hits.buffer, CL_FALSE, 0, m_hitsRead * sizeof(GpucolNearHit),
                                m_hostHits.data());
        queue.finish();
      }
    } else {
      queue.enqueueReadBuffer(m_counters, CL_TRUE, 0, sizeof counters, counters);
    }
    if (counters[1] != 0) {
      throw std::length_error("OpenCL mesh pipeline: more than 2^32 - 1 candidate pairs in one batch");
    }
    if (counters[0] <= capacity) break;
    // Overflow: nothing was lost, only not written; grow to what was counted and run the pass again.
    capacity = std::size_t(counters[0]) + counters[0] / 4;
    m_keys.ensure(ctx, capacity * sizeof(cl_ulong));
    capacity = m_keys.bytes / sizeof(cl_ulong);
    ++s.traversalReruns;
  }
  s.nodeTests += pairCount + ((std::uint64_t(counters[3]) << 32) | counters[2]);
  s.traversalMs += millisecondsSince(start);
  s.nearMs += nearMs;
  records = counters[4];
  return counters[0];
}

struct PipelineRegistry {
  std::mutex mutex;
  // Never destroyed, like the contexts they use (see opencl_context.cpp).
  std::map<std::string, OpenClMeshPipeline*> pipelines;
  std::set<std::string> refused;
};

PipelineRegistry& pipelineRegistry() {
  static PipelineRegistry* instance = new PipelineRegistry();
  return *instance;
}

}  // namespace

MeshBatchDevice* sharedMeshPipeline(const Config& config) {
  OpenClContext* context = OpenClContext::tryGet(config.openclDevice);
  if (context == nullptr) return nullptr;
  PipelineRegistry& r = pipelineRegistry();
  std::lock_guard<std::mutex> lock(r.mutex);
  const std::string key = context->deviceName();
  auto found = r.pipelines.find(key);
  if (found != r.pipelines.end()) return found->second;
  if (r.refused.count(key)) return nullptr;
  const std::string extensions = translateClErrors(
      "querying device extensions", [&] { return context->device().getInfo<CL_DEVICE_EXTENSIONS>(); });
  if (extensions.find("cl_khr_fp64") == std::string::npos) {
    r.refused.insert(key);
    std::cerr
        << "gpucol: the OpenCL device \"" << key
        << "\" lacks cl_khr_fp64 (the mesh near phase is a double-precision test): mesh pairs use the CPU "
           "path\n";
    return nullptr;
  }
  OpenClMeshPipeline* pipeline = new OpenClMeshPipeline(*context);
  r.pipelines.emplace(key, pipeline);
  return pipeline;
}

}  // namespace gpucol::opencl
