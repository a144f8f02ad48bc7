#pragma once
// How collideMeshesBatch runs the device path (bvh/mesh_batch_device.h), for the benchmarks and tests that
// measure it: the options of the next batches and the stage timings of the last one. Process-wide.
#include "bvh/mesh_batch_device.h"

namespace gpucol::detail {

/// Sets the device options used by later batches that run on OpenCL (start depth, early-out test, residency,
/// sort place). Thread-safe; a batch uses the options current when it starts.
void setMeshDeviceOptions(const MeshBatchDeviceOptions& options);

/// The device options in use.
MeshBatchDeviceOptions meshDeviceOptions();

/// Stage timings and counters of the last batch that ran on the device (empty before the first).
MeshBatchDeviceStats lastMeshDeviceStats();

/// Total triangles (A's plus B's, summed over the pairs whose root boxes overlap) from which Backend::Auto
/// sends a batch to a GPU. Not measured here (no GPU in this project's runs so far): it is the thesis's
/// crossover, about 27K triangles per mesh (Tables 6.2, 6.5), for two meshes. A CPU OpenCL device (PoCL)
/// never gets a batch under Auto: it was measured slower than the CPU path at every size (README, "Mesh pairs
/// on OpenCL").
inline constexpr std::uint64_t kAutoGpuMinimumTriangles = 2 * 27000;

}  // namespace gpucol::detail
