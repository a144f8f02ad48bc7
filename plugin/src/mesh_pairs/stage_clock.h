#pragma once
// The clock the mesh pair stages are timed by (MeshPairStats).
#include <chrono>

namespace gpucol {

/// A steady clock: stage times must not jump with the wall clock.
using Clock = std::chrono::steady_clock;

/// Milliseconds from `start` to now.
inline double millisecondsSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

}  // namespace gpucol
