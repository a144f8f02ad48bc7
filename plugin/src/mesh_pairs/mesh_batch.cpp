// A batch of mesh pairs (collideMeshesBatch, and collideMeshes as a batch of one): on the device through the
// seam of mesh_batch_device.h when the backend choice wants it, else each pair on the CPU (cpu_mesh_pair.h).
#include "mesh_pairs/mesh_batch.h"

#include <tbb/parallel_for.h>

#include <optional>
#include <stdexcept>
#include <string>

#include "bullet/warn_once.h"
#include "gpucol/collide_meshes.h"
#include "gpucol/mesh_shape.h"
#include "mesh_pairs/cpu_mesh_pair.h"
#include "mesh_pairs/mesh_batch_device.h"
#include "mesh_pairs/mesh_device_backend.h"
#include "mesh_pairs/pair_frame.h"
#include "mesh_pairs/stage_clock.h"
#include "opencl/host/opencl_started.h"

namespace gpucol {
namespace {

// The batch on the device (mesh_pairs/mesh_batch_device.h), when the backend choice wants it: returns false, having
// filled nothing, when the batch is to run on the CPU instead (Auto's measured choice, Auto without a GPU, no
// device, or a device failure, which is said once). When Auto is measuring and the batch goes to the CPU,
// `timeCpu` is set to the batch's size for the caller to record the CPU path's time. Pairs whose root boxes
// miss never reach the device.
bool collideOnDevice(const std::vector<MeshPairQuery>& queries, const Config& config,
                     std::vector<MeshPairResult>& results, std::optional<std::uint64_t>& timeCpu) {
  for (const MeshPairQuery& q : queries) requireFinite(q.transformA, q.transformB);
  const auto start = Clock::now();
  std::vector<PairFrame> frames;
  frames.reserve(queries.size());
  std::vector<std::size_t> overlapping;
  std::uint64_t triangles = 0;
  for (std::size_t i = 0; i < queries.size(); ++i) {
    const MeshPairQuery& q = queries[i];
    frames.push_back(makePairFrame(*q.shapeA, q.transformA, *q.shapeB, q.transformB, q.speculativeMotion,
                                   q.speculativeDistance));
    if (rootBoxesOverlap(q.shapeA->tree(), q.shapeB->tree(), frames.back().treeMap, frames.back().candidateReach)) {
      overlapping.push_back(i);
      triangles += q.shapeA->mesh().triangleCount() + q.shapeB->mesh().triangleCount();
    }
  }
  const double rootMs = millisecondsSince(start);
  const bool autoChoice = config.meshBackend == Backend::Auto;
  const bool autoUsesCpuDevice = detail::autoUsesCpuDevice();
  MeasuredBackendChoice& measured = detail::meshAutoChoice();
  // Auto: the measured choice for this size first, then, the first time it wants the device, the device
  // lists: batches that stay on the CPU never touch OpenCL, and a machine whose only OpenCL device is a CPU
  // one never sets OpenCL up for them.
  if (autoChoice && measured.choose(triangles) == MeasuredBackendChoice::Path::Cpu) {
    if (!measured.decided(triangles)) timeCpu = triangles;
    return false;
  }
  if (autoChoice && !autoUsesCpuDevice && !opencl::chosenDeviceIsGpu(config.openclDevice)) {
    measured.deviceFailed();
    return false;
  }

  MeshBatchDevice* device = nullptr;
  try {
    device = sharedMeshBatchDevice(config);
  } catch (const std::exception& e) {
    warnOnce("mesh-opencl-setup",
             std::string("the OpenCL mesh pipeline failed to set up, using the CPU: ") + e.what());
    if (autoChoice) measured.deviceFailed();
    return false;
  }
  if (device == nullptr) {
    if (config.meshBackend == Backend::OpenCL) {
      warnOnce("mesh-opencl-absent",
               kBuiltWithOpenCl
                   ? "Backend::OpenCL was asked for mesh pairs, but no usable OpenCL device "
                     "was found: they run on the CPU"
                   : "Backend::OpenCL was asked for mesh pairs, but gpucol was built without "
                     "OpenCL: they run on the CPU");
    }
    if (autoChoice) measured.deviceFailed();
    return false;
  }
  // Auto never picks a CPU OpenCL device: the CPU path was faster on it at every size measured.
  if (autoChoice && !autoUsesCpuDevice && !device->isGpu()) {
    measured.deviceFailed();
    return false;
  }

  std::vector<DeviceMeshPair> pairs(overlapping.size());
  for (std::size_t k = 0; k < overlapping.size(); ++k) {
    const MeshPairQuery& q = queries[overlapping[k]];
    const PairFrame& frame = frames[overlapping[k]];
    DeviceMeshPair& p = pairs[k];
    p.meshA = q.shapeA->sharedMesh();
    p.meshB = q.shapeB->sharedMesh();
    p.treeA = &q.shapeA->tree();
    p.treeB = &q.shapeB->tree();
    p.frame = frame;
  }
  const MeshBatchDeviceOptions options = detail::meshDeviceOptions();
  std::vector<DeviceMeshPairResult> found;
  MeshBatchDeviceStats stats;
  try {
    device->run(pairs, options, found, &stats);
  } catch (const std::exception& e) {
    warnOnce("mesh-opencl-run",
             std::string("the OpenCL mesh pipeline failed, running mesh batches on the CPU: ") + e.what());
    if (autoChoice) measured.deviceFailed();
    return false;
  }
  detail::recordMeshDeviceStats(stats);

  // Per-pair timings: the batch's stages shared evenly among its device pairs, so that they add up to the
  // batch; node tests are counted per batch by the device (MeshBatchDeviceStats), not per pair.
  const double share = overlapping.empty() ? 0.0 : 1.0 / double(overlapping.size());
  const double middleMs = (stats.uploadMs + stats.traversalMs + stats.scanMs + stats.sortMs) * share;
  const double nearMs = (stats.prefilterMs + stats.nearMs + stats.compactionMs + stats.readbackMs) * share;
  for (std::size_t i = 0; i < queries.size(); ++i) {
    results[i] = MeshPairResult();
    results[i].stats.nodeTests = 1;
    results[i].stats.rootBoxesMissed = true;
    results[i].stats.middlePhaseMs = rootMs / double(queries.size());
  }
  for (std::size_t k = 0; k < overlapping.size(); ++k) {
    MeshPairResult& result = results[overlapping[k]];
    result.stats.rootBoxesMissed = false;
    result.stats.nodeTests = 0;
    result.stats.backendUsed = Backend::OpenCL;
    result.stats.middlePhaseMs += middleMs;
    result.stats.nearPhaseMs = nearMs;
    result.candidatePairs = std::move(found[k].candidates);
    collectHits(found[k].hits, *queries[overlapping[k]].shapeA, *queries[overlapping[k]].shapeB,
                frames[overlapping[k]], config, result);
  }
  if (autoChoice) measured.record(triangles, MeasuredBackendChoice::Path::Device, millisecondsSince(start));
  return true;
}

}  // namespace

MeshPairResult collideMeshes(const MeshShape& shapeA, const btTransform& transformA, const MeshShape& shapeB,
                             const btTransform& transformB, const Config& config) {
  MeshPairQuery query;
  query.shapeA = &shapeA;
  query.transformA = transformA;
  query.shapeB = &shapeB;
  query.transformB = transformB;
  return collideMeshes(query, config);
}

MeshPairResult collideMeshes(const MeshPairQuery& query, const Config& config) {
  return collideMeshes(query, config, nullptr);
}

MeshPairResult collideMeshes(const MeshPairQuery& query, const Config& config, CandidateCache* cache) {
  if (config.meshBackend != Backend::Cpu) return std::move(collideMeshesBatch({query}, config, {cache})[0]);
  if (query.shapeA == nullptr || query.shapeB == nullptr) {
    throw std::invalid_argument("collideMeshes: the query has a null shape");
  }
  return collidePairOnCpu(query, config, cache);
}

std::vector<MeshPairResult> collideMeshesBatch(const std::vector<MeshPairQuery>& queries,
                                               const Config& config) {
  return collideMeshesBatch(queries, config, {});
}

std::vector<MeshPairResult> collideMeshesBatch(const std::vector<MeshPairQuery>& queries,
                                               const Config& config,
                                               const std::vector<CandidateCache*>& caches) {
  if (!caches.empty() && caches.size() != queries.size()) {
    throw std::invalid_argument("collideMeshesBatch: " + std::to_string(caches.size()) + " caches for " +
                                std::to_string(queries.size()) + " queries");
  }
  for (std::size_t i = 0; i < queries.size(); ++i) {
    if (queries[i].shapeA == nullptr || queries[i].shapeB == nullptr) {
      throw std::invalid_argument("collideMeshesBatch: query " + std::to_string(i) + " has a null shape");
    }
  }
  std::vector<MeshPairResult> results(queries.size());
  std::optional<std::uint64_t> timeCpu;  // set when Auto is measuring this batch's size on the CPU path
  if (config.meshBackend != Backend::Cpu && !queries.empty() &&
      collideOnDevice(queries, config, results, timeCpu)) {
    return results;
  }
  const auto start = Clock::now();
  // Pairs run in parallel; each pair's own stages are parallel too, and oneTBB balances the nesting.
  tbb::parallel_for(std::size_t(0), queries.size(), [&](std::size_t i) {
    results[i] = collidePairOnCpu(queries[i], config, caches.empty() ? nullptr : caches[i]);
  });
  if (timeCpu) {
    detail::meshAutoChoice().record(*timeCpu, MeasuredBackendChoice::Path::Cpu, millisecondsSince(start));
  }
  return results;
}

}  // namespace gpucol
