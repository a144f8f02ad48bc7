// gpucol-bench crossover: where Backend::Auto puts the line between the CPU path and the OpenCL device, for
// mesh batches (by triangles) and for the broad phase (by live proxies), beside the two paths' own medians.
// Auto measures only on a GPU; on a CPU device (PoCL) it stays on the CPU and says so.
#include <btBulletCollisionCommon.h>
#include <gpucol/gpucol.h>

#include <fstream>
#include <iomanip>
#include <iostream>
#include <memory>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "bench_commands.h"
#include "bench_stats.h"
#include "mesh_pairs/mesh_device_backend.h"
#include "scenes/gimpact_peer.h"

namespace gpucol::bench {
namespace {

struct CrossoverOptions {
  std::string meshDirectory = GPUCOL_DEFAULT_MESH_DIR;
  std::string csvPath;
  bool quick = false;
  int runs = 5;
};

/// Calls Auto makes before every class has decided: 2 on the CPU, then 1 + kTimedCalls on each path.
constexpr int kAutoCalls = 2 + 2 * (1 + MeasuredBackendChoice::kTimedCalls) + 2;

struct Row {
  std::string kind, work;
  std::uint64_t size = 0;  // triangles or proxies
  double cpuMs = 0, openclMs = 0;
  std::string autoPath;
};

std::string pathName(std::optional<MeasuredBackendChoice::Path> path, bool deviceIsGpu) {
  if (!deviceIsGpu) return "cpu (device not a GPU: never measured)";
  if (!path) return "undecided";
  return *path == MeasuredBackendChoice::Path::Cpu ? "cpu" : "opencl";
}

bool openClGpu(const Config& config) {
  MeshBatchDevice* device = sharedMeshBatchDevice(config);
  return device != nullptr && device->isGpu();
}

Row meshRow(const std::string& work, const std::vector<MeshPairQuery>& queries, int runs) {
  Row row;
  row.kind = "mesh batch";
  row.work = work;
  for (const MeshPairQuery& q : queries) {
    row.size += q.shapeA->mesh().triangleCount() + q.shapeB->mesh().triangleCount();
  }
  Config config;
  for (Backend backend : {Backend::Cpu, Backend::OpenCL}) {
    config.meshBackend = backend;
    collideMeshesBatch(queries, config);  // uploads and builds, not counted
    std::vector<double> samples;
    for (int r = 0; r < runs; ++r) samples.push_back(millisecondsOf([&] { collideMeshesBatch(queries, config); }));
    (backend == Backend::Cpu ? row.cpuMs : row.openclMs) = median(samples);
  }
  config.meshBackend = Backend::Auto;
  detail::meshAutoChoice().reset();
  for (int i = 0; i < kAutoCalls; ++i) collideMeshesBatch(queries, config);
  row.autoPath = pathName(detail::meshAutoChoice().decided(row.size), openClGpu(config));
  return row;
}

/// n unit boxes in a cloud of about one box per 8 unit volumes, each drifting a little every step.
class Cloud {
 public:
  Cloud(std::size_t n, Backend backend) : m_dispatcher(&m_configuration) {
    Config config;
    config.broadphaseBackend = backend;
    m_broadphase = std::make_unique<GridBroadphase>(config);
    const float side = std::cbrt(float(n) * 8.0f);
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> position(0, side);
    for (std::size_t i = 0; i < n; ++i) {
      m_centre.emplace_back(position(rng), position(rng), position(rng));
      m_proxies.push_back(m_broadphase->createProxy(m_centre[i] - kHalf, m_centre[i] + kHalf, 0, nullptr, 1, -1,
                                                    &m_dispatcher));
    }
    m_broadphase->calculateOverlappingPairs(&m_dispatcher);
  }
  // No destroyProxy loop: Bullet's pair cache scans every pair per removed proxy (a quadratic teardown); the
  // broad phase frees its proxies when it is destroyed.
  void step() {
    const btVector3 drift(0.01f * float(++m_step % 7 - 3), 0.0f, 0.0f);
    for (std::size_t i = 0; i < m_proxies.size(); ++i) {
      m_centre[i] += drift;
      m_broadphase->setAabb(m_proxies[i], m_centre[i] - kHalf, m_centre[i] + kHalf, &m_dispatcher);
    }
    m_broadphase->calculateOverlappingPairs(&m_dispatcher);
  }
  const GridBroadphase& broadphase() const { return *m_broadphase; }

