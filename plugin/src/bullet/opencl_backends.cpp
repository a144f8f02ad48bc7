// The plugin's one entry into the OpenCL module: where GPUCOL_WITH_OPENCL builds it in, the broad phase's
// pair finder and the mesh pipeline's device come from opencl/host; without it there are none, and both
// callers take their CPU paths.
#include "broadphase/grid_pair_finder.h"
#include "mesh_pairs/mesh_batch_device.h"

#ifdef GPUCOL_WITH_OPENCL
#include "opencl/host/mesh_pipeline.h"
#include "opencl/host/opencl_pair_finder.h"
#endif

namespace gpucol {

std::unique_ptr<PairFinder> makeOpenClPairFinder(const Config& config) {
#ifdef GPUCOL_WITH_OPENCL
  return opencl::makePairFinder(config);
#else
  (void)config;
  return nullptr;
#endif
}

MeshBatchDevice* sharedMeshBatchDevice(const Config& config) {
#ifdef GPUCOL_WITH_OPENCL
  return opencl::sharedMeshPipeline(config);
#else
  (void)config;
  return nullptr;
#endif
}

}  // namespace gpucol
