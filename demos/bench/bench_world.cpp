// gpucol-bench world: whole Bullet worlds stepped with gpucol (MeshShape, CollisionDispatcher,
// GridBroadphase), with GImpact (btGImpactMeshShape, btCollisionDispatcher, btDbvtBroadphase) and with the
// GImpact world whose dispatcher alone is gpucol's, in one run, same scene, same steps: speed, contacts, and
// how well the bodies rest once they should.
#include <fstream>
#include <iomanip>
#include <iostream>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "bench_commands.h"
#include "bench_stats.h"
#include "scenes/scene_run.h"
#include "scenes/world_scene.h"
#include "scenes/world_scenes.h"

namespace gpucol::bench {
namespace {

struct WorldBenchOptions {
  std::vector<std::string> scenes = {"pile"};
  std::vector<std::string> backends = {"gpucol", "gimpact"};
  int steps = 900;
  // 10 s to fall and settle (measured with gpucol: kinetic energy about 1 % of its peak by step 300, the pile
  // asleep by step 540 in one run), then 300 steps in which the bodies should rest.
  int settleStep = 600;
  int runs = 3;
  float dt = 1.0f / 60.0f;
  float gimpactMargin = scenes::WorldOptions().gimpactMargin;
  bool noSleep = false;
  std::string csvPath;
};

// Medians over the runs; the simulated quantities are the same in every run (Bullet and gpucol are
// deterministic), `varied` says when they were not.
struct Row {
  std::string scene, backend;
  int bodies = 0, stepsRun = 0;
  double stepsPerSecond = 0, msPerStep = 0, contactsPerStep = 0;
  double restingDrift = 0, topDrift = 0, restingPenetration = 0, largestPenetration = 0,
         finalKineticEnergy = 0;
  int movingBodies = 0, sleepingBodies = 0;
  bool tracked = false;  // The scene has a tracked body (the stack's top box).
  std::string failure;
  bool varied = false;
};

scenes::SceneDescription makeScene(const std::string& name) {
  if (name == "pile") return scenes::makePileScene();
  if (name == "stack") return scenes::makeStackScene();
  if (name == "tori") return scenes::makeToriAndCratesScene();
  if (name == "tori-x3") return scenes::makeToriAndCratesScene(32, 1, 3);
  throw std::invalid_argument("unknown scene '" + name + "' (pile, stack, tori or tori-x3)");
}

Row measure(const std::string& sceneName, const std::string& backend, const WorldBenchOptions& options) {
  const scenes::SceneDescription description = makeScene(sceneName);
  scenes::WorldOptions worldOptions;
  worldOptions.backend = backend == "gimpact"          ? scenes::CollisionBackend::GImpact
                         : backend == "gimpact-gpucol" ? scenes::CollisionBackend::GImpactOnGpucol
                                                       : scenes::CollisionBackend::Gpucol;
  worldOptions.gimpactMargin = options.gimpactMargin;
  worldOptions.allowSleeping = !options.noSleep;
  scenes::RunOptions runOptions;
  runOptions.steps = options.steps;
  runOptions.dt = options.dt;
  runOptions.settleStep = options.settleStep;

  Row row;
  row.scene = sceneName;
  row.backend = backend;
  std::vector<double> speed, contacts, drift, resting, largest, energy;
  scenes::RunSummary first;
  for (int run = 0; run < options.runs; ++run) {
    scenes::WorldScene world(description, worldOptions);
    const scenes::RunSummary s = scenes::runScene(world, runOptions);
    if (run == 0) {
      first = s;
      row.bodies = int(world.dynamicBodies().size());
    } else if (s.steps != first.steps || s.contactsPerStep != first.contactsPerStep ||
               s.restingDrift != first.restingDrift || s.finalKineticEnergy != first.finalKineticEnergy) {
      row.varied = true;
    }
    speed.push_back(s.stepsPerSecond);
    contacts.push_back(s.contactsPerStep);
    drift.push_back(s.restingDrift);
    resting.push_back(s.restingPenetration);
    largest.push_back(s.largestPenetration);
    energy.push_back(s.finalKineticEnergy);
    std::ostringstream progress;
    progress << "  " << sceneName << " / " << backend << " run " << run + 1 << ": " << std::fixed
             << std::setprecision(1) << s.stepsPerSecond << " steps/s";
    std::cout << progress.str() << std::endl;
  }
  row.stepsRun = first.steps;
  row.stepsPerSecond = median(speed);
  row.msPerStep = row.stepsPerSecond > 0 ? 1000.0 / row.stepsPerSecond : 0;
  row.contactsPerStep = median(contacts);
  row.restingDrift = median(drift);
  row.restingPenetration = median(resting);
  row.largestPenetration = median(largest);
  row.finalKineticEnergy = median(energy);
  row.tracked = description.trackedBody >= 0;
  row.topDrift = first.trackedHeightDrift;
  row.movingBodies = first.movingBodies;
  row.sleepingBodies = first.sleepingBodies;
  row.failure = first.failure == scenes::RunFailure::None
                    ? "none"
                    : std::string(scenes::failureName(first.failure)) + " (" + first.failureMessage + ")";
  return row;
}

void printTable(const std::vector<Row>& rows, const WorldBenchOptions& options, std::ostream& out) {
  const int settle = options.settleStep < 0 ? options.steps / 2 : options.settleStep;
  out << "\n"
      << options.steps << " steps of " << options.dt << " s, median of " << options.runs
      << " runs; resting columns measured after step " << settle << "; sleeping "
      << (options.noSleep ? "off" : "on") << "; GImpact margin " << options.gimpactMargin << " m\n";
  out << "| scene | backend | bodies | steps/s | ms/step | contacts/step | resting drift m | top box drift m "
         "| resting penetration m | largest penetration m | final KE J | moving at end | asleep at end "
         "| failure |\n";
  out << "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|\n";
  for (const Row& r : rows) {
    std::ostringstream line;
    line << "| " << r.scene << " | " << r.backend << " | " << r.bodies << " | " << std::fixed
         << std::setprecision(1) << r.stepsPerSecond << " | " << std::setprecision(3) << r.msPerStep << " | "
         << std::setprecision(1) << r.contactsPerStep << " | " << std::scientific << std::setprecision(2)
         << r.restingDrift << " | ";
    if (r.tracked) {
      line << std::showpos << r.topDrift << std::noshowpos;
    } else {
      line << "-";
    }
    line << " | " << r.restingPenetration << " | " << r.largestPenetration << " | " << r.finalKineticEnergy
         << " | " << r.movingBodies << " | " << r.sleepingBodies << " | " << r.failure
         << (r.varied ? " (runs differed)" : "") << " |\n";
    out << line.str();
  }
  out << "steps/s: steps / time inside stepSimulation (collision detection, solver, integration). Resting "
         "drift: "
         "largest distance a body's centre of mass moved from where it was at the settle step. Top box "
         "drift: "
         "final minus start height of the stack's top box. Penetration: deepest contact in Bullet's "
         "manifolds "
         "(GImpact's include its margin). Moving: awake and above "
      << scenes::WorldScene::kRestLinearSpeed << " m/s or " << scenes::WorldScene::kRestAngularSpeed
      << " rad/s.\n";
}

void writeCsv(const std::vector<Row>& rows, const WorldBenchOptions& options, const std::string& path) {
  std::ofstream csv(path);
  if (!csv) throw std::runtime_error("cannot write " + path);
  csv << "scene,backend,bodies,steps,steps_run,dt,runs,settle_step,sleeping,gimpact_margin,steps_per_second,"
         "ms_per_step,contacts_per_step,resting_drift_m,top_box_drift_m,resting_penetration_m,"
         "largest_penetration_m,final_kinetic_energy_j,moving_at_end,asleep_at_end,failure,runs_differed\n";
  const int settle = options.settleStep < 0 ? options.steps / 2 : options.settleStep;
  for (const Row& r : rows) {
    csv << r.scene << ',' << r.backend << ',' << r.bodies << ',' << options.steps << ',' << r.stepsRun << ','
        << options.dt << ',' << options.runs << ',' << settle << ',' << (options.noSleep ? 0 : 1) << ','
        << options.gimpactMargin << ',' << r.stepsPerSecond << ',' << r.msPerStep << ',' << r.contactsPerStep
        << ',' << r.restingDrift << ',';
    if (r.tracked) csv << r.topDrift;
    csv << ',' << r.restingPenetration << ',' << r.largestPenetration << ',' << r.finalKineticEnergy << ','
        << r.movingBodies << ',' << r.sleepingBodies << ",\"" << r.failure << "\"," << (r.varied ? 1 : 0)
        << '\n';
  }
}

void run(const WorldBenchOptions& options) {
  if (options.settleStep >= options.steps) {
    throw std::invalid_argument("--settle " + std::to_string(options.settleStep) +
                                " leaves no resting steps in --steps " + std::to_string(options.steps));
  }
  std::vector<Row> rows;
  for (const std::string& scene : options.scenes) {
    for (const std::string& backend : options.backends) rows.push_back(measure(scene, backend, options));
  }
  printTable(rows, options, std::cout);
  if (!options.csvPath.empty()) writeCsv(rows, options, options.csvPath);
}

const CommandRegistration kRegistration([](CLI::App& app) {
  auto options = std::make_shared<WorldBenchOptions>();
  CLI::App* command = app.add_subcommand("world",
                                         "Bullet worlds stepped with gpucol and with GImpact + "
                                         "btDbvtBroadphase: speed, contacts, resting error");
  command
      ->add_option("--scenes", options->scenes,
                   "built-in scenes: pile (50 mixed meshes in a bin), stack (10 boxes), tori (32 tori and "
                   "crates in a bin), tori-x3 (the same with 9 times the triangles)")
      ->delimiter(',')
      ->check(CLI::IsMember({"pile", "stack", "tori", "tori-x3"}))
      ->capture_default_str();
  command
      ->add_option("--backends", options->backends,
                   "gpucol, gimpact, gimpact-gpucol (the GImpact world with gpucol::CollisionDispatcher)")
      ->delimiter(',')
      ->check(CLI::IsMember({"gpucol", "gimpact", "gimpact-gpucol"}))
      ->capture_default_str();
  command->add_option("--steps", options->steps, "steps per run")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  command
      ->add_option("--settle", options->settleStep,
                   "step after which bodies should rest (negative: steps / 2)")
      ->capture_default_str();
  command->add_option("--runs", options->runs, "runs per backend; medians reported")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  command->add_option("--dt", options->dt, "seconds per step")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  command
      ->add_option("--gimpact-margin", options->gimpactMargin, "collision margin of the GImpact shapes (m)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  command->add_flag("--no-sleep", options->noSleep,
                    "keep every body awake (resting contacts tested every step)");
  command->add_option("--csv", options->csvPath, "also write the rows to this CSV file");
  command->callback([options] { run(*options); });
});

}  // namespace
}  // namespace gpucol::bench
