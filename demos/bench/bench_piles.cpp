// gpucol-bench piles: mesh piles beside the same piles of Bullet's convex shapes (issue 57's reference):
// for each scene (the mixed pile, the stack of ten boxes, the pile of thin bodies, the pile of real meshes),
// body count and seed, the pile of gpucol MeshShapes and the pile of boxes, spheres, hulls and compounds of
// them with the same masses, inertia and start poses, stepped until every body sleeps. Per run:
// the step every body was asleep, the deepest penetration over the run and once the reference had settled,
// the worst kinetic energy after the reference's first fell below 1% of its peak (as a share of that peak),
// and steps per second.
#include <algorithm>
#include <cstdio>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "bench_commands.h"
#include "bench_stats.h"
#include "scenes/pile_meshes.h"
#include "scenes/scene_run.h"
#include "scenes/world_scene.h"
#include "scenes/world_scenes.h"

namespace gpucol::bench {
namespace {

struct Options {
  std::string scene = "pile";
  std::vector<int> bodies{50, 200};
  std::vector<unsigned> seeds{1, 2, 3, 4, 5};
  int steps = 3000;
  std::string csv;
  std::string series;  // kinetic energy per step, for plots
  float meshMargin = 0;
  std::string meshDir = GPUCOL_DEFAULT_MESH_DIR;
  std::vector<std::string> meshes{"torus-1152",
                                  "armadillo-5000"};  // closed solids that HACD splits in seconds
  float meshSize = 0.3f;
  // gpucol's mesh batch and broad phase on the CPU paths: under Auto a batch's path is chosen by measured
  // times, which changes the last bits of contacts, so runs of a chaotic pile repeat only with the paths
  // fixed.
  bool cpuPaths = false;
  bool measureOverlap = true;  // the per-step overlap on the convex pieces (GJK and EPA), the slow part
};

// The stack's boxes start 1 cm apart, so that the seeds' shifted and turned boxes fall onto each other.
constexpr float kStackGap = 0.01f;

scenes::SceneDescription makeScene(const Options& o, const scenes::PileMeshes& meshes, int bodies,
                                   unsigned seed) {
  if (o.scene == "stack") return scenes::makeStackScene(bodies, kStackGap, seed);
  if (o.scene == "thin") return scenes::makeThinPileScene(bodies, seed);
  if (o.scene == "meshes") return scenes::makeRealMeshPileScene(meshes, bodies, seed);
  return scenes::makePileScene(bodies, seed);
}

/// One pile's run, step by step.
struct Trace {
  std::vector<double> energy;      // kinetic energy after each step (J)
  std::vector<float> penetration;  // deepest contact after each step (m)
  std::vector<float> overlap;      // deepest overlap of two bodies in contact after each step (m, BodyOverlap)
  int restStep = -1;               // first step after which every body slept; -1: not within the steps
  double stepsPerSecond = 0;
};

Trace runPile(const scenes::SceneDescription& description, unsigned seed, scenes::CollisionBackend backend,
              const Options& o) {
  const int bodies = int(description.bodies.size()) - 1;  // less the static bin or ground
  scenes::WorldOptions options;
  options.backend = backend;
  options.meshMargin = o.meshMargin;
  if (o.cpuPaths) {
    options.config.meshBackend = Backend::Cpu;
    options.config.broadphaseBackend = Backend::Cpu;
  }
  scenes::WorldScene world(description, options);
  scenes::RunOptions run;
  run.steps = o.steps;
  run.stopWhenAllAsleep = true;
  Trace t;
  const scenes::RunSummary summary = scenes::runScene(
      world, run,
      [&](const scenes::StepSample& s) {
        t.energy.push_back(s.kineticEnergy);
        t.penetration.push_back(s.largestPenetration);
        t.overlap.push_back(o.measureOverlap ? world.deepestBodyOverlap() : -1.0f);
        if (s.sleepingBodies == bodies && t.restStep < 0) t.restStep = s.step;
      },
      1);
  t.stepsPerSecond = summary.stepsPerSecond;
  if (summary.failure != scenes::RunFailure::None)
    std::printf("  %s %s of %d, seed %u: %s\n", scenes::backendName(backend), description.name.c_str(),
                bodies, seed, summary.failureMessage.c_str());
  return t;
}

struct Row {
  int bodies = 0;
  unsigned seed = 0;
  Trace mesh, reference;
  double peak = 0;           // the reference's peak kinetic energy
  int settledStep = -1;      // the reference's first step below 1% of its peak, after it
  double meshWorstShare = 0;  // gpucol's largest kinetic energy from settledStep on, over the peak
  double referenceWorstShare = 0;
  float meshDeepest = 0, referenceDeepest = 0;
  float meshRestingDeepest = 0, referenceRestingDeepest = 0;  // from settledStep on
  float meshOverlap = 0, referenceOverlap = 0;                // the same, measured on the bodies' solids
  float meshRestingOverlap = 0, referenceRestingOverlap = 0;
};

Row compare(const scenes::SceneDescription& description, int bodies, unsigned seed, const Options& o) {
  Row r;
  r.bodies = bodies;
  r.seed = seed;
  r.reference = runPile(description, seed, scenes::CollisionBackend::Primitives, o);
  r.mesh = runPile(description, seed, scenes::CollisionBackend::Gpucol, o);
  const std::vector<double>& e = r.reference.energy;
  const auto peakAt = std::max_element(e.begin(), e.end());
  r.peak = peakAt == e.end() ? 0 : *peakAt;
  for (auto it = peakAt; it != e.end(); ++it) {
    if (*it < 0.01 * r.peak) {
      r.settledStep = int(it - e.begin());
      break;
    }
  }
  // A run that stopped because every body slept holds zero energy from there on.
  auto worstFrom = [&](const Trace& t) {
    double worst = 0;
    for (std::size_t i = std::size_t(std::max(0, r.settledStep)); i < t.energy.size(); ++i)
      worst = std::max(worst, t.energy[i]);
    return r.peak > 0 ? worst / r.peak : 0.0;
  };
  auto deepestFrom = [&](const std::vector<float>& depths, int from) {
    float deepest = 0;
    for (std::size_t i = std::size_t(std::max(0, from)); i < depths.size(); ++i)
      deepest = std::max(deepest, depths[i]);
    return deepest;
  };
  if (r.settledStep >= 0) {
    r.meshWorstShare = worstFrom(r.mesh);
    r.referenceWorstShare = worstFrom(r.reference);
    r.meshRestingDeepest = deepestFrom(r.mesh.penetration, r.settledStep);
    r.referenceRestingDeepest = deepestFrom(r.reference.penetration, r.settledStep);
    r.meshRestingOverlap = deepestFrom(r.mesh.overlap, r.settledStep);
    r.referenceRestingOverlap = deepestFrom(r.reference.overlap, r.settledStep);
  }
  r.meshDeepest = deepestFrom(r.mesh.penetration, 0);
  r.referenceDeepest = deepestFrom(r.reference.penetration, 0);
  r.meshOverlap = deepestFrom(r.mesh.overlap, 0);
  r.referenceOverlap = deepestFrom(r.reference.overlap, 0);
  if (!o.measureOverlap) {
    r.meshOverlap = r.referenceOverlap = r.meshRestingOverlap = r.referenceRestingOverlap = -1;
  }
  return r;
}

void runAll(const Options& o) {
  scenes::PileMeshes meshes;
  if (o.scene == "meshes") {
    std::vector<std::string> paths;
    for (const std::string& name : o.meshes) paths.push_back(o.meshDir + "/" + name + ".ply");
    meshes = scenes::loadPileMeshes(paths, o.meshSize);
    for (std::size_t i = 0; i < o.meshes.size(); ++i)
      std::printf("%s: %zu triangles, %zu convex hulls (HACD)\n", o.meshes[i].c_str(),
                  meshes.meshes[i]->triangleCount(), meshes.convexPieces[i].size());
  }
  std::printf(
      "Scene %s: mesh piles (gpucol MeshShape, margin %g m) beside the same piles of Bullet's convex shapes; "
      "up "
      "to %d steps of 1/60 s.\n"
      "rest: the step every body slept (-: not within the steps). deepest: the deepest contact over the run, "
      "and (after /) once the reference's kinetic energy first fell below 1%% of its peak. overlap: the same "
      "for the deepest overlap of two bodies in contact, measured on the convex pieces of their solids (GJK "
      "and EPA) in both piles. burst: the largest kinetic energy from then on, as %% of the reference's "
      "peak.\n\n",
      o.scene.c_str(), double(o.meshMargin), o.steps);
  std::printf("%6s %5s | %6s %6s %7s | %15s %15s | %15s %15s | %8s %8s | %9s %9s\n", "bodies", "seed", "rest",
              "ref", "ratio", "deepest mesh", "deepest ref", "overlap mesh", "overlap ref", "burst", "ref",
              "steps/s", "ref");
  std::ofstream csv, series;
  if (!o.csv.empty()) {
    csv.open(o.csv);
    csv << "bodies,seed,mesh_rest_step,reference_rest_step,mesh_deepest_m,reference_deepest_m,"
           "mesh_resting_deepest_m,reference_resting_deepest_m,reference_peak_j,reference_settled_step,"
           "mesh_worst_share,reference_worst_share,mesh_steps_per_second,reference_steps_per_second,"
           "mesh_overlap_m,reference_overlap_m,mesh_resting_overlap_m,reference_resting_overlap_m\n";
  }
  if (!o.series.empty()) {
    series.open(o.series);
    series << "bodies,seed,backend,step,kinetic_energy_j\n";
  }
  for (int n : o.bodies) {
    std::vector<double> ratios;
    for (unsigned seed : o.seeds) {
      const Row r = compare(makeScene(o, meshes, n, seed), n, seed, o);
      const double ratio = r.mesh.restStep > 0 && r.reference.restStep > 0
                               ? double(r.mesh.restStep) / double(r.reference.restStep)
                               : -1;
      if (ratio > 0) ratios.push_back(ratio);
      auto rest = [](int step) { return step < 0 ? std::string("-") : std::to_string(step); };
      std::printf(
          "%6d %5u | %6s %6s %7.2f | %6.3f / %6.3f %6.3f / %6.3f | %6.3f / %6.3f %6.3f / %6.3f | %7.2f%% %7.2f%% | "
          "%9.1f %9.1f\n",
          n, seed, rest(r.mesh.restStep).c_str(), rest(r.reference.restStep).c_str(), ratio,
          double(r.meshDeepest), double(r.meshRestingDeepest), double(r.referenceDeepest),
          double(r.referenceRestingDeepest), double(r.meshOverlap), double(r.meshRestingOverlap),
          double(r.referenceOverlap), double(r.referenceRestingOverlap), 100 * r.meshWorstShare,
          100 * r.referenceWorstShare, r.mesh.stepsPerSecond, r.reference.stepsPerSecond);
      std::fflush(stdout);
      if (csv) {
        csv << n << ',' << seed << ',' << r.mesh.restStep << ',' << r.reference.restStep << ','
            << r.meshDeepest << ',' << r.referenceDeepest << ',' << r.meshRestingDeepest << ','
            << r.referenceRestingDeepest << ',' << r.peak << ',' << r.settledStep << ',' << r.meshWorstShare
            << ',' << r.referenceWorstShare << ',' << r.mesh.stepsPerSecond << ','
            << r.reference.stepsPerSecond << ',' << r.meshOverlap << ',' << r.referenceOverlap << ','
            << r.meshRestingOverlap << ',' << r.referenceRestingOverlap << '\n';
      }
      if (series) {
        for (std::size_t i = 0; i < r.mesh.energy.size(); ++i)
          series << n << ',' << seed << ",gpucol," << i + 1 << ',' << r.mesh.energy[i] << '\n';
        for (std::size_t i = 0; i < r.reference.energy.size(); ++i)
          series << n << ',' << seed << ",primitives," << i + 1 << ',' << r.reference.energy[i] << '\n';
      }
    }
    if (!ratios.empty())
      std::printf("%6d bodies: median rest ratio %.2f over %zu seeds that both came to rest\n", n, median(ratios),
                  ratios.size());
  }
}

const CommandRegistration kRegistration([](CLI::App& app) {
  auto options = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand(
      "piles",
      "mesh piles beside the same piles of Bullet's convex shapes: steps to rest, deepest penetration, energy "
      "bursts after settling, steps per second, per body count and seed");
  cmd->footer("Example: gpucol-bench piles --bodies 50,200 --seeds 1,2,3,4,5 --steps 3000 --csv piles.csv");
  cmd->add_option(
         "--scene", options->scene,
         "pile (boxes, spheres, tori, L-shapes), stack (boxes on one another; --bodies counts them), "
         "thin (rods, plates, thin tori, crosses) or meshes (real meshes, --meshes)")
      ->check(CLI::IsMember({"pile", "stack", "thin", "meshes"}))
      ->capture_default_str();
  cmd->add_option("--bodies", options->bodies, "body counts")->delimiter(',')->capture_default_str();
  cmd->add_option("--seeds", options->seeds, "seeds of the start poses")->delimiter(',')->capture_default_str();
  cmd->add_option("--steps", options->steps, "most steps per pile")->check(CLI::PositiveNumber)->capture_default_str();
  cmd->add_option("--csv", options->csv, "also write the rows to this CSV file");
  cmd->add_option("--series", options->series, "write each pile's kinetic energy per step to this CSV file");
  cmd->add_option("--mesh-margin", options->meshMargin, "collision margin of the MeshShapes (m)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->add_option("--mesh-dir", options->meshDir, "folder of the real meshes (scene meshes)")
      ->capture_default_str();
  cmd->add_option("--meshes", options->meshes, "real meshes of the scene meshes, by file name without .ply")
      ->delimiter(',')
      ->capture_default_str();
  cmd->add_option("--mesh-size", options->meshSize, "largest side of each real mesh's bounding box (m)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_flag(
      "--cpu-paths", options->cpuPaths,
      "run gpucol's mesh batch and broad phase on the CPU, so that a seed's run repeats exactly (under "
      "Auto the measured choice of path changes the last bits of contacts)");
  cmd->add_flag("--no-overlap{false}", options->measureOverlap,
                "skip the overlap of two bodies measured on their convex pieces every step (its columns are "
                "then -1): many seeds in little time");
  cmd->callback([options] { runAll(*options); });
});

}  // namespace
}  // namespace gpucol::bench
