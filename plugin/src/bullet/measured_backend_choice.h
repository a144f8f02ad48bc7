// Backend::Auto's choice between the CPU path and an OpenCL GPU, from times measured on the device in use.
#pragma once

#include <array>
#include <cstdint>
#include <mutex>
#include <optional>
#include <vector>

namespace gpucol {

/// Chooses, for work of a given size (the triangles of a mesh batch, the proxies of a broad-phase search),
/// the path that was faster on this machine, so that Auto's crossover is the device's own, whatever device it
/// is.
///
/// Sizes fall in classes (powers of two). A class starts on the CPU path. When the faster of its first two CPU
/// calls takes less than kDeviceWorthMs, it stays there without trying the device. Otherwise its next calls alternate between
/// the two paths, the device first, until each path has kTimedCalls calls counted beyond its first (the first
/// is not counted: on the device it pays the set-up, kernel builds and uploads of meshes new to it); then the
/// class goes for good to the path with the lower median time.
///
/// The two paths give the same pairs; contacts agree within float tolerance, so which path a class took can
/// change the last bits of contacts between runs. Backend::Cpu or Backend::OpenCL fix the path.
class MeasuredBackendChoice {
 public:
  enum class Path { Cpu, Device };

  /// Calls of each path per class that are timed (after the one that is not).
  static constexpr int kTimedCalls = 3;

  /// Work that the CPU path does in less than this stays there untried on the device. Not measured: a call
  /// this short cannot save more than its own time, while starting OpenCL for it (context, kernel builds)
  /// costs hundreds of milliseconds once, and a device round trip costs tens of microseconds every time
  /// (about 50 on PoCL here, docs/measured-results.md "Mesh pairs on OpenCL").
  static constexpr double kDeviceWorthMs = 0.5;

  /// The path for the next call with work of `size`.
  Path choose(std::uint64_t size) const;

  /// The wall time of a call with work of `size` that ran on `path`.
  void record(std::uint64_t size, Path path, double milliseconds);

  /// The device failed or is not there: every class takes the CPU path from now on.
  void deviceFailed();

  /// The path decided for the class of `size`, or nothing while it is being measured.
  std::optional<Path> decided(std::uint64_t size) const;

  /// Forgets every measurement and the device's failure.
  void reset();

 private:
  struct SizeClass {
    std::vector<double> cpuMs, deviceMs;  // every call recorded, the first of each path included
    std::optional<Path> decided;
  };

  static std::size_t classOf(std::uint64_t size);

  mutable std::mutex m_mutex;
  std::array<SizeClass, 65> m_classes;
  bool m_deviceFailed = false;
};

namespace detail {

/// Lets Backend::Auto measure and use a CPU OpenCL device as it would a GPU (tests of the measured choice on
/// PoCL). Off by default: Auto then never starts OpenCL on a machine whose chosen device is a CPU.
void setAutoUsesCpuDevice(bool use);
bool autoUsesCpuDevice();

}  // namespace detail

}  // namespace gpucol
