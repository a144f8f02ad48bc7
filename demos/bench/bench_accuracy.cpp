// gpucol-bench accuracy: sweeps the knobs that trade run time for error (contact reduction, tessellation, leaf
// size, near phase precision, mapping-function square root, grid cell size, time step), writes one CSV row per
// setting and, with --plot, PNG plots of time against error drawn by scripts/plot_accuracy.py (matplotlib).
#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <memory>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "accuracy_row.h"
#include "bench_commands.h"

namespace gpucol::bench {
namespace {

struct AccuracyOptions {
  AccuracyContext context;
  std::vector<std::string> studies = {"mesh", "broadphase", "world"};
  std::string csvPath = "accuracy.csv";
  std::string plotDirectory;
};

// "model name" of /proc/cpuinfo and the hardware threads: the CSV says where each figure came from.
std::string machineName() {
  std::ifstream cpuinfo("/proc/cpuinfo");
  std::string line, model = "unknown CPU";
  while (std::getline(cpuinfo, line)) {
    if (line.rfind("model name", 0) == 0) {
      model = line.substr(line.find(':') + 2);
      break;
    }
  }
  return model + ", " + std::to_string(std::thread::hardware_concurrency()) + " threads";
}

void run(const AccuracyOptions& options) {
  const std::set<std::string> known = {"mesh", "broadphase", "world"};
  for (const std::string& s : options.studies) {
    if (!known.count(s)) throw std::invalid_argument("unknown study group '" + s + "' (mesh, broadphase, world)");
  }
  std::vector<AccuracyRow> rows;
  const auto wants = [&](const char* group) {
    return std::find(options.studies.begin(), options.studies.end(), group) != options.studies.end();
  };
  std::cout << "settings marked * are gpucol's defaults; ms is the median of " << options.context.runs << " runs\n";
  if (wants("mesh")) runMeshAccuracyStudies(options.context, rows);
  if (wants("broadphase")) runBroadphaseAccuracyStudies(options.context, rows);
  if (wants("world")) runWorldAccuracyStudies(options.context, rows);
  // The CPU paths are measured: the device column says so (the OpenCL paths give the same pairs and contacts).
  writeAccuracyCsv(rows, options.csvPath, machineName(), "CPU (oneTBB)");
  std::cout << "wrote " << rows.size() << " rows to " << options.csvPath << "\n";
  if (!options.plotDirectory.empty()) {
    // Debian's interpreter, where python3-matplotlib is installed (a python3 earlier on PATH may lack it).
    const std::string command = "/usr/bin/python3 \"" GPUCOL_SOURCE_DIR "/scripts/plot_accuracy.py\" \"" + options.csvPath +
                                "\" \"" + options.plotDirectory + "\"";
    if (std::system(command.c_str()) != 0) throw std::runtime_error("plotting failed: " + command);
  }
}

const CommandRegistration kRegistration([](CLI::App& app) {
  auto options = std::make_shared<AccuracyOptions>();
  options->context.meshDirectory = GPUCOL_DEFAULT_MESH_DIR;
  CLI::App* command = app.add_subcommand("accuracy", "run time against error for each knob; CSV and PNG plots");
  command->add_option("--studies", options->studies, "study groups: mesh, broadphase, world")->delimiter(',');
  command->add_option("--csv", options->csvPath, "CSV file to write (one row per setting)");
  command->add_option("--plot", options->plotDirectory, "folder for the PNG plots (needs python3-matplotlib)");
  command->add_option("--runs", options->context.runs, "timed repetitions per setting")->check(CLI::PositiveNumber);
  command->add_option("--mesh-dir", options->context.meshDirectory, "folder of the mesh files");
  command->add_flag("--quick", options->context.quick, "small scenes and few settings (checks the command works)");
  command->callback([options] { run(*options); });
});

}  // namespace
}  // namespace gpucol::bench
