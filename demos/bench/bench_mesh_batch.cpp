// gpucol-bench meshbatch: many mesh pairs in one collideMeshesBatch call against the same pairs one call at a
// time, on the CPU and on OpenCL (thesis §7.3: the whole batch of a step in one traversal). The pairs are
// copies of the thesis scene, each with its own small random turn and shift, so no two pairs are the same.
#include <gpucol/gpucol.h>

#include <iomanip>
#include <iostream>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "bench_commands.h"
#include "bench_stats.h"
#include "mesh_pairs/mesh_device_backend.h"
#include "scenes/gimpact_peer.h"

namespace gpucol::bench {
namespace {

struct MeshBatchOptions {
  std::string meshDirectory = GPUCOL_DEFAULT_MESH_DIR;
  std::string mesh = "armadillo-2766.ply";
  int pairs = 100;
  int runs = 5;
};

struct Timing {
  double batchMs = 0;
  double singleMs = 0;
  std::size_t contacts = 0;
  bool same = true;  // the batch and the single calls found the same pairs and contacts
};

Timing measure(const std::vector<MeshPairQuery>& queries, const Config& config, int runs) {
  Timing t;
  std::vector<MeshPairResult> batch = collideMeshesBatch(queries, config);  // warm-up (uploads, builds)
  std::vector<double> batchSamples, singleSamples;
  std::vector<MeshPairResult> singles(queries.size());
  for (int r = 0; r < runs; ++r) {
    batchSamples.push_back(millisecondsOf([&] { batch = collideMeshesBatch(queries, config); }));
    singleSamples.push_back(millisecondsOf([&] {
      for (std::size_t i = 0; i < queries.size(); ++i) {
        const MeshPairQuery& q = queries[i];
        singles[i] = collideMeshes(*q.shapeA, q.transformA, *q.shapeB, q.transformB, config);
      }
    }));
  }
  t.batchMs = median(batchSamples);
  t.singleMs = median(singleSamples);
  for (std::size_t i = 0; i < queries.size(); ++i) {
    t.contacts += batch[i].contacts.size();
    t.same = t.same && batch[i].candidatePairs == singles[i].candidatePairs &&
             batch[i].intersectingPairs == singles[i].intersectingPairs &&
             batch[i].contacts.size() == singles[i].contacts.size();
  }
  return t;
}

void run(const MeshBatchOptions& options) {
  const std::string path = options.meshDirectory + "/" + options.mesh;
  const auto mesh = std::make_shared<const TriangleMesh>(scenes::centredOnVertexCentroid(loadMesh(path)));
  const MeshShape shape(mesh);
  const scenes::PairPose pose = scenes::thesisPose(*mesh);
  std::mt19937 rng(2024);
  std::uniform_real_distribution<float> turn(-0.1f, 0.1f), shift(-0.02f, 0.02f);
  btVector3 lo, hi;
  shape.getAabb(btTransform::getIdentity(), lo, hi);
  const float size = (hi - lo).length();
  std::vector<MeshPairQuery> queries;
  for (int i = 0; i < options.pairs; ++i) {
    btTransform b = pose.b;
    b.setRotation(btQuaternion(btVector3(0, 1, 0), 0.5f + turn(rng)));
    b.setOrigin(pose.b.getOrigin() + btVector3(shift(rng), shift(rng), shift(rng)) * size);
    queries.push_back(MeshPairQuery{&shape, pose.a, &shape, b});
  }
  std::cout << std::fixed << std::setprecision(2);
  std::cout << options.pairs << " pairs of " << options.mesh
            << " (thesis scene, each turned and shifted a little), "
            << "median of " << options.runs << " runs\n";
  std::cout << "| backend | one batch ms | " << options.pairs
            << " single calls ms | batch speed-up | contacts | "
            << "batch == single calls |\n|---|---:|---:|---:|---:|---|\n";
  for (Backend backend : {Backend::Cpu, Backend::OpenCL}) {
    Config config;
    config.meshBackend = backend;
    if (backend == Backend::OpenCL && !sharedMeshBatchDevice(config)) {
      std::cout << "| OpenCL | no usable device | | | | |\n";
      continue;
    }
    const Timing t = measure(queries, config, options.runs);
    std::cout << "| " << (backend == Backend::Cpu ? "CPU" : "OpenCL") << " | " << t.batchMs << " | "
              << t.singleMs << " | " << std::setprecision(1) << t.singleMs / t.batchMs << "x"
              << std::setprecision(2) << " | " << t.contacts << " | " << (t.same ? "yes" : "NO") << " |\n";
    if (backend == Backend::OpenCL) {
      // The same batch with the candidates sorted on the device before the near phase, and on the host after
      // it (CandidateSort::Auto takes one of the two, by the device's shape).
      for (CandidateSort sort : {CandidateSort::Device, CandidateSort::Host}) {
        MeshBatchDeviceOptions sorted;
        sorted.candidateSort = sort;
        detail::setMeshDeviceOptions(sorted);
        const Timing d = measure(queries, config, options.runs);
        detail::setMeshDeviceOptions(MeshBatchDeviceOptions());
        std::cout << (sort == CandidateSort::Device ? "| OpenCL, device sort | " : "| OpenCL, host sort | ")
                  << d.batchMs << " | " << d.singleMs << " | " << std::setprecision(1) << d.singleMs / d.batchMs
                  << "x" << std::setprecision(2) << " | " << d.contacts << " | " << (d.same ? "yes" : "NO")
                  << " |\n";
      }
      // The stages of one more batch that waits after the traversal, so that its time is split. It runs the
      // traversal and the near kernel apart, a program of its own on a CPU device: a first batch builds it.
      MeshBatchDeviceOptions split;
      split.splitTimes = true;
      detail::setMeshDeviceOptions(split);
      collideMeshesBatch(queries, config);
      collideMeshesBatch(queries, config);
      detail::setMeshDeviceOptions(MeshBatchDeviceOptions());
      const MeshBatchDeviceStats s = detail::lastMeshDeviceStats();
      std::cout << "  OpenCL batch stages, ms (one run): upload " << s.uploadMs << ", traversal "
                << s.traversalMs << ", prefix sum " << s.scanMs << ", sort " << s.sortMs << ", near "
                << s.nearMs << ", compaction " << s.compactionMs << ", readback " << s.readbackMs << "; "
                << s.frontSizes.size() << " levels, " << s.candidates << " candidates, " << s.hits
                << " intersecting\n";
    }
  }
}

const CommandRegistration kRegistration([](CLI::App& app) {
  auto options = std::make_shared<MeshBatchOptions>();
  CLI::App* command = app.add_subcommand(
      "meshbatch", "many mesh pairs as one batch against one call per pair, CPU and OpenCL");
  command->add_option("--mesh-dir", options->meshDirectory, "folder of the mesh files");
  command->add_option("--mesh", options->mesh, "mesh file in --mesh-dir (default armadillo-2766.ply)");
  command->add_option("--pairs", options->pairs, "pairs in the batch")->check(CLI::PositiveNumber);
  command->add_option("--runs", options->runs, "runs per measurement; the median is reported")
      ->check(CLI::PositiveNumber);
  command->callback([options] { run(*options); });
});

}  // namespace
}  // namespace gpucol::bench
