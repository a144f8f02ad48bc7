#pragma once

#include <vector>

namespace gpucol::scenes {
class WorldScene;
}

namespace gpucol::demo {

/// What a run looked like over time, one sample per recorded step: the heights of the dynamic bodies'
/// centres of mass above the ground's top face, and the kinetic energy of all of them. What time_plot draws.
struct TimeSeries {
  std::vector<double> time;           ///< Seconds since the start.
  std::vector<double> trackedHeight;  ///< The scene's tracked body (the stack's top box); empty without one.
  std::vector<double> highestHeight;  ///< The highest dynamic body (metres).
  std::vector<double> meanHeight;     ///< Mean over the dynamic bodies (metres).
  std::vector<double> kineticEnergy;  ///< Joules, linear plus rotational, all dynamic bodies.

  /// Appends the state of `scene` at `seconds`.
  void record(const scenes::WorldScene& scene, double seconds);
  /// Samples recorded.
  std::size_t size() const { return time.size(); }
};

}  // namespace gpucol::demo
