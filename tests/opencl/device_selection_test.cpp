#include "opencl/host/device_selection.h"

#include <gtest/gtest.h>

#include <cstdlib>

namespace gpucol::opencl {
namespace {

const std::vector<DeviceCandidate> kDevices = {
    {"Portable Computing Language", "pthread-skylake-avx512-AMD EPYC", false},
    {"NVIDIA CUDA", "NVIDIA H200", true},
    {"Intel(R) OpenCL", "Intel(R) Xeon(R) CPU", false},
};

TEST(DeviceSelection, PrefersAGpuWhenNoFilter) { EXPECT_EQ(chooseDevice(kDevices, ""), 1u); }

TEST(DeviceSelection, FallsBackToTheFirstCpuDevice) {
  const std::vector<DeviceCandidate> cpus = {kDevices[0], kDevices[2]};
  EXPECT_EQ(chooseDevice(cpus, ""), 0u);
}

TEST(DeviceSelection, FilterMatchesDeviceOrPlatformCaseInsensitively) {
  EXPECT_EQ(chooseDevice(kDevices, "pthread"), 0u);
  EXPECT_EQ(chooseDevice(kDevices, "intel"), 2u);
  EXPECT_EQ(chooseDevice(kDevices, "portable computing"), 0u);
  EXPECT_EQ(chooseDevice(kDevices, "h200"), 1u);
  EXPECT_FALSE(chooseDevice(kDevices, "radeon").has_value());
  EXPECT_FALSE(chooseDevice({}, "").has_value());
}

TEST(DeviceSelection, EnvironmentOverridesTheConfiguredFilter) {
  ::setenv("GPUCOL_OPENCL_DEVICE", "pthread", 1);
  EXPECT_EQ(effectiveDeviceFilter("nvidia"), "pthread");
  ::setenv("GPUCOL_OPENCL_DEVICE", "", 1);
  EXPECT_EQ(effectiveDeviceFilter("nvidia"), "nvidia");
  ::unsetenv("GPUCOL_OPENCL_DEVICE");
  EXPECT_EQ(effectiveDeviceFilter("nvidia"), "nvidia");
}

}  // namespace
}  // namespace gpucol::opencl
