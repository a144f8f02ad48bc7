#pragma once

#include "opencl/host/cl_api.h"

#include <cstddef>
#include <map>
#include <mutex>
#include <string>

namespace gpucol::opencl {

/// One OpenCL device with its context, in-order queue and program cache, shared by every user of that
/// device in the process. Created lazily, on the first get(), so that a program that never asks for
/// OpenCL never touches the ICD loader.
class OpenClContext {
 public:
  /// The shared context of the device chosen by `configuredDevice` (Config::openclDevice; the
  /// environment variable GPUCOL_OPENCL_DEVICE overrides it), created on first call. Throws
  /// OpenClError or std::runtime_error when there is no such device or its setup fails.
  static OpenClContext& get(const std::string& configuredDevice = {});

  /// Like get(), but returns nullptr when OpenCL is not usable, after saying why once on stderr (the
  /// caller then takes its CPU path). Never throws.
  static OpenClContext* tryGet(const std::string& configuredDevice = {}) noexcept;

  /// True when get() would succeed: callers choose between their OpenCL and CPU paths with it.
  static bool usable(const std::string& configuredDevice = {}) noexcept {
    return tryGet(configuredDevice) != nullptr;
  }

  OpenClContext(const OpenClContext&) = delete;
  OpenClContext& operator=(const OpenClContext&) = delete;

  /// The OpenCL context (one device).
  const cl::Context& context() const { return m_context; }
  /// The chosen device.
  const cl::Device& device() const { return m_device; }
  /// The in-order queue every launch of this layer goes through.
  cl::CommandQueue& queue() { return m_queue; }
  /// The device's name, e.g. "pthread-skylake-avx512-AMD EPYC".
  const std::string& deviceName() const { return m_deviceName; }
  /// True when the device is a GPU.
  bool isGpu() const { return m_isGpu; }
  /// True when kernels are launched in a GPU's shapes (one work-item per candidate, wide fronts, tile sorts)
  /// rather than a CPU device's (few work-items walking chunks, vector lanes): the device's type, unless the
  /// environment variable GPUCOL_OPENCL_SHAPE says `gpu` or `cpu` (tests run both shapes on PoCL with it).
  bool gpuShaped() const { return m_gpuShaped; }
  /// True when the device's memory is the host's (a CPU device, or a GPU that shares the host's memory):
  /// its buffers then take the process's memory.
  bool sharesHostMemory() const { return m_sharesHostMemory; }

  /// The program `name` built from `source` with `options`, built once per (name, options, source
  /// hash) and cached for the life of the process (Boost.Compute's rule). A failed build throws an
  /// OpenClError carrying the build log. Thread-safe.
  cl::Program program(const std::string& name, const char* source, const std::string& options = {});

  /// Number of programs built so far (the cache's misses); lets tests check the cache.
  std::size_t programBuilds() const;

  /// Largest power-of-two work-group size that `kernel` can be launched with on this device, given
  /// `localBytesPerItem` bytes of local memory per work-item (plus `localBytesFixed` per group). Asked
  /// of the device and the compiled kernel (CL_KERNEL_WORK_GROUP_SIZE, CL_DEVICE_LOCAL_MEM_SIZE), never
  /// assumed: PoCL's CPU device and GPUs have very different limits.
  std::size_t workGroupSize(const cl::Kernel& kernel, std::size_t localBytesPerItem = 0,
                            std::size_t localBytesFixed = 0) const;

 private:
  explicit OpenClContext(const std::string& filter);

  cl::Device m_device;
  cl::Context m_context;
  cl::CommandQueue m_queue;
  std::string m_deviceName;
  bool m_isGpu = false;
  bool m_gpuShaped = false;
  bool m_sharesHostMemory = true;

  mutable std::mutex m_programMutex;
  std::map<std::string, cl::Program> m_programs;
  std::size_t m_programBuilds = 0;
};

}  // namespace gpucol::opencl
