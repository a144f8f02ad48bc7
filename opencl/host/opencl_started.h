#pragma once
// What the plugin may ask of OpenCL without depending on the OpenCL module or setting a device up: how many
// contexts this process has created (gpucol::openClStarted), and whether the device OpenCL would choose is a
// GPU. Header-only, so the plugin compiles the same whether or not it was built with OpenCL. DESIGN.md's lazy
// start: Backend::Auto asks the probe only once its measured choice wants the device, and before it sets
// anything up, so short work never touches OpenCL and a machine whose only device is a CPU one (PoCL) never
// builds a context or a program for Auto, whatever the scene's size.
#include <atomic>
#include <cstdint>
#include <functional>
#include <string>

namespace gpucol::opencl {

/// Count of OpenCL contexts created so far (OpenClContext's constructor adds one when setup succeeds).
inline std::atomic<std::uint32_t>& openClContextsCreated() {
  static std::atomic<std::uint32_t> count{0};
  return count;
}

/// Says whether the device chosen for a Config::openclDevice filter is a GPU, from the platform and device
/// lists alone (no context); false when there is no OpenCL or no such device. Installed by the OpenCL module at
/// static initialisation; empty without it. Never throws.
inline std::function<bool(const std::string&)>& chosenDeviceIsGpuProbe() {
  static std::function<bool(const std::string&)> probe;
  return probe;
}

/// Count of chosenDeviceIsGpu calls that asked an installed probe (tests: short work never asks).
inline std::atomic<std::uint32_t>& deviceListsAsked() {
  static std::atomic<std::uint32_t> count{0};
  return count;
}

/// The probe's answer, false when no probe is installed.
inline bool chosenDeviceIsGpu(const std::string& configuredDevice) {
  const auto& probe = chosenDeviceIsGpuProbe();
  if (!probe) return false;
  ++deviceListsAsked();
  return probe(configuredDevice);
}

}  // namespace gpucol::opencl
