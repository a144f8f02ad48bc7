// The device path's process-wide state (mesh_device_backend.h): the options of the next batches, the last
// batch's stages and Auto's measured choice.
#include "mesh_pairs/mesh_device_backend.h"

#include <mutex>

namespace gpucol::detail {
namespace {

struct DeviceBackendState {
  std::mutex mutex;
  MeshBatchDeviceOptions options;
  MeshBatchDeviceStats lastStats;
  MeasuredBackendChoice autoChoice;
};

DeviceBackendState& deviceBackendState() {
  static DeviceBackendState state;
  return state;
}

}  // namespace

void setMeshDeviceOptions(const MeshBatchDeviceOptions& options) {
  std::lock_guard<std::mutex> lock(deviceBackendState().mutex);
  deviceBackendState().options = options;
}

MeshBatchDeviceOptions meshDeviceOptions() {
  std::lock_guard<std::mutex> lock(deviceBackendState().mutex);
  return deviceBackendState().options;
}

MeshBatchDeviceStats lastMeshDeviceStats() {
  std::lock_guard<std::mutex> lock(deviceBackendState().mutex);
  return deviceBackendState().lastStats;
}

MeasuredBackendChoice& meshAutoChoice() {
  return deviceBackendState().autoChoice;
}

void recordMeshDeviceStats(const MeshBatchDeviceStats& stats) {
  std::lock_guard<std::mutex> lock(deviceBackendState().mutex);
  deviceBackendState().lastStats = stats;
}

}  // namespace gpucol::detail
