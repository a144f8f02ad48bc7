#pragma once
// Lets Backend::Auto measure and use PoCL's CPU device as it would a GPU for one test's scope
// (gpucol::detail::setAutoUsesCpuDevice), and turns that off again when the scope ends.
#include "bullet/measured_backend_choice.h"

namespace gpucol::test {

struct AutoOnCpuDevice {
  AutoOnCpuDevice() { detail::setAutoUsesCpuDevice(true); }
  ~AutoOnCpuDevice() { detail::setAutoUsesCpuDevice(false); }
  AutoOnCpuDevice(const AutoOnCpuDevice&) = delete;
  AutoOnCpuDevice& operator=(const AutoOnCpuDevice&) = delete;
};

}  // namespace gpucol::test
