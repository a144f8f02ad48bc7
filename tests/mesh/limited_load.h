#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace gpucol::test {

/// How a load in a child process ended.
struct LimitedLoad {
  /// Loaded; threw MeshError; threw something else (std::bad_alloc at the limit); died (signal, time limit).
  enum class Outcome { kLoaded, kMeshError, kOtherException, kKilled };
  Outcome outcome = Outcome::kKilled;
  std::string message;  ///< The MeshError's or other exception's text, or how the child died.
  std::vector<float> xyz;
  std::vector<std::uint32_t> indices;
  bool closed = false;  ///< The loaded mesh's report says closed.
};

/// Runs loadMesh(path) in a forked child whose address space may grow by at most `memoryBytes` above what it
/// has when forked (setrlimit RLIMIT_AS; under AddressSanitizer, which reserves terabytes of address space,
/// no limit is set) and which SIGALRM ends after `seconds`, so a loader that would exhaust memory or hang
/// fails the test instead of the machine. The mesh or the message comes back through a pipe.
LimitedLoad loadWithinLimits(const std::string& path, std::size_t memoryBytes, unsigned seconds);

}  // namespace gpucol::test
