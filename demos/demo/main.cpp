// gpucol-demo: a headless falling-stack demo. Builds a Bullet world (a box stack, a pile of mixed meshes in a
// bin, or copies of a mesh file dropped on the ground) with gpucol's shapes, dispatcher and broad phase, or
// with GImpact for comparison, steps it, prints progress and a summary, and fails loudly on NaN or an
// explosion. On request it writes a picture of the final scene and a plot of heights and kinetic energy over
// time (PNG).
#include <gpucol/collision_dispatcher.h>
#include <gpucol/triangle_mesh.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "demo/scene_picture.h"
#include "demo/time_plot.h"
#include "demo/time_series.h"
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
  float meshMargin = gpucol::scenes::WorldOptions().meshMargin;
  bool noSleep = false;
  int every = 60;
  std::string picturePath;
  std::vector<int> pictureSize{1024, 768};
  bool orthographic = false;
  std::string plotPath;
  std::vector<int> plotSize{1000, 720};
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
  worldOptions.backend = options.backend == "gimpact"          ? CollisionBackend::GImpact
                         : options.backend == "gimpact-gpucol" ? CollisionBackend::GImpactOnGpucol
                         : options.backend == "primitives"     ? CollisionBackend::Primitives
                                                               : CollisionBackend::Gpucol;
  worldOptions.gimpactMargin = options.gimpactMargin;
  worldOptions.meshMargin = options.meshMargin;
  worldOptions.allowSleeping = !options.noSleep;
  WorldScene world(scene, worldOptions);

  std::printf("scene %s: %zu dynamic bodies, %zu triangles in all; backend %s", scene.name.c_str(),
              world.dynamicBodies().size(), triangleCount(scene), backendName(worldOptions.backend));
  if (worldOptions.backend != CollisionBackend::Gpucol)
    std::printf(" (margin %g m)", worldOptions.gimpactMargin);
  std::printf("; %d steps of %g s; sleeping %s\n", options.steps, options.dt, options.noSleep ? "off" : "on");

  RunOptions runOptions;
  runOptions.steps = options.steps;
  runOptions.dt = options.dt;
  // The plot wants every step, so runScene reports every step and the progress line keeps its own pace.
  gpucol::demo::TimeSeries series;
  const bool recording = !options.plotPath.empty();
  if (recording) series.record(world, 0.0);
  const RunSummary summary = runScene(
      world, runOptions,
      [&](const StepSample& s) {
        if (recording) series.record(world, double(s.step) * double(options.dt));
        if (s.step % options.every != 0 && s.step != options.steps) return;
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
      recording ? 1 : options.every);

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
  // Written even when the run failed: the picture shows where the bodies went.
  if (!options.picturePath.empty()) {
    gpucol::demo::PictureOptions picture;
    picture.width = options.pictureSize[0];
    picture.height = options.pictureSize[1];
    picture.perspective = !options.orthographic;
    // The pile lies inside a bin with 2.5 m walls: seen from 17 degrees above the horizon (the stack's view)
    // the walls hide it, so its picture looks down at 45 degrees.
    if (scene.name == "pile") picture.elevation = 0.785f;
    gpucol::demo::writeScenePicture(world, options.picturePath, picture);
    std::printf("  picture               %s (%d x %d, the scene after step %d)\n",
                options.picturePath.c_str(), picture.width, picture.height, summary.steps);
  }
  if (recording) {
    gpucol::demo::PlotOptions plot;
    plot.width = options.plotSize[0];
    plot.height = options.plotSize[1];
    char title[256];
    std::snprintf(title, sizeof title, "gpucol-demo: %s with %s, %d steps of %.4g s", scene.name.c_str(),
                  backendName(worldOptions.backend), summary.steps, double(options.dt));
    plot.title = title;
    if (scene.name == "stack") plot.trackedLabel = "top box";
    gpucol::demo::writeTimePlot(series, options.plotPath, plot);
    std::printf("  plot                  %s (%d x %d, %zu samples)\n", options.plotPath.c_str(), plot.width,
                plot.height, series.size());
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
                 "collision code: gpucol, gimpact (GImpact + btDbvtBroadphase), gimpact-gpucol (that GImpact "
                 "world with gpucol::CollisionDispatcher) or primitives (the same bodies as Bullet's boxes, "
                 "spheres and compounds of boxes and capsules: the reference)")
      ->check(CLI::IsMember({"gpucol", "gimpact", "gimpact-gpucol", "primitives"}))
      ->capture_default_str();
  app.add_option("--mesh-margin", options.meshMargin, "collision margin of gpucol's MeshShapes (metres)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  app.add_option("--gimpact-margin", options.gimpactMargin, "collision margin of the GImpact shapes (metres)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  app.add_flag("--no-sleep", options.noSleep, "keep every body awake (no deactivation)");
  app.add_option("--every", options.every, "print a progress line every this many steps")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app.add_option("--picture", options.picturePath,
                 "write a PNG picture of the final scene, seen from the side");
  app.add_option("--picture-size", options.pictureSize, "width and height of --picture in pixels")
      ->expected(2)
      ->check(CLI::Range(64, 8192))
      ->capture_default_str();
  app.add_flag("--orthographic", options.orthographic, "draw --picture without perspective");
  app.add_option("--plot", options.plotPath,
                 "write a PNG plot of the bodies' heights and kinetic energy over the run (every step)");
  app.add_option("--plot-size", options.plotSize, "width and height of --plot in pixels")
      ->expected(2)
      ->check(CLI::Range(320, 8192))
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
