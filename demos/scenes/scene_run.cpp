#include "scenes/scene_run.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>
#include <vector>

namespace gpucol::scenes {
namespace {

StepSample sample(const WorldScene& scene, int step, const RunOptions& options) {
  StepSample s;
  s.step = step;
  s.contacts = scene.contactCount();
  s.kineticEnergy = scene.kineticEnergy();
  s.largestPenetration = scene.largestPenetration();
  s.movingBodies = scene.movingBodyCount(options.restLinearSpeed, options.restAngularSpeed);
  s.sleepingBodies = scene.sleepingBodyCount();
  return s;
}

}  // namespace

const char* failureName(RunFailure failure) {
  switch (failure) {
    case RunFailure::None:
      return "none";
    case RunFailure::NotFinite:
      return "nan";
    case RunFailure::Explosion:
      return "explosion";
    case RunFailure::FellThrough:
      return "fell-through";
  }
  return "unknown";
}

RunSummary runScene(WorldScene& scene, const RunOptions& options,
                    const std::function<void(const StepSample&)>& progress, int progressEvery) {
  RunSummary summary;
  const int settleStep = options.settleStep < 0 ? options.steps / 2 : options.settleStep;
  const double startEnergy = scene.kineticEnergy() + scene.potentialEnergy();
  const float farLimit = 100.0f * scene.description().extent;
  const int tracked = scene.description().trackedBody;
  const std::vector<btVector3> start = scene.positions();
  std::vector<btVector3> settled = settleStep == 0 ? start : std::vector<btVector3>();
  double contactSum = 0;

  auto fail = [&](RunFailure failure, int step, const std::string& what) {
    summary.failure = failure;
    std::ostringstream message;
    message << "step " << step << ": " << what;
    summary.failureMessage = message.str();
  };

  for (int step = 1; step <= options.steps; ++step) {
    const auto begin = std::chrono::steady_clock::now();
    scene.step(options.dt);
    summary.stepSeconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count();
    summary.steps = step;

    if (!scene.allFinite()) {
      fail(RunFailure::NotFinite, step, "a body's position, orientation or velocity is NaN or infinite");
      break;
    }
    const double kinetic = scene.kineticEnergy();
    const double energy = kinetic + scene.potentialEnergy();
    if (energy > 1.5 * startEnergy + 1.0) {
      std::ostringstream what;
      what << "mechanical energy " << energy << " J exceeds 1.5 x the " << startEnergy
           << " J the scene started with (energy from nowhere)";
      fail(RunFailure::Explosion, step, what.str());
      break;
    }
    if (scene.farthestBody() > farLimit) {
      std::ostringstream what;
      what << "a body is " << scene.farthestBody() << " m from the origin, beyond 100 scene extents ("
           << farLimit << " m)";
      fail(RunFailure::Explosion, step, what.str());
      break;
    }
    if (const int below = scene.bodiesBelowGround()) {
      const std::vector<btVector3> now = scene.positions();
      std::size_t first = 0;
      const float floor = scene.description().groundTop - scene.description().fallTolerance;
      while (first + 1 < now.size() && now[first].y() >= floor) ++first;
      std::ostringstream what;
      what << below
           << " bodies have their centre of mass below the ground's top face (through the ground or off "
           << "its edge); the first, dynamic body " << first << ", is at (" << now[first].x() << ", "
           << now[first].y() << ", " << now[first].z() << ")";
      fail(RunFailure::FellThrough, step, what.str());
      break;
    }

    const int contacts = scene.contactCount();
    const float penetration = scene.largestPenetration();
    contactSum += contacts;
    summary.largestPenetration = std::max(summary.largestPenetration, penetration);
    if (step == settleStep) settled = scene.positions();
    if (step > settleStep) {
      summary.restingPenetration = std::max(summary.restingPenetration, penetration);
      const std::vector<btVector3> now = scene.positions();
      for (std::size_t i = 0; i < now.size(); ++i) {
        summary.restingDrift = std::max(summary.restingDrift, now[i].distance(settled[i]));
      }
    }
    if (progress && (step % progressEvery == 0 || step == options.steps))
      progress(sample(scene, step, options));
    // Nothing wakes a world whose every body sleeps.
    if (options.stopWhenAllAsleep && scene.sleepingBodyCount() == int(scene.dynamicBodies().size())) break;
  }

  summary.stepsPerSecond = summary.stepSeconds > 0 ? summary.steps / summary.stepSeconds : 0;
  summary.contactsPerStep = summary.steps > 0 ? contactSum / summary.steps : 0;
  summary.finalKineticEnergy = scene.kineticEnergy();
  summary.movingBodies = scene.movingBodyCount(options.restLinearSpeed, options.restAngularSpeed);
  summary.sleepingBodies = scene.sleepingBodyCount();
  summary.atRest = summary.failure == RunFailure::None && summary.movingBodies == 0;
  if (tracked >= 0 && std::size_t(tracked) < start.size()) {
    summary.trackedHeightDrift =
        scene.positions()[std::size_t(tracked)].y() - start[std::size_t(tracked)].y();
  }
  return summary;
}

}  // namespace gpucol::scenes
