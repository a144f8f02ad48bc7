#include "opencl/host/opencl_context.h"

#include "opencl/host/opencl_started.h"

#include "opencl/host/device_selection.h"

#include <cstdlib>
#include <functional>
#include <iostream>
#include <memory>
#include <set>
#include <stdexcept>
#include <vector>

namespace gpucol::opencl {

namespace {

struct Registry {
  std::mutex mutex;
  // Keyed by the effective device filter. Contexts are never destroyed: destroying OpenCL objects from a
  // static destructor races the ICD loader's own teardown at exit, so they live until the process ends.
  std::map<std::string, OpenClContext*> contexts;
  // Filters whose setup failed, with the reason; each is said once on stderr.
  std::map<std::string, std::string> failures;
};

Registry& registry() {
  static Registry* instance = new Registry();
  return *instance;
}

std::vector<cl::Device> allDevices(std::vector<DeviceCandidate>& candidates) {
  std::vector<cl::Platform> platforms;
  // The ICD loader reports "no platform" as CL_PLATFORM_NOT_FOUND_KHR (-1001): that is "no OpenCL here".
  try {
    cl::Platform::get(&platforms);
  } catch (const cl::Error& e) {
    if (e.err() == -1001) {
      return {};
    }
    throw;
  }
  std::vector<cl::Device> devices;
  for (const cl::Platform& platform : platforms) {
    std::vector<cl::Device> platformDevices;
    try {
      platform.getDevices(CL_DEVICE_TYPE_ALL, &platformDevices);
    } catch (const cl::Error& e) {
      if (e.err() == CL_DEVICE_NOT_FOUND) {
        continue;
      }
      throw;
    }
    const std::string platformName = platform.getInfo<CL_PLATFORM_NAME>();
    for (const cl::Device& device : platformDevices) {
      DeviceCandidate candidate;
      candidate.platformName = platformName;
      candidate.deviceName = device.getInfo<CL_DEVICE_NAME>();
      candidate.isGpu = (device.getInfo<CL_DEVICE_TYPE>() & CL_DEVICE_TYPE_GPU) != 0;
      candidates.push_back(candidate);
      devices.push_back(device);
    }
  }
  return devices;
}

// The probe of opencl_started.h: the chosen device's type from the device lists, once per filter (the lists
// do not change while the process runs).

/// CL_DEVICE_HOST_UNIFIED_MEMORY, deprecated since OpenCL 2.0: a driver that no longer answers it is taken
/// to share the host's memory unless its device is a GPU.
bool hostUnifiedMemory(const cl::Device& device, bool isGpu) {
  try {
    return device.getInfo<CL_DEVICE_HOST_UNIFIED_MEMORY>() != CL_FALSE;
  } catch (const cl::Error&) {
    return !isGpu;
  }
}

/// The kernel shape (OpenClContext::gpuShaped): GPUCOL_OPENCL_SHAPE=gpu or cpu, else the device's type. Any
/// other value is refused, so that a misspelt switch does not silently test the device's own shape.
bool kernelShapeIsGpu(bool isGpu) {
  const char* shape = std::getenv("GPUCOL_OPENCL_SHAPE");
  if (shape == nullptr || shape[0] == '\0') return isGpu;
  const std::string value = shape;
  if (value == "gpu") return true;
  if (value == "cpu") return false;
  throw std::runtime_error("GPUCOL_OPENCL_SHAPE is \"" + value + "\"; it must be gpu, cpu or unset");
}

std::string hexHash(const char* source) {
  const std::size_t h = std::hash<std::string>{}(source);
  static const char* kDigits = "0123456789abcdef";
  std::string text;
  for (int shift = static_cast<int>(sizeof(h) * 8) - 4; shift >= 0; shift -= 4) {
    text += kDigits[(h >> shift) & 0xf];
  }
  return text;
}

}  // namespace

bool probeChosenDeviceIsGpu(const std::string& configured) {
  static std::mutex mutex;
  static std::map<std::string, bool> answers;
  const std::string filter = effectiveDeviceFilter(configured);
  std::lock_guard<std::mutex> lock(mutex);
  const auto found = answers.find(filter);
  if (found != answers.end()) return found->second;
  bool isGpu = false;
  try {
    std::vector<DeviceCandidate> candidates;
    allDevices(candidates);
    const std::optional<std::size_t> chosen = chooseDevice(candidates, filter);
    isGpu = chosen && candidates[*chosen].isGpu;
  } catch (const std::exception&) {
    isGpu = false;  // A failing platform query: the caller stays on the CPU, as with no device.
  }
  answers[filter] = isGpu;
  return isGpu;
}

OpenClContext::OpenClContext(const std::string& filter) {
  translateClErrors("OpenCL setup", [&] {
    std::vector<DeviceCandidate> candidates;
    std::vector<cl::Device> devices = allDevices(candidates);
    const std::optional<std::size_t> chosen = chooseDevice(candidates, filter);
    if (!chosen) {
      std::string message = devices.empty() ? "no OpenCL platform or device found"
                                            : "no OpenCL device matches \"" + filter + "\" (devices:";
      if (!devices.empty()) {
        for (const DeviceCandidate& c : candidates) {
          message += " \"" + c.deviceName + "\"";
        }
        message += ")";
      }
      throw std::runtime_error(message);
    }
    m_device = devices[*chosen];
    m_deviceName = candidates[*chosen].deviceName;
    m_isGpu = candidates[*chosen].isGpu;
    m_sharesHostMemory = hostUnifiedMemory(m_device, m_isGpu);
    m_gpuShaped = kernelShapeIsGpu(m_isGpu);
    m_context = cl::Context(m_device);
    m_queue = cl::CommandQueue(m_context, m_device);
  });
  ++openClContextsCreated();
}

OpenClContext& OpenClContext::get(const std::string& configuredDevice) {
  const std::string filter = effectiveDeviceFilter(configuredDevice);
  Registry& r = registry();
  std::lock_guard<std::mutex> lock(r.mutex);
  auto found = r.contexts.find(filter);
  if (found != r.contexts.end()) {
    return *found->second;
  }
  auto failed = r.failures.find(filter);
  if (failed != r.failures.end()) {
    throw std::runtime_error(failed->second);
  }
  try {
    OpenClContext* context = new OpenClContext(filter);
    r.contexts.emplace(filter, context);
    return *context;
  } catch (const std::exception& e) {
    r.failures.emplace(filter, e.what());
    throw;
  }
}

OpenClContext* OpenClContext::tryGet(const std::string& configuredDevice) noexcept {
  try {
    return &get(configuredDevice);
  } catch (const std::exception& e) {
    // Said once per filter: the registry remembers the failure, so later calls are silent.
    static std::mutex saidMutex;
    static std::set<std::string>* said = new std::set<std::string>();
    std::lock_guard<std::mutex> lock(saidMutex);
    const std::string filter = effectiveDeviceFilter(configuredDevice);
    if (said->insert(filter).second) {
      std::cerr << "gpucol: OpenCL is not usable, using the CPU path instead: " << e.what() << "\n";
    }
  } catch (...) {
  }
  return nullptr;
}

cl::Program OpenClContext::program(const std::string& name, const char* source, const std::string& options) {
  const std::string key = name + '\n' + options + '\n' + hexHash(source);
  std::lock_guard<std::mutex> lock(m_programMutex);
  auto found = m_programs.find(key);
  if (found != m_programs.end()) {
    return found->second;
  }
  cl::Program program = translateClErrors(("building OpenCL program " + name).c_str(), [&] {
    cl::Program p(m_context, std::string(source));
    p.build(std::vector<cl::Device>{m_device}, ("-cl-std=CL1.2 " + options).c_str());
    return p;
  });
  ++m_programBuilds;
  m_programs.emplace(key, program);
  return program;
}

std::size_t OpenClContext::programBuilds() const {
  std::lock_guard<std::mutex> lock(m_programMutex);
  return m_programBuilds;
}

std::size_t OpenClContext::workGroupSize(const cl::Kernel& kernel, std::size_t localBytesPerItem,
                                         std::size_t localBytesFixed) const {
  return translateClErrors("querying work-group limits", [&] {
    std::size_t limit = kernel.getWorkGroupInfo<CL_KERNEL_WORK_GROUP_SIZE>(m_device);
    limit = std::min(limit, m_device.getInfo<CL_DEVICE_MAX_WORK_GROUP_SIZE>());
    limit = std::min(limit, m_device.getInfo<CL_DEVICE_MAX_WORK_ITEM_SIZES>().at(0));
    if (localBytesPerItem > 0) {
      const std::size_t localMemory = m_device.getInfo<CL_DEVICE_LOCAL_MEM_SIZE>();
      const std::size_t kernelStatic = kernel.getWorkGroupInfo<CL_KERNEL_LOCAL_MEM_SIZE>(m_device);
      const std::size_t used = kernelStatic + localBytesFixed;
      if (used >= localMemory) {
        throw std::runtime_error("OpenCL kernel needs more local memory than the device has");
      }
      limit = std::min(limit, (localMemory - used) / localBytesPerItem);
    }
    if (limit == 0) {
      throw std::runtime_error("OpenCL device allows no work-group for this kernel");
    }
    std::size_t size = 1;
    while (size * 2 <= limit) {
      size *= 2;
    }
    return size;
  });
}

}  // namespace gpucol::opencl
