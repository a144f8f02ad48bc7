// Backend::Auto's measured choice (bullet/measured_backend_choice.h) on made-up times.
#include "bullet/measured_backend_choice.h"

#include <gtest/gtest.h>

#include <vector>

namespace gpucol {
namespace {

using Path = MeasuredBackendChoice::Path;

/// Runs the choice for `size` until it decides, with every call on `path` taking `ms(path, call)`; returns
/// the paths taken in order.
template <typename Times>
std::vector<Path> measure(MeasuredBackendChoice& choice, std::uint64_t size, Times ms) {
  std::vector<Path> taken;
  int calls[2] = {0, 0};
  while (!choice.decided(size) && taken.size() < 100) {
    const Path p = choice.choose(size);
    taken.push_back(p);
    choice.record(size, p, ms(p, calls[int(p)]++));
  }
  return taken;
}

TEST(MeasuredBackendChoice, TwoCpuCallsThenAlternatesAndKeepsTheFasterDevice) {
  MeasuredBackendChoice choice;
  // The device's first call pays its set-up (50 ms) and is not counted; afterwards it is twice as fast.
  const std::vector<Path> taken = measure(choice, 5000, [](Path p, int call) {
    if (p == Path::Cpu) return 2.0;
    return call == 0 ? 50.0 : 1.0;
  });
  const std::vector<Path> expected = {Path::Cpu,    Path::Cpu, Path::Device, Path::Device,
                                      Path::Device, Path::Cpu, Path::Device, Path::Cpu};
  EXPECT_EQ(taken, expected);
  ASSERT_TRUE(choice.decided(5000));
  EXPECT_EQ(*choice.decided(5000), Path::Device);
  EXPECT_EQ(choice.choose(5000), Path::Device);
  // A decided class keeps its path whatever is recorded later.
  choice.record(5000, Path::Device, 1000.0);
  EXPECT_EQ(choice.choose(5000), Path::Device);
}

TEST(MeasuredBackendChoice, KeepsTheCpuWhenTheDeviceIsSlower) {
  MeasuredBackendChoice choice;
  measure(choice, 5000, [](Path p, int) { return p == Path::Cpu ? 2.0 : 3.0; });
  ASSERT_TRUE(choice.decided(5000));
  EXPECT_EQ(*choice.decided(5000), Path::Cpu);
}

TEST(MeasuredBackendChoice, MediansIgnoreOneSlowCall) {
  MeasuredBackendChoice choice;
  // One of the device's counted calls is slow (another tenant, a page fault): the median still sees it
  // faster.
  measure(choice, 5000, [](Path p, int call) {
    if (p == Path::Cpu) return 2.0;
    return call == 2 ? 40.0 : 1.0;
  });
  EXPECT_EQ(*choice.decided(5000), Path::Device);
}

TEST(MeasuredBackendChoice, ShortCpuWorkNeverTriesTheDevice) {
  MeasuredBackendChoice choice;
  const double shortMs = MeasuredBackendChoice::kDeviceWorthMs / 2;
  const std::vector<Path> taken = measure(choice, 100, [&](Path, int) { return shortMs; });
  EXPECT_EQ(taken, std::vector<Path>(2, Path::Cpu));
  EXPECT_EQ(*choice.decided(100), Path::Cpu);
}

TEST(MeasuredBackendChoice, ShortCpuWorkSlowedOnceNeverTriesTheDevice) {
  // The second call is slowed (another tenant, a page fault): the class still stays on the CPU.
  MeasuredBackendChoice choice;
  const double shortMs = MeasuredBackendChoice::kDeviceWorthMs / 2;
  const std::vector<Path> taken = measure(choice, 100, [&](Path, int call) { return call == 1 ? 40.0 : shortMs; });
  EXPECT_EQ(taken, std::vector<Path>(2, Path::Cpu));
  EXPECT_EQ(*choice.decided(100), Path::Cpu);
}

TEST(MeasuredBackendChoice, SizeClassesArePowersOfTwoAndIndependent) {
  MeasuredBackendChoice choice;
  measure(choice, 1024, [](Path p, int) { return p == Path::Cpu ? 2.0 : 1.0; });
  EXPECT_EQ(choice.decided(2047), Path::Device);  // same class as 1024
  EXPECT_FALSE(choice.decided(2048));             // the next class is still unmeasured
  EXPECT_FALSE(choice.decided(1023));
  EXPECT_EQ(choice.choose(2048), Path::Cpu);
  measure(choice, 4000, [](Path p, int) { return p == Path::Cpu ? 2.0 : 3.0; });
  EXPECT_EQ(choice.decided(4000), Path::Cpu);
  EXPECT_EQ(choice.decided(1500), Path::Device);
}

TEST(MeasuredBackendChoice, AFailedDeviceSendsEverythingToTheCpuUntilReset) {
  MeasuredBackendChoice choice;
  measure(choice, 1024, [](Path p, int) { return p == Path::Cpu ? 2.0 : 1.0; });
  choice.deviceFailed();
  EXPECT_EQ(choice.choose(1024), Path::Cpu);
  EXPECT_EQ(choice.decided(1024), Path::Cpu);
  EXPECT_EQ(choice.decided(1u << 20), Path::Cpu);
  choice.reset();
  EXPECT_FALSE(choice.decided(1024));
  EXPECT_EQ(choice.choose(1024), Path::Cpu);
}

TEST(MeasuredBackendChoice, ExtremeSizesHaveClasses) {
  MeasuredBackendChoice choice;
  for (std::uint64_t size : {std::uint64_t(0), std::uint64_t(1), ~std::uint64_t(0)}) {
    measure(choice, size, [](Path p, int) { return p == Path::Cpu ? 2.0 : 1.0; });
    EXPECT_EQ(choice.decided(size), Path::Device) << size;
  }
}

}  // namespace
}  // namespace gpucol
