#pragma once

#include "mesh_pairs/mesh_batch_device.h"
#include "gpucol/config.h"

namespace gpucol::opencl {

/// The OpenCL mesh pipeline of `config`'s device (one per device, kept until the process ends): resident mesh
/// data, the breadth-first middle phase of mesh_middle_phase.cl and the near phase of mesh_near_phase.cl over
/// a whole batch, with scan.cl and radix_sort.cl. Returns nullptr, after saying why once on stderr, when
/// OpenCL is not usable or the device lacks cl_khr_fp64 (the near phase is the CPU's double test); the caller
/// then takes the CPU path. Throws OpenClError when the programs fail to build on a usable device.
MeshBatchDevice* sharedMeshPipeline(const Config& config);

}  // namespace gpucol::opencl
