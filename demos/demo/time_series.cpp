#include "demo/time_series.h"

#include <algorithm>
#include <limits>

#include "scenes/world_scene.h"

namespace gpucol::demo {

void TimeSeries::record(const scenes::WorldScene& scene, double seconds) {
  const std::vector<btVector3> positions = scene.positions();
  const double ground = scene.description().groundTop;
  double highest = positions.empty() ? 0 : -std::numeric_limits<double>::infinity(), sum = 0;
  for (const btVector3& p : positions) {
    highest = std::max(highest, double(p.y()) - ground);
    sum += double(p.y()) - ground;
  }
  time.push_back(seconds);
  highestHeight.push_back(highest);
  meanHeight.push_back(positions.empty() ? 0 : sum / double(positions.size()));
  kineticEnergy.push_back(scene.kineticEnergy());
  const int tracked = scene.description().trackedBody;
  if (tracked >= 0 && std::size_t(tracked) < positions.size()) {
    trackedHeight.push_back(double(positions[std::size_t(tracked)].y()) - ground);
  }
}

}  // namespace gpucol::demo
