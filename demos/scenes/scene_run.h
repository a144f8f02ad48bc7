#pragma once

#include <functional>
#include <string>

#include "scenes/world_scene.h"

namespace gpucol::scenes {

/// How runScene steps a world.
struct RunOptions {
  int steps = 600;          ///< Steps to run.
  float dt = 1.0f / 60.0f;  ///< Seconds per step.
  /// Step after which the bodies should be at rest: their positions then are the reference of the resting
  /// drift. Negative: half of `steps`.
  int settleStep = -1;
  /// A body is moving when it is awake and faster than these (m/s, rad/s).
  float restLinearSpeed = WorldScene::kRestLinearSpeed;
  float restAngularSpeed = WorldScene::kRestAngularSpeed;  ///< See restLinearSpeed.
  /// Stop after the first step at which every dynamic body sleeps (a world asleep stays so).
  bool stopWhenAllAsleep = false;
};

/// What the world looked like after one step, for progress lines.
struct StepSample {
  int step = 0;                  ///< Steps done (1 after the first).
  int contacts = 0;              ///< Contact points in all manifolds.
  double kineticEnergy = 0;      ///< Joules.
  float largestPenetration = 0;  ///< Metres, >= 0.
  int movingBodies = 0;          ///< Awake bodies above the rest speeds.
  int sleepingBodies = 0;        ///< Bodies Bullet put to sleep.
};

/// Why a run stopped early.
enum class RunFailure {
  None,        ///< Ran every step.
  NotFinite,   ///< A position, orientation or velocity became NaN or infinite.
  Explosion,   ///< Energy grew well beyond what the scene started with, or a body flew far out of the scene.
  FellThrough  ///< A body's centre of mass went below the ground's top face.
};

/// What a run measured.
struct RunSummary {
  RunFailure failure = RunFailure::None;  ///< None when every step ran.
  std::string failureMessage;             ///< What went wrong and at which step, for people.
  int steps = 0;                          ///< Steps run.
  double stepSeconds = 0;                 ///< Wall time inside WorldScene::step (measurements excluded).
  double stepsPerSecond = 0;              ///< steps / stepSeconds.
  double contactsPerStep = 0;             ///< Mean contact points per step.
  float largestPenetration = 0;           ///< Deepest contact over the whole run (metres).
  float restingPenetration = 0;           ///< Deepest contact after the settle step (metres).
  double finalKineticEnergy = 0;          ///< Joules, after the last step.
  bool atRest = false;                    ///< Every body asleep or below the rest speeds after the last step.
  int movingBodies = 0;                   ///< Bodies not at rest after the last step.
  int sleepingBodies = 0;                 ///< Bodies asleep after the last step.
  /// Largest distance any body's centre of mass moved away from where it was at the settle step, over every
  /// step after it (metres): the resting drift.
  float restingDrift = 0;
  /// Final height minus start height of the scene's tracked body (the stack's top box), 0 without one.
  float trackedHeightDrift = 0;
};

/// Steps `scene` and measures it. `progress`, when given, is called after every `progressEvery`-th step (and
/// after the last). Stops at the first failure: non-finite state, energy above 1.5 times the mechanical
/// energy the scene started with plus 1 J (a world without motors cannot gain energy; the solver's position
/// correction adds a little), a body farther than 100 scene extents from the origin, or a body below the
/// ground.
RunSummary runScene(WorldScene& scene, const RunOptions& options,
                    const std::function<void(const StepSample&)>& progress = {}, int progressEvery = 60);

/// A one-word name of a failure: "none", "nan", "explosion", "fell-through".
const char* failureName(RunFailure failure);

}  // namespace gpucol::scenes
