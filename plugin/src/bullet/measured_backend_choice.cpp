#include "bullet/measured_backend_choice.h"

#include <algorithm>
#include <atomic>

namespace gpucol {
namespace {

/// Median of the calls after the first (see MeasuredBackendChoice).
double medianOfCounted(std::vector<double> ms) {
  ms.erase(ms.begin());
  std::sort(ms.begin(), ms.end());
  return ms[ms.size() / 2];
}

std::atomic<bool>& autoUsesCpuDeviceFlag() {
  static std::atomic<bool> flag{false};
  return flag;
}

}  // namespace

std::size_t MeasuredBackendChoice::classOf(std::uint64_t size) {
  std::size_t bits = 0;
  while (bits < 64 && (size >> bits) != 0) ++bits;
  return bits;  // 0 for size 0, else floor(log2(size)) + 1
}

MeasuredBackendChoice::Path MeasuredBackendChoice::choose(std::uint64_t size) const {
  std::lock_guard<std::mutex> lock(m_mutex);
  if (m_deviceFailed) return Path::Cpu;
  const SizeClass& c = m_classes[classOf(size)];
  if (c.decided) return *c.decided;
  if (c.cpuMs.size() < 2) return Path::Cpu;
  // The path with fewer calls so far, the device on a tie.
  return c.deviceMs.size() <= c.cpuMs.size() ? Path::Device : Path::Cpu;
}

void MeasuredBackendChoice::record(std::uint64_t size, Path path, double milliseconds) {
  std::lock_guard<std::mutex> lock(m_mutex);
  SizeClass& c = m_classes[classOf(size)];
  if (c.decided) return;
  (path == Path::Cpu ? c.cpuMs : c.deviceMs).push_back(milliseconds);
  // The faster of the two: one call slowed by another tenant does not send short work to the device.
  if (c.cpuMs.size() == 2 && c.deviceMs.empty() && std::min(c.cpuMs[0], c.cpuMs[1]) < kDeviceWorthMs) {
    c.decided = Path::Cpu;
    return;
  }
  const std::size_t needed = std::size_t(kTimedCalls) + 1;
  if (c.cpuMs.size() >= needed && c.deviceMs.size() >= needed) {
    c.decided = medianOfCounted(c.deviceMs) < medianOfCounted(c.cpuMs) ? Path::Device : Path::Cpu;
  }
}

void MeasuredBackendChoice::deviceFailed() {
  std::lock_guard<std::mutex> lock(m_mutex);
  m_deviceFailed = true;
}

std::optional<MeasuredBackendChoice::Path> MeasuredBackendChoice::decided(std::uint64_t size) const {
  std::lock_guard<std::mutex> lock(m_mutex);
  if (m_deviceFailed) return Path::Cpu;
  return m_classes[classOf(size)].decided;
}

void MeasuredBackendChoice::reset() {
  std::lock_guard<std::mutex> lock(m_mutex);
  m_classes = {};
  m_deviceFailed = false;
}

namespace detail {

void setAutoUsesCpuDevice(bool use) {
  autoUsesCpuDeviceFlag() = use;
}

bool autoUsesCpuDevice() {
  return autoUsesCpuDeviceFlag();
}

}  // namespace detail

}  // namespace gpucol
