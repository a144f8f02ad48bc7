#pragma once

#include "opencl/host/opencl_context.h"

#include <gtest/gtest.h>

/// Sets `context_var` to the shared OpenCL context (one per process, so PoCL compiles each program once
/// for the whole suite), or skips the test with a clear message when no OpenCL device exists.
#define GPUCOL_REQUIRE_OPENCL(context_var)                                                         \
  ::gpucol::opencl::OpenClContext* context_var##_pointer = ::gpucol::opencl::OpenClContext::tryGet(); \
  if (context_var##_pointer == nullptr)                                                             \
    GTEST_SKIP() << "no usable OpenCL device (install pocl-opencl-icd, or check GPUCOL_OPENCL_DEVICE)"; \
  [[maybe_unused]] ::gpucol::opencl::OpenClContext& context_var = *context_var##_pointer
