// Bullet3's headers bring their own OpenCL declarations (clew); this file includes no other OpenCL header.
// Bullet3 targets OpenCL 1.x (clCreateCommandQueue and friends).
#ifndef CL_TARGET_OPENCL_VERSION
#define CL_TARGET_OPENCL_VERSION 120
#endif
#include "b3_gpu_grid_peer.h"

#include <Bullet3Common/b3Logging.h>
#include <Bullet3OpenCL/BroadphaseCollision/b3GpuGridBroadphase.h>
#include <Bullet3OpenCL/Initialize/b3OpenCLUtils.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <stdexcept>

namespace gpucol::bench {

namespace {

/// b3GpuGridBroadphase with access to its protected grid parameters: the constructor fixes the cell at 3
/// units, which only suits boxes smaller than that.
class TunableGridBroadphase : public b3GpuGridBroadphase {
 public:
  using b3GpuGridBroadphase::b3GpuGridBroadphase;

  void setCellSize(float cell) {
    for (int a = 0; a < 3; ++a) {
      m_paramsCPU.m_invCellSize[a] = 1.0f / cell;
    }
    m_paramsGPU.copyFromHostPointer(&m_paramsCPU, 1);
  }

  void clearProxies() {
    m_allAabbsCPU1.resize(0);
    m_smallAabbsMappingCPU.resize(0);
    m_largeAabbsMappingCPU.resize(0);
  }
};

/// Bullet3 prints its kernel compilation progress with b3Printf (stdout); the benchmark's tables own stdout.
void printToStderr(const char* message) {
  std::fputs(message, stderr);
}

/// Large proxies: boxes whose largest extent is more than this many times the median largest extent.
constexpr float kLargeFactor = 4.0f;

}  // namespace

struct B3GpuGridPeer::Impl {
  cl_context context = nullptr;
  cl_device_id device = nullptr;
  cl_command_queue queue = nullptr;
  std::string deviceName;
  std::unique_ptr<TunableGridBroadphase> broadphase;
  std::vector<std::uint32_t> slots;  // proxy index -> slot of ProxyArrays, in creation order
  std::vector<std::uint32_t> order;  // b3 proxy order: small first as created, then large
  std::size_t smallCount = 0;        // the first smallCount entries of order are binned
  int maxPairs = 0;
};

B3GpuGridPeer::B3GpuGridPeer(const std::string& deviceFilter) : m_impl(std::make_unique<Impl>()) {
  const std::filesystem::path cache = std::filesystem::temp_directory_path() / "gpucol-b3-kernel-cache";
  std::filesystem::create_directories(cache);
  static std::string cachePath;
  cachePath = cache.string() + "/";
  b3OpenCLUtils::setCachePath(cachePath.c_str());
  b3SetCustomPrintfFunc(printToStderr);

  cl_int err = 0;
  const int platforms = b3OpenCLUtils::getNumPlatforms(&err);
  for (int p = 0; p < platforms && m_impl->context == nullptr; ++p) {
    cl_platform_id platform = b3OpenCLUtils::getPlatform(p, &err);
    cl_context context = b3OpenCLUtils::createContextFromPlatform(platform, CL_DEVICE_TYPE_ALL, &err);
    if (context == nullptr || err != CL_SUCCESS) {
      continue;
    }
    for (int d = 0; d < b3OpenCLUtils::getNumDevices(context); ++d) {
      cl_device_id device = b3OpenCLUtils::getDevice(context, d);
      b3OpenCLDeviceInfo info;
      b3OpenCLUtils::getDeviceInfo(device, &info);
      if (deviceFilter.empty() || std::string(info.m_deviceName).find(deviceFilter) != std::string::npos) {
        m_impl->context = context;
        m_impl->device = device;
        m_impl->deviceName = info.m_deviceName;
        break;
      }
    }
    if (m_impl->context == nullptr) {
      clReleaseContext(context);
    }
  }
  if (m_impl->context == nullptr) {
    throw std::runtime_error("b3GpuGridBroadphase peer: no OpenCL device" +
                             (deviceFilter.empty() ? std::string() : " matching \"" + deviceFilter + "\""));
  }
  m_impl->queue = clCreateCommandQueue(m_impl->context, m_impl->device, 0, &err);
  if (m_impl->queue == nullptr || err != CL_SUCCESS) {
    clReleaseContext(m_impl->context);
    throw std::runtime_error("b3GpuGridBroadphase peer: clCreateCommandQueue failed with " +
                             std::to_string(err));
  }
  // Bullet3 reports kernel build failures only on stderr (b3Assert is compiled out in Debian's release
  // build); a failed build shows up as a failed launch below.
  m_impl->broadphase =
      std::make_unique<TunableGridBroadphase>(m_impl->context, m_impl->device, m_impl->queue);
}

B3GpuGridPeer::~B3GpuGridPeer() {
  m_impl->broadphase.reset();
  if (m_impl->queue != nullptr) {
    clReleaseCommandQueue(m_impl->queue);
  }
  if (m_impl->context != nullptr) {
    clReleaseContext(m_impl->context);
  }
}

const std::string& B3GpuGridPeer::deviceName() const {
  return m_impl->deviceName;
}

void B3GpuGridPeer::reset() {
  m_impl->slots.clear();
}

void B3GpuGridPeer::setBoxes(const ProxyArrays& p) {
  Impl& m = *m_impl;
  std::vector<std::uint32_t> active;
  for (std::uint32_t s = 0; s < p.count; ++s) {
    if (p.flags[s] & kProxyActive) {
      active.push_back(s);
    }
  }
  auto extent = [&](std::uint32_t s) {
    return std::max({p.maxX[s] - p.minX[s], p.maxY[s] - p.minY[s], p.maxZ[s] - p.minZ[s]});
  };
  if (active != m.slots) {
    // (Re)create: small boxes first, then large ones, as b3GpuGridBroadphase keeps them in one array.
    m.slots = active;
    std::vector<float> extents;
    for (std::uint32_t s : active) {
      extents.push_back(extent(s));
    }
    float median = 0.0f;
    if (!extents.empty()) {
      std::nth_element(extents.begin(), extents.begin() + std::ptrdiff_t(extents.size() / 2), extents.end());
      median = extents[extents.size() / 2];
    }
    m.broadphase->clearProxies();
    m.order.clear();
    for (int large = 0; large < 2; ++large) {
      for (std::uint32_t s : active) {
        if ((extent(s) > kLargeFactor * median) != (large == 1)) {
          continue;
        }
        const b3Vector3 lo = b3MakeVector3(p.minX[s], p.minY[s], p.minZ[s]);
        const b3Vector3 hi = b3MakeVector3(p.maxX[s], p.maxY[s], p.maxZ[s]);
        if (large) {
          m.broadphase->createLargeProxy(lo, hi, int(s), 1, 1);
        } else {
          m.broadphase->createProxy(lo, hi, int(s), 1, 1);
        }
        m.order.push_back(s);
      }
      if (large == 0) {
        m.smallCount = m.order.size();
      }
    }
    m.maxPairs = std::max<int>(1024, int(std::min<std::size_t>(active.size() * 8, 1u << 30)));
  }
  b3AlignedObjectArray<b3SapAabb>& boxes = m.broadphase->getAllAabbsCPU();
  float cell = 0.0f;
  for (int i = 0; i < boxes.size(); ++i) {
    const std::uint32_t s = m.order[std::size_t(i)];
    boxes[i].m_minVec = b3MakeVector3(p.minX[s], p.minY[s], p.minZ[s]);
    boxes[i].m_maxVec = b3MakeVector3(p.maxX[s], p.maxY[s], p.maxZ[s]);
    boxes[i].m_minIndices[3] = int(s);
    boxes[i].m_signedMaxIndices[3] = i;
  }
  // The cell must hold every binned box (hashing by the centre, 27 neighbours): the largest small extent.
  for (std::size_t i = 0; i < m.smallCount; ++i) {
    cell = std::max(cell, extent(m.order[i]));
  }
  m.broadphase->setCellSize(cell > 0.0f ? cell : 1.0f);
  m.broadphase->writeAabbsToGpu();
}

std::size_t B3GpuGridPeer::step() {
  Impl& m = *m_impl;
  for (;;) {
    m.broadphase->calculateOverlappingPairs(m.maxPairs);
    const int found = m.broadphase->getNumOverlap();
    if (found < m.maxPairs || m.maxPairs >= (1 << 30)) {
      return std::size_t(found);
    }
    m.maxPairs *= 2;
  }
}

std::vector<std::uint64_t> B3GpuGridPeer::pairs() const {
  b3AlignedObjectArray<b3Int4> found;
  m_impl->broadphase->getOverlappingPairsGPU().copyToHost(found);
  std::vector<std::uint64_t> keys;
  keys.reserve(std::size_t(found.size()));
  for (int i = 0; i < found.size(); ++i) {
    keys.push_back(makePairKey(std::uint32_t(found[i].x), std::uint32_t(found[i].y)));
  }
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  return keys;
}

}  // namespace gpucol::bench
