#pragma once
// What the plugin may ask of OpenCL without depending on the OpenCL module or setting a device up: how many
// contexts this process has created (gpucol::openClStarted), and whether the device OpenCL would choose is a
// GPU (a call into the OpenCL module where GPUCOL_WITH_OPENCL builds it in; false otherwise). DESIGN.md's lazy
// start: Backend::Auto asks the probe only once its measured choice wants the device, and before it sets
// anything up, so short work never touches OpenCL and a machine whose only device is a CPU one (PoCL) never
// builds a context or a program for Auto, whatever the scene's size.
#include <atomic>
#include <cstdint>
#include <string>

namespace gpucol::opencl {

/// Count of OpenCL contexts created so far (OpenClContext's constructor adds one when setup succeeds).
inline std::atomic<std::uint32_t>& openClContextsCreated() {
  static std::atomic<std::uint32_t> count{0};
  return count;
}

#ifdef GPUCOL_WITH_OPENCL
/// Says whether the device chosen for a Config::openclDevice filter is a GPU, from the platform and device
/// lists alone (no context); false when there is no OpenCL or no such device. Never throws
/// (opencl_context.cpp).
bool probeChosenDeviceIsGpu(const std::string& configuredDevice);
#endif

/// Count of chosenDeviceIsGpu calls that asked the device lists (tests: short work never asks).
inline std::atomic<std::uint32_t>& deviceListsAsked() {
  static std::atomic<std::uint32_t> count{0};
  return count;
}

/// Whether the chosen device is a GPU; false when gpucol was built without OpenCL.
inline bool chosenDeviceIsGpu(const std::string& configuredDevice) {
#ifdef GPUCOL_WITH_OPENCL
  ++deviceListsAsked();
  return probeChosenDeviceIsGpu(configuredDevice);
#else
  (void)configuredDevice;
  return false;
#endif
}

}  // namespace gpucol::opencl