 private:
  inline static const btVector3 kHalf{0.5f, 0.5f, 0.5f};
  btDefaultCollisionConfiguration m_configuration;
  btCollisionDispatcher m_dispatcher;
  std::unique_ptr<GridBroadphase> m_broadphase;
  std::vector<btVector3> m_centre;
  std::vector<btBroadphaseProxy*> m_proxies;
  int m_step = 0;
};

Row broadphaseRow(std::size_t n, int runs, bool deviceIsGpu) {
  Row row;
  row.kind = "broad phase";
  row.work = "uniform cloud";
  row.size = n;
  for (Backend backend : {Backend::Cpu, Backend::OpenCL}) {
    Cloud cloud(n, backend);
    cloud.step();  // not counted
    std::vector<double> samples;
    for (int r = 0; r < runs; ++r) samples.push_back(millisecondsOf([&] { cloud.step(); }));
    (backend == Backend::Cpu ? row.cpuMs : row.openclMs) = median(samples);
  }
  Cloud cloud(n, Backend::Auto);
  for (int i = 0; i < kAutoCalls; ++i) cloud.step();
  const bool device = cloud.broadphase().stats().usedOpenCl;
  row.autoPath = deviceIsGpu ? (device ? "opencl" : "cpu") : pathName(std::nullopt, false);
  return row;
}

/// One row of the table, printed as soon as it is measured.
void printRow(const Row& r) {
  std::cout << std::fixed << std::setprecision(3) << "| " << r.kind << " | " << r.work << " | " << r.size << " | "
            << r.cpuMs << " | " << r.openclMs << " | " << r.autoPath << " |" << std::endl;
}

void run(const CrossoverOptions& options) {
  Config probe;
  probe.meshBackend = Backend::OpenCL;
  const bool gpu = openClGpu(probe);
  std::cout << "Backend::Auto's choice after " << kAutoCalls << " calls, beside each path's median of "
            << options.runs << " (ms); device is " << (gpu ? "a GPU" : "not a GPU") << "\n";
  std::cout << "| work | what | size | CPU ms | OpenCL ms | Auto |\n|---|---|---:|---:|---:|---|" << std::endl;
  std::vector<Row> rows;
  const std::vector<std::string> meshes =
      options.quick ? std::vector<std::string>{"armadillo-2766"}
                    : std::vector<std::string>{"armadillo-2766", "armadillo-27674", "armadillo-99976",
                                               "armadillo-399904"};
  std::vector<std::unique_ptr<MeshShape>> shapes;
  for (const std::string& name : meshes) {
    const auto mesh = std::make_shared<const TriangleMesh>(
        scenes::centredOnVertexCentroid(loadMesh(options.meshDirectory + "/" + name + ".ply")));
    shapes.push_back(std::make_unique<MeshShape>(mesh));
    const scenes::PairPose pose = scenes::thesisPose(*mesh);
    rows.push_back(meshRow(name + " x1", {MeshPairQuery{shapes.back().get(), pose.a, shapes.back().get(), pose.b}},
                           options.runs));
    printRow(rows.back());
    if (name != "armadillo-2766") continue;
    // Batches of the small pair, each copy turned a little (bench meshbatch's scene).
    std::mt19937 rng(2024);
    std::uniform_real_distribution<float> turn(-0.1f, 0.1f);
    for (int pairs : options.quick ? std::vector<int>{8} : std::vector<int>{4, 16, 64, 256}) {
      std::vector<MeshPairQuery> queries;
      for (int i = 0; i < pairs; ++i) {
        btTransform b = pose.b;
        b.setRotation(btQuaternion(btVector3(0, 1, 0), 0.5f + turn(rng)));
        queries.push_back(MeshPairQuery{shapes.back().get(), pose.a, shapes.back().get(), b});
      }
      rows.push_back(meshRow(name + " x" + std::to_string(pairs), queries, options.runs));
      printRow(rows.back());
    }
  }
  for (std::size_t n : options.quick ? std::vector<std::size_t>{1000, 16000}
                                     : std::vector<std::size_t>{1000, 4000, 16000, 64000, 256000, 1000000}) {
    rows.push_back(broadphaseRow(n, options.runs, gpu));
    printRow(rows.back());
  }
  if (!options.csvPath.empty()) {
    std::ofstream csv(options.csvPath);
    csv << "kind,work,size,cpu_ms,opencl_ms,auto\n";
    for (const Row& r : rows) {
      csv << r.kind << "," << r.work << "," << r.size << "," << r.cpuMs << "," << r.openclMs << ",\""
          << r.autoPath << "\"\n";
    }
  }
}

const CommandRegistration kRegistration([](CLI::App& app) {
  auto options = std::make_shared<CrossoverOptions>();
  CLI::App* command = app.add_subcommand(
      "crossover", "where Backend::Auto puts mesh batches and broad-phase steps, beside CPU and OpenCL times");
  command->add_option("--mesh-dir", options->meshDirectory, "folder of the mesh files");
  command->add_option("--csv", options->csvPath, "also write the rows to this CSV file");
  command->add_option("--runs", options->runs, "timed calls per path; the median is reported")
      ->check(CLI::PositiveNumber);
  command->add_flag("--quick", options->quick, "one mesh, one batch and two proxy counts");
  command->callback([options] { run(*options); });
});

}  // namespace
}  // namespace gpucol::bench
