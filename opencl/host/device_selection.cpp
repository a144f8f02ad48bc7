#include "opencl/host/device_selection.h"

#include <algorithm>
#include <cctype>
#include <cstdlib>

namespace gpucol::opencl {

namespace {

std::string lowerCase(std::string text) {
  std::transform(text.begin(), text.end(), text.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return text;
}

bool contains(const std::string& text, const std::string& lowerNeedle) {
  return lowerCase(text).find(lowerNeedle) != std::string::npos;
}

}  // namespace

std::string effectiveDeviceFilter(const std::string& configured) {
  const char* fromEnvironment = std::getenv("GPUCOL_OPENCL_DEVICE");
  if (fromEnvironment != nullptr && fromEnvironment[0] != '\0') {
    return fromEnvironment;
  }
  return configured;
}

std::optional<std::size_t> chooseDevice(const std::vector<DeviceCandidate>& candidates,
                                        const std::string& filter) {
  const std::string needle = lowerCase(filter);
  std::optional<std::size_t> firstMatch;
  for (std::size_t i = 0; i < candidates.size(); ++i) {
    const DeviceCandidate& c = candidates[i];
    if (!needle.empty() && !contains(c.deviceName, needle) && !contains(c.platformName, needle)) {
      continue;
    }
    if (c.isGpu) {
      return i;
    }
    if (!firstMatch) {
      firstMatch = i;
    }
  }
  return firstMatch;
}

}  // namespace gpucol::opencl
