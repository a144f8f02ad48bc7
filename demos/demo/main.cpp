// gpucol-demo: a headless falling-stack demo. Builds a Bullet world (a box stack, a pile of mixed meshes in a
// bin, or copies of a mesh file dropped on the ground) with gpucol's shapes, dispatcher and broad phase, or
// with GImpact for comparison, steps it, prints progress and a summary, and fails loudly on NaN or an
// explosion.
#include <gpucol/collision_dispatcher.h>
#include <gpucol/triangle_mesh.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>
#include <iostream>
#include <memory>
#include <string>

#include "scenes/scene_run.h"
#include "scenes/world_scene.h"
#include "scenes/world_scenes.h"

namespace {

struct DemoOptions {
  std::string scene = "stack";
  std::string meshFile;
  int count = 10;
  int steps = 600;
  float dt = 1.0f / 60.0f;
  std::string backend = "gpucol";
  float gimpactMargin = gpucol::scenes::WorldOptions().gimpactMargin;
  bool noSleep = false;
  int every = 60;
};

// Exit codes: 0 the run finished, 1 bad input (options, mesh file), 2 the simulation failed (NaN, explosion,
// bodies through the ground).
constexpr int kExitBadInput = 1;
constexpr int kExitSimulationFailed = 2;

std::size_t triangleCount(const gpucol::scenes::SceneDescription& scene) {
  std::size_t triangles = 0;
  for (const auto& body : scene.bodies) triangles += scene.meshes[body.mesh]->triangleCount();
  return triangles;
}

int run(const DemoOptions& options) {
  using namespace gpucol::scenes;
  SceneDescription scene;
  if (!options.meshFile.empty()) {
    try {
      scene = makeMeshDropScene(gpucol::loadMesh(options.meshFile), options.count);
    } catch (const std::exception& e) {
      std::cerr << "gpucol-demo: cannot drop mesh '" << options.meshFile << "': " << e.what() << "\n";
      return kExitBadInput;
    }
  } else if (options.scene == "pile") {
    scene = makePileScene();
  } else {
    scene = makeStackScene();
  }

  WorldOptions worldOptions;
  worldOptions.backend = options.backend == "gimpact" ? CollisionBackend::GImpact : CollisionBackend::Gpucol;
  worldOptions.gimpactMargin = options.gimpactMargin;
  worldOptions.allowSleeping = !options.noSleep;
  WorldScene world(scene, worldOptions);

  std::printf("scene %s: %zu dynamic bodies, %zu triangles in all; backend %s", scene.name.c_str(),
              world.dynamicBodies().size(), triangleCount(scene), backendName(worldOptions.backend));
  if (worldOptions.backend == CollisionBackend::GImpact)
    std::printf(" (margin %g m)", worldOptions.gimpactMargin);
  std::printf("; %d steps of %g s; sleeping %s\n", options.steps, options.dt, options.noSleep ? "off" : "on");

  RunOptions runOptions;
  runOptions.steps = options.steps;
  runOptions.dt = options.dt;
  const RunSummary summary = runScene(
      world, runOptions,
      [&world](const StepSample& s) {
        std::printf("step %5d  contacts %5d  kinetic energy %11.4f J  deepest %.2e m  moving %3d  asleep %3d",
                    s.step, s.contacts, s.kineticEnergy, double(s.largestPenetration), s.movingBodies,
                    s.sleepingBodies);
        if (const gpucol::CollisionDispatcher* dispatcher = world.gpucolDispatcher()) {
          std::printf("  mesh pairs %llu (%.2f ms)",
                      (unsigned long long)dispatcher->lastStepStats().meshPairs,
                      dispatcher->lastStepStats().batchMilliseconds);
        }
        std::printf("\n");
        std::fflush(stdout);
      },
      options.every);

  std::printf("\nsummary (%s, %s)\n", scene.name.c_str(), backendName(worldOptions.backend));
  std::printf("  steps run             %d of %d\n", summary.steps, options.steps);
  std::printf("  steps per second      %.1f (%.3f s inside stepSimulation)\n", summary.stepsPerSecond,
              summary.stepSeconds);
  std::printf("  contacts per step     %.1f\n", summary.contactsPerStep);
  std::printf("  largest penetration   %.3e m (after step %d: %.3e m)\n", double(summary.largestPenetration),
              options.steps / 2, double(summary.restingPenetration));
  std::printf("  final kinetic energy  %.6f J\n", summary.finalKineticEnergy);
  std::printf(
      "  came to rest          %s (%d moving, %d asleep; rest = asleep or below %g m/s and %g rad/s)\n",
      summary.atRest ? "yes" : "no", summary.movingBodies, summary.sleepingBodies,
      double(runOptions.restLinearSpeed), double(runOptions.restAngularSpeed));
  std::printf("  resting drift         %.3e m (largest move of a body after step %d)\n",
              double(summary.restingDrift), options.steps / 2);
  if (scene.trackedBody >= 0) {
    std::printf("  top box height drift  %+.3e m (final minus start height)\n",
                double(summary.trackedHeightDrift));
  }
  if (summary.failure != RunFailure::None) {
    std::fflush(stdout);
    std::fprintf(stderr, "gpucol-demo: simulation failed (%s) at %s\n", failureName(summary.failure),
                 summary.failureMessage.c_str());
    return kExitSimulationFailed;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  DemoOptions options;
  CLI::App app{"gpucol-demo: bodies falling and coming to rest in a Bullet world with gpucol's collision"};
  app.add_option("--scene", options.scene,
                 "built-in scene: stack (10 boxes) or pile (50 mixed meshes in a bin)")
      ->check(CLI::IsMember({"stack", "pile"}))
      ->capture_default_str();
  CLI::Option* mesh = app.add_option("--mesh", options.meshFile,
                                     "drop --count copies of this mesh file (PLY, OBJ, STL; closed) instead");
  app.add_option("--count", options.count, "copies of --mesh")
      ->check(CLI::PositiveNumber)
      ->capture_default_str()
      ->needs(mesh);
  app.add_option("--steps", options.steps, "steps to run")->check(CLI::PositiveNumber)->capture_default_str();
  app.add_option("--dt", options.dt, "seconds per step")->check(CLI::PositiveNumber)->capture_default_str();
  app.add_option("--backend", options.backend,
                 "collision code: gpucol or gimpact (GImpact + btDbvtBroadphase)")
      ->check(CLI::IsMember({"gpucol", "gimpact"}))
      ->capture_default_str();
  app.add_option("--gimpact-margin", options.gimpactMargin, "collision margin of the GImpact shapes (metres)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  app.add_flag("--no-sleep", options.noSleep, "keep every body awake (no deactivation)");
  app.add_option("--every", options.every, "print a progress line every this many steps")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app.footer(
      "Exit status: 0 finished, 1 bad input (options, unreadable or open mesh), 2 the simulation failed "
      "(NaN, explosion, bodies through the ground).");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int status = app.exit(e);  // Prints help or the error.
    return status == 0 ? 0 : kExitBadInput;
  }
  try {
    return run(options);
  } catch (const std::exception& e) {
    std::cerr << "gpucol-demo: " << e.what() << "\n";
    return kExitBadInput;
  }
}
