#pragma once
// How collideMeshesBatch runs the device path (mesh_pairs/mesh_batch_device.h), for the benchmarks and tests that
// measure it: the options of the next batches and the stage timings of the last one. Process-wide.
#include "bullet/measured_backend_choice.h"
#include "mesh_pairs/mesh_batch_device.h"

namespace gpucol::detail {

/// Sets the device options used by later batches that run on OpenCL (start depth, early-out test, residency,
/// sort place). Thread-safe; a batch uses the options current when it starts.
void setMeshDeviceOptions(const MeshBatchDeviceOptions& options);

/// The device options in use.
MeshBatchDeviceOptions meshDeviceOptions();

/// Stage timings and counters of the last batch that ran on the device (empty before the first).
MeshBatchDeviceStats lastMeshDeviceStats();

/// Keeps `stats` as the last batch's (mesh_batch.cpp, after each batch that ran on the device).
void recordMeshDeviceStats(const MeshBatchDeviceStats& stats);

/// Backend::Auto's measured choice for mesh batches (one for the process: the device is chosen once), by the
/// batch's size: its triangles, A's plus B's, summed over the pairs whose root boxes overlap. Auto measures
/// only when the chosen OpenCL device is a GPU; on a CPU device (PoCL) the CPU path was measured faster at
/// every size (docs/measured-results.md, "Mesh pairs on OpenCL") and Auto never starts OpenCL for it.
MeasuredBackendChoice& meshAutoChoice();

}  // namespace gpucol::detail
