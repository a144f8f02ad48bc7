#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

namespace gpucol::opencl {

/// What device selection needs to know of one OpenCL device.
struct DeviceCandidate {
  /// Name of the device's platform, e.g. "Portable Computing Language".
  std::string platformName;
  /// Name of the device, e.g. "pthread-skylake-avx512-AMD EPYC".
  std::string deviceName;
  /// True for CL_DEVICE_TYPE_GPU devices.
  bool isGpu = false;
};

/// The device filter in force: $GPUCOL_OPENCL_DEVICE when set and not empty, else `configured`
/// (Config::openclDevice).
std::string effectiveDeviceFilter(const std::string& configured);

/// Index in `candidates` of the device to use, or nullopt when none fits. A non-empty `filter` keeps only
/// devices whose device or platform name contains it (case-insensitive); among those a GPU is preferred,
/// else the first device (e.g. PoCL's CPU device). Ties keep enumeration order, so the choice is stable.
std::optional<std::size_t> chooseDevice(const std::vector<DeviceCandidate>& candidates,
                                        const std::string& filter);

}  // namespace gpucol::opencl
