#pragma once

// The one place that includes the OpenCL C++ bindings (opencl-clhpp-headers, CL/opencl.hpp), so every
// translation unit sees them with the same settings: OpenCL 1.2 (supported by PoCL and by GPU drivers)
// and exceptions on, so that no call's result can go unchecked. Host code catches cl::Error through
// translateClErrors() and rethrows it as gpucol::opencl::OpenClError.
#ifndef CL_HPP_TARGET_OPENCL_VERSION
#define CL_HPP_TARGET_OPENCL_VERSION 120
#endif
#ifndef CL_HPP_MINIMUM_OPENCL_VERSION
#define CL_HPP_MINIMUM_OPENCL_VERSION 120
#endif
#ifndef CL_HPP_ENABLE_EXCEPTIONS
#define CL_HPP_ENABLE_EXCEPTIONS
#endif
#include <CL/opencl.hpp>

#include "opencl/host/opencl_error.h"

#include <string>
#include <utility>

namespace gpucol::opencl {

/// Runs `body` and turns any cl::Error it throws into an OpenClError naming the failed call, the error
/// and (for program builds) the build log; `what` says what the caller was doing.
template <class Body>
decltype(auto) translateClErrors(const char* what, Body&& body) {
  try {
    return std::forward<Body>(body)();
  } catch (const cl::BuildError& e) {
    std::string log;
    for (const auto& deviceLog : e.getBuildLog()) {
      log += deviceLog.second;
    }
    throw OpenClError(what, e.what(), e.err(), log);
  } catch (const cl::Error& e) {
    throw OpenClError(what, e.what(), e.err());
  }
}

/// Sets arguments first, first + 1, ... of `kernel` to `args`, in order (one clSetKernelArg each, checked
/// like every call), so that a launch's arguments read as one list.
template <class... Args>
void setKernelArgs(cl::Kernel& kernel, cl_uint first, const Args&... args) {
  cl_uint index = first;
  (kernel.setArg(index++, args), ...);
}

}  // namespace gpucol::opencl
