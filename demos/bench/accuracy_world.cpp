// The simulation's studies of `gpucol-bench accuracy`: the resting error of a stack of ten boxes (how far the top
// box sinks or rises, how deep the contacts rest) against the time step and the contact reduction, every body
// kept awake so that the contacts are tested every step.
#include <cmath>
#include <iostream>
#include <string>

#include "accuracy_row.h"
#include "scenes/scene_run.h"
#include "scenes/world_scenes.h"

namespace gpucol::bench {
namespace {

// Simulated seconds per setting: long enough to settle and rest, short enough that the awake stack stands.
constexpr double kSimulatedSeconds = 5.0;

AccuracyRow runStack(const Config& config, int stepsPerSecond, bool quick) {
  scenes::WorldOptions options;
  options.config = config;
  options.allowSleeping = false;
  scenes::WorldScene scene(scenes::makeStackScene(quick ? 4 : 10), options);
  scenes::RunOptions run;
  run.dt = 1.0f / float(stepsPerSecond);
  run.steps = int(kSimulatedSeconds * stepsPerSecond);
  const scenes::RunSummary summary = scenes::runScene(scene, run);
  AccuracyRow row;
  row.scene = std::string(quick ? "stack of 4" : "stack of 10") +
              (summary.failure == scenes::RunFailure::None ? "" : std::string(" (") +
                                                                     scenes::failureName(summary.failure) + ")");
  row.timeMs = summary.stepSeconds * 1000.0 / kSimulatedSeconds;
  row.heightDrift = std::fabs(summary.trackedHeightDrift);
  row.penetration = summary.restingPenetration;
  row.timeStep = "1/" + std::to_string(stepsPerSecond);
  row.reductionResolution = std::to_string(config.reductionResolution);
  return row;
}

void add(std::vector<AccuracyRow>& rows, AccuracyRow row, const std::string& study, const std::string& setting,
         bool isDefault) {
  row.study = study;
  // The top box more than half a box lower: the stack fell over, which the plot should say next to the point.
  row.setting = row.heightDrift > 0.5 ? setting + " (fell)" : setting;
  row.isDefault = isDefault;
  printAccuracyRow(row);
  rows.push_back(std::move(row));
}

}  // namespace

void runWorldAccuracyStudies(const AccuracyContext& context, std::vector<AccuracyRow>& rows) {
  std::cout << "time_step: a stack kept awake for " << kSimulatedSeconds
            << " s; ms is wall time per simulated second\n";
  for (int stepsPerSecond : {30, 60, 120, 240}) {
    add(rows, runStack(Config(), stepsPerSecond, context.quick), "time_step", "1/" + std::to_string(stepsPerSecond),
        stepsPerSecond == 60);
  }
  std::cout << "stack_reduction: the same stack at 1/60 s with each contact reduction resolution\n";
  const Config defaults;
  for (int resolution : {0, 1, 2, 4, 8}) {
    Config config;
    config.reductionResolution = resolution;
    add(rows, runStack(config, 60, context.quick), "stack_reduction", std::to_string(resolution),
        resolution == defaults.reductionResolution);
  }
}

}  // namespace gpucol::bench
