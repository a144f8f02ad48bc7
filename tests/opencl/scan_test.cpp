#include "opencl/host/scan.h"

#include "opencl_test_device.h"

#include <cstdint>
#include <numeric>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

namespace gpucol::opencl {
namespace {

// Reference: std::exclusive_scan in 64 bits, so a wrong total cannot hide behind wrap-around.
void expectScanMatchesStd(OpenClScan& scan, std::size_t n, std::uint32_t maxValue, std::uint32_t seed) {
  std::mt19937 random(seed);
  std::uniform_int_distribution<std::uint32_t> value(0, maxValue);
  std::vector<std::uint32_t> data(n);
  for (auto& v : data) {
    v = value(random);
  }
  std::vector<std::uint64_t> expected(n);
  std::exclusive_scan(data.begin(), data.end(), expected.begin(), std::uint64_t{0});
  const std::uint64_t expectedTotal = std::accumulate(data.begin(), data.end(), std::uint64_t{0});
  ASSERT_LT(expectedTotal, std::uint64_t{1} << 32) << "test input too large for uint32";

  const std::uint32_t total = scan.exclusiveScan(data);
  EXPECT_EQ(total, expectedTotal) << "n = " << n;
  std::size_t mismatches = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (data[i] != expected[i] && mismatches++ < 5) {
      ADD_FAILURE() << "n = " << n << ": element " << i << " is " << data[i] << ", expected " << expected[i];
    }
  }
  EXPECT_EQ(mismatches, 0u) << "n = " << n;
}

/// Both block methods run on every device, whichever one Auto would pick there.
class OpenClScanMethods : public ::testing::TestWithParam<OpenClScan::Method> {};

TEST_P(OpenClScanMethods, MatchesStdExclusiveScanOnAwkwardLengths) {
  GPUCOL_REQUIRE_OPENCL(context);
  OpenClScan scan(context, GetParam());
  std::vector<std::size_t> lengths = {0, 1, 2, 3, 7, 31, 32, 33, 255, 256, 257, 511, 512, 513, 1023, 1024, 1025,
                                      4095, 4096, 4097, 8191, 8192, 8193, 65535, 65536, 65537, 100003};
  std::uint32_t seed = 1;
  for (std::size_t n : lengths) {
    expectScanMatchesStd(scan, n, 1000, seed++);
  }
}

TEST_P(OpenClScanMethods, QueuedScanWritesTheSameValuesWithoutWaiting) {
  GPUCOL_REQUIRE_OPENCL(context);
  OpenClScan scan(context, GetParam());
  std::mt19937 random(9);
  std::uniform_int_distribution<std::uint32_t> value(0, 1000);
  for (std::size_t n : {std::size_t{1}, std::size_t{33}, std::size_t{4097}, std::size_t{100003}, std::size_t{1} << 21}) {
    std::vector<std::uint32_t> data(n);
    for (auto& v : data) v = value(random);
    std::vector<std::uint32_t> expected = data;
    scan.exclusiveScan(expected);
    cl::Buffer buffer(context.context(), CL_MEM_READ_WRITE, n * sizeof(cl_uint));
    context.queue().enqueueWriteBuffer(buffer, CL_FALSE, 0, n * sizeof(cl_uint), data.data());
    scan.exclusiveScanQueued(buffer, n);
    context.queue().enqueueReadBuffer(buffer, CL_TRUE, 0, n * sizeof(cl_uint), data.data());
    EXPECT_EQ(data, expected) << "n = " << n;
  }
}

TEST_P(OpenClScanMethods, MatchesStdOnAMillionValuesOverSeveralLevels) {
  GPUCOL_REQUIRE_OPENCL(context);
  OpenClScan scan(context, GetParam());
  expectScanMatchesStd(scan, 1000000, 4000, 42);
  // Lengths past (2L)^2 need a third level whatever L the device allows; 2^21 + 1 with L <= 512 does.
  expectScanMatchesStd(scan, (std::size_t{1} << 21) + 1, 3, 43);
}

TEST_P(OpenClScanMethods, AllOnesGivesIndices) {
  GPUCOL_REQUIRE_OPENCL(context);
  OpenClScan scan(context, GetParam());
  std::vector<std::uint32_t> data(123457, 1u);
  EXPECT_EQ(scan.exclusiveScan(data), 123457u);
  for (std::size_t i = 0; i < data.size(); ++i) {
    ASSERT_EQ(data[i], i);
  }
}

TEST_P(OpenClScanMethods, TotalPastUint32IsAnError) {
  GPUCOL_REQUIRE_OPENCL(context);
  OpenClScan scan(context, GetParam());
  std::vector<std::uint32_t> data(5000, 0x00100000u);  // 5000 * 2^20 > 2^32
  EXPECT_THROW(scan.exclusiveScan(data), std::overflow_error);
  // The overflow flag is reset: a later good scan succeeds.
  std::vector<std::uint32_t> small(10, 2u);
  EXPECT_EQ(scan.exclusiveScan(small), 20u);
  // A total of exactly 2^32 - 1 is still representable.
  std::vector<std::uint32_t> edge = {0xfffffff0u, 0xfu};
  EXPECT_EQ(scan.exclusiveScan(edge), 0xffffffffu);
}

INSTANTIATE_TEST_SUITE_P(BothMethods, OpenClScanMethods,
                         ::testing::Values(OpenClScan::Method::Blelloch, OpenClScan::Method::Chunked),
                         [](const ::testing::TestParamInfo<OpenClScan::Method>& info) {
                           return info.param == OpenClScan::Method::Blelloch ? std::string("Blelloch")
                                                                             : std::string("Chunked");
                         });

TEST(OpenClContext, ProgramsAreBuiltOncePerContext) {
  GPUCOL_REQUIRE_OPENCL(context);
  OpenClScan first(context);
  const std::size_t builds = context.programBuilds();
  OpenClScan second(context);
  EXPECT_EQ(context.programBuilds(), builds);
  EXPECT_EQ(&OpenClContext::get(), &context);
}

TEST(OpenClContext, FailedBuildCarriesCallErrorNameAndLog) {
  GPUCOL_REQUIRE_OPENCL(context);
  try {
    context.program("broken", "__kernel void broken_kernel(__global int* x) { x[0] = undeclared_name; }");
    FAIL() << "building a broken program did not throw";
  } catch (const OpenClError& e) {
    EXPECT_EQ(e.call(), "clBuildProgram");
    EXPECT_STREQ(e.codeName(), "CL_BUILD_PROGRAM_FAILURE");
    EXPECT_NE(e.buildLog().find("undeclared_name"), std::string::npos) << e.buildLog();
    EXPECT_NE(std::string(e.what()).find("CL_BUILD_PROGRAM_FAILURE"), std::string::npos);
  }
}

TEST(OpenClContext, WorkGroupSizeIsAPowerOfTwoWithinDeviceLimits) {
  GPUCOL_REQUIRE_OPENCL(context);
  cl::Program program = context.program("tiny", "__kernel void k(__global int* x) { x[get_global_id(0)] = 1; }");
  cl::Kernel kernel(program, "k");
  const std::size_t size = context.workGroupSize(kernel);
  EXPECT_GT(size, 0u);
  EXPECT_EQ(size & (size - 1), 0u);
  EXPECT_LE(size, context.device().getInfo<CL_DEVICE_MAX_WORK_GROUP_SIZE>());
  const std::size_t localMemory = context.device().getInfo<CL_DEVICE_LOCAL_MEM_SIZE>();
  EXPECT_LE(context.workGroupSize(kernel, localMemory / 4), 4u);
}

}  // namespace
}  // namespace gpucol::opencl
