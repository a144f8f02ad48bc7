// gpucol-bench meshpair: the thesis's scene (two copies of a mesh, the second moved along x by 0.3 × the
// largest side and turned 0.5 rad about y), gpucol beside btGImpactCollisionAlgorithm in the same run.
#include <gpucol/gpucol.h>

#include <algorithm>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <memory>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "bench_commands.h"
#include "bench_stats.h"
#include "mesh_pairs/mesh_device_backend.h"
#include "scenes/gimpact_peer.h"
#include "scenes/procedural_meshes.h"

namespace gpucol::bench {
namespace {

struct MeshPairOptions {
  std::string meshDirectory = GPUCOL_DEFAULT_MESH_DIR;
  std::vector<std::string> meshes = {"armadillo-2766.ply", "armadillo-27674.ply", "armadillo-99976.ply",
                                     "armadillo-399904.ply"};
  bool builtin = false;
  int runs = 5;
  std::string csvPath;
  std::string backend = "cpu";
  bool variants = true;  // --backend opencl: also the variants' table
};

struct Row {
  std::string name;
  std::size_t triangles = 0;
  double gpucolBuildMs = 0, gimpactBuildMs = 0;
  double middleMs = 0, nearMs = 0, reductionMs = 0, gpucolTotalMs = 0, gimpactMs = 0;
  TurnTimes warm;  // gpucol (first) and GImpact (second) taking turns in blocks of calls
  std::uint64_t nodeTests = 0;
  std::size_t candidates = 0, intersecting = 0, contacts = 0, reduced = 0, gimpactContacts = 0;
  std::size_t gimpactPairsMissed = 0;  // GImpact pairs whose triangles' boxes overlap, not among candidates.
  std::size_t gimpactPairsApart = 0;   // GImpact pairs whose triangles' boxes miss in either body's frame.
};

/// The box, in double, of triangle t of `mesh` placed in the world by `placement`, seen in the frame of the
/// world transform `frame`.
void triangleBoxInFrame(const TriangleMesh& mesh, const btTransform& placement, const btTransform& frame,
                        std::uint32_t t, double (&lo)[3], double (&hi)[3]) {
  for (int axis = 0; axis < 3; ++axis) {
    lo[axis] = 1e300;
    hi[axis] = -1e300;
  }
  for (int corner = 0; corner < 3; ++corner) {
    const float* p = mesh.positions().data() + 3 * std::size_t(mesh.indices()[3 * std::size_t(t) + corner]);
    double world[3];
    for (int r = 0; r < 3; ++r) {
      world[r] = placement.getOrigin()[r];
      for (int c = 0; c < 3; ++c) world[r] += double(placement.getBasis()[r][c]) * double(p[c]);
    }
    for (int r = 0; r < 3; ++r) {
      double local = 0;
      for (int c = 0; c < 3; ++c) local += double(frame.getBasis()[c][r]) * (world[c] - frame.getOrigin()[c]);
      lo[r] = std::min(lo[r], local);
      hi[r] = std::max(hi[r], local);
    }
  }
}

/// The two triangles' boxes overlap in `frame` (touching counts).
bool boxesOverlapInFrame(const TriangleMesh& mesh, const scenes::PairPose& pose, const TrianglePair& pair,
                         const btTransform& frame) {
  double loA[3], hiA[3], loB[3], hiB[3];
  triangleBoxInFrame(mesh, pose.a, frame, pair.triangleA, loA, hiA);
  triangleBoxInFrame(mesh, pose.b, frame, pair.triangleB, loB, hiB);
  bool overlap = true;
  for (int axis = 0; axis < 3; ++axis) overlap &= loA[axis] <= hiB[axis] && loB[axis] <= hiA[axis];
  return overlap;
}

Row measure(const std::string& name, const TriangleMesh& loaded, int runs) {
  const auto mesh = std::make_shared<const TriangleMesh>(scenes::centredOnVertexCentroid(loaded));
  const scenes::PairPose pose = scenes::thesisPose(*mesh);
  Row row;
  row.name = name;
  row.triangles = mesh->triangleCount();

  std::vector<double> buildSamples, gimpactBuildSamples;
  std::unique_ptr<MeshShape> shape;
  std::unique_ptr<scenes::GImpactMesh> peer;
  for (int i = 0; i < runs; ++i) {
    buildSamples.push_back(millisecondsOf([&] { shape = std::make_unique<MeshShape>(mesh); }));
    peer = std::make_unique<scenes::GImpactMesh>(*mesh);
    gimpactBuildSamples.push_back(peer->buildMilliseconds());
  }
  row.gpucolBuildMs = median(buildSamples);
  row.gimpactBuildMs = median(gimpactBuildSamples);

  std::vector<double> total, middle, nearPhase, reduction, gimpact;
  MeshPairResult result;
  std::vector<scenes::GImpactContact> peerContacts;
  scenes::GImpactMesh peerB(*mesh);
  scenes::GImpactPair peerPair(*peer, pose.a, peerB, pose.b);
  for (int i = 0; i < runs; ++i) {
    total.push_back(millisecondsOf([&] { result = collideMeshes(*shape, pose.a, *shape, pose.b); }));
    middle.push_back(result.stats.middlePhaseMs);
    nearPhase.push_back(result.stats.nearPhaseMs);
    reduction.push_back(result.stats.reductionMs);
    gimpact.push_back(millisecondsOf([&] { peerContacts = peerPair.collide(); }));
  }
  // The same two calls in blocks (takeTurns): each meets caches and threads as its own previous call left
  // them. One by one, each gpucol call follows a GImpact call of several ms on one thread, after which gpucol
  // ran here about as slowly as after a walk over 64 MB, with the second core idle (README, Mesh pairs).
  row.warm = takeTurns(
      runs, [&] { collideMeshes(*shape, pose.a, *shape, pose.b); }, [&] { peerPair.collide(); }, [] {});
  row.gpucolTotalMs = median(total);
  row.middleMs = median(middle);
  row.nearMs = median(nearPhase);
  row.reductionMs = median(reduction);
  row.gimpactMs = median(gimpact);
  row.nodeTests = result.stats.nodeTests;
  row.candidates = result.candidatePairs.size();
  row.intersecting = result.intersectingPairs.size();
  row.contacts = result.contacts.size();
  row.reduced = result.reducedContacts.size();
  row.gimpactContacts = peerContacts.size();

  // Every triangle pair GImpact made a contact from and whose triangles' boxes overlap in both bodies' frames
  // (in double) must be among gpucol's candidates: the middle phase loses nothing. Pairs whose boxes miss in
  // either frame cannot touch; GImpact's contacts from such pairs are counted apart. Whether a pair truly
  // intersects is the exact test's call, checked against a double-precision reference in the test suite.
  const std::set<TrianglePair> candidates(result.candidatePairs.begin(), result.candidatePairs.end());
  std::set<TrianglePair> peerPairs;
  for (const auto& c : peerContacts) peerPairs.insert({c.triangleA, c.triangleB});
  for (const auto& p : peerPairs) {
    if (!boxesOverlapInFrame(*mesh, pose, p, pose.a) || !boxesOverlapInFrame(*mesh, pose, p, pose.b)) {
      ++row.gimpactPairsApart;
    } else if (!candidates.count(p)) {
      ++row.gimpactPairsMissed;
    }
  }
  return row;
}

void printTable(const std::vector<Row>& rows, std::ostream& out) {
  out << std::fixed << std::setprecision(2);
  out << "| mesh | triangles | build gpucol / GImpact ms | middle ms | near ms | reduction ms "
         "| gpucol total ms | GImpact ms | speed-up, one by one | node tests | candidates | intersecting "
         "| contacts | reduced | GImpact contacts | GImpact pairs missed by gpucol "
         "| GImpact pairs whose triangles are apart | in blocks: gpucol / GImpact ms "
         "| in blocks: speed-up (range) |\n";
  out << "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
  for (const Row& r : rows) {
    out << "| " << r.name << " | " << r.triangles << " | " << r.gpucolBuildMs << " / " << r.gimpactBuildMs
        << " | " << r.middleMs << " | " << r.nearMs << " | " << r.reductionMs << " | " << r.gpucolTotalMs
        << " | " << r.gimpactMs << " | " << std::setprecision(1) << r.gimpactMs / r.gpucolTotalMs << "x"
        << std::setprecision(2) << " | " << r.nodeTests << " | " << r.candidates << " | " << r.intersecting
        << " | " << r.contacts << " | " << r.reduced << " | " << r.gimpactContacts << " | "
        << r.gimpactPairsMissed << " | " << r.gimpactPairsApart << " | " << r.warm.firstMs << " / "
        << r.warm.secondMs << " | " << std::setprecision(1) << r.warm.ratio << "x (" << r.warm.ratioLow << "-"
        << r.warm.ratioHigh << ")" << std::setprecision(2) << " |\n";
  }
}

void writeCsv(const std::vector<Row>& rows, const std::string& path) {
  std::ofstream csv(path);
  if (!csv) throw std::runtime_error("cannot write " + path);
  csv << "mesh,triangles,gpucol_build_ms,gimpact_build_ms,middle_ms,near_ms,reduction_ms,gpucol_total_ms,"
         "gimpact_ms,node_tests,candidates,intersecting,contacts,reduced,gimpact_contacts,gimpact_pairs_"
         "missed,gimpact_pairs_apart,blocks_gpucol_ms,blocks_gimpact_ms,blocks_speedup\n";
  for (const Row& r : rows) {
    csv << r.name << ',' << r.triangles << ',' << r.gpucolBuildMs << ',' << r.gimpactBuildMs << ','
        << r.middleMs << ',' << r.nearMs << ',' << r.reductionMs << ',' << r.gpucolTotalMs << ','
        << r.gimpactMs << ',' << r.nodeTests << ',' << r.candidates << ',' << r.intersecting << ','
        << r.contacts << ',' << r.reduced << ',' << r.gimpactContacts << ',' << r.gimpactPairsMissed << ','
        << r.gimpactPairsApart << ',' << r.warm.firstMs << ',' << r.warm.secondMs << ',' << r.warm.ratio
        << '\n';
  }
}

// --backend opencl: the thesis's Tables 6.2-6.5 and Figs. 6.2-6.3 on the OpenCL device beside the CPU path,
// same scene, same run. Each OpenCL variant gets one warm-up call first (program builds and the resident
// upload are one-time costs, reported apart as the first call).
struct OpenClRow {
  std::string name;
  std::size_t triangles = 0;
  double cpuMiddleMs = 0, cpuNearMs = 0, cpuTotalMs = 0;
  double firstCallMs = 0;  // the first OpenCL call: mesh upload (and program builds on the very first mesh)
  MeshBatchDeviceStats stages;  // stage medians of the default options with splitTimes
  double clTotalMs = 0;         // the default options (one wait for traversal, near kernel and readback)
  double clSplitTotalMs = 0;    // the same with splitTimes (a wait after the traversal)
  double startDepthMs[3] = {0, 0, 0};  // breadth-first, d0 = 0, 3, 6
  double depthFirstMs[4] = {0, 0, 0, 0};  // depth-first, start depth 6, 8, 10, 11
  double noEarlyOutMs = 0, deviceSortMs = 0, hostSortMs = 0;
  double ratio = 0, ratioLow = 0, ratioHigh = 0;  // OpenCL / CPU over the blocks of calls: median, range
  bool variants = false;                          // the variants' columns were measured
  std::size_t candidates = 0, intersecting = 0;
  bool sameAsCpu = false;
};

constexpr int kStartDepths[3] = {0, 3, 6};
constexpr int kDepthFirstStartDepths[4] = {6, 8, 10, 11};

// Median end-to-end time of collideMeshes on OpenCL with `device` options, and the stage medians.
double timeOpenCl(const MeshShape& shape, const scenes::PairPose& pose, const MeshBatchDeviceOptions& device,
                  int runs, MeshBatchDeviceStats* stages, MeshPairResult* result) {
  Config config;
  config.meshBackend = Backend::OpenCL;
  detail::setMeshDeviceOptions(device);
  MeshPairResult r = collideMeshes(shape, pose.a, shape, pose.b, config);  // warm-up
  std::vector<double> total, upload, traversal, scan, sort, prefilter, nearPhase, compaction, readback;
  for (int i = 0; i < runs; ++i) {
    total.push_back(millisecondsOf([&] { r = collideMeshes(shape, pose.a, shape, pose.b, config); }));
    const MeshBatchDeviceStats s = detail::lastMeshDeviceStats();
    upload.push_back(s.uploadMs);
    traversal.push_back(s.traversalMs);
    scan.push_back(s.scanMs);
    sort.push_back(s.sortMs);
    prefilter.push_back(s.prefilterMs);
    nearPhase.push_back(s.nearMs);
    compaction.push_back(s.compactionMs);
    readback.push_back(s.readbackMs);
    if (stages && i == 0) *stages = s;
  }
  if (stages) {
    stages->uploadMs = median(upload);
    stages->traversalMs = median(traversal);
    stages->scanMs = median(scan);
    stages->sortMs = median(sort);
    stages->prefilterMs = median(prefilter);
    stages->nearMs = median(nearPhase);
    stages->compactionMs = median(compaction);
    stages->readbackMs = median(readback);
  }
  if (result) *result = std::move(r);
  detail::setMeshDeviceOptions(MeshBatchDeviceOptions());
  return median(total);
}

OpenClRow measureOpenCl(const std::string& name, const TriangleMesh& loaded, int runs, bool variants) {
  const auto mesh = std::make_shared<const TriangleMesh>(scenes::centredOnVertexCentroid(loaded));
  const scenes::PairPose pose = scenes::thesisPose(*mesh);
  const MeshShape shape(mesh);
  OpenClRow row;
  row.name = name;
  row.triangles = mesh->triangleCount();
  Config cpu;
  cpu.meshBackend = Backend::Cpu;
  MeshPairResult cpuResult = collideMeshes(shape, pose.a, shape, pose.b, cpu);
  Config cl;
  cl.meshBackend = Backend::OpenCL;
  detail::setMeshDeviceOptions(MeshBatchDeviceOptions());
  row.firstCallMs = millisecondsOf([&] { collideMeshes(shape, pose.a, shape, pose.b, cl); });
  MeshPairResult clResult = collideMeshes(shape, pose.a, shape, pose.b, cl);  // warm-up
  // The CPU path and the default OpenCL path take turns in blocks of calls (takeTurns), so that both meet the
  // same load; each total is the median of the blocks' medians, the ratio the median of the blocks' ratios.
  std::vector<double> middle, nearPhase;
  const TurnTimes turns = takeTurns(
      runs, [&] { cpuResult = collideMeshes(shape, pose.a, shape, pose.b, cpu); },
      [&] { clResult = collideMeshes(shape, pose.a, shape, pose.b, cl); },
      [&] {
        middle.push_back(cpuResult.stats.middlePhaseMs);
        nearPhase.push_back(cpuResult.stats.nearPhaseMs + cpuResult.stats.reductionMs);
      });
  row.cpuTotalMs = turns.firstMs;
  row.cpuMiddleMs = median(middle);
  row.cpuNearMs = median(nearPhase);
  row.clTotalMs = turns.secondMs;
  row.ratio = turns.ratio;
  row.ratioLow = turns.ratioLow;
  row.ratioHigh = turns.ratioHigh;
  MeshBatchDeviceOptions split;
  split.splitTimes = true;
  row.clSplitTotalMs = timeOpenCl(shape, pose, split, runs, &row.stages, nullptr);
  row.sameAsCpu = clResult.stats.backendUsed == Backend::OpenCL &&
                  clResult.candidatePairs == cpuResult.candidatePairs &&
                  clResult.intersectingPairs == cpuResult.intersectingPairs &&
                  clResult.contacts.size() == cpuResult.contacts.size();
  row.candidates = cpuResult.candidatePairs.size();
  row.intersecting = cpuResult.intersectingPairs.size();
  MeshBatchDeviceStats breadthFirst;
  MeshBatchDeviceOptions fromRoots;
  fromRoots.traversal = MeshTraversal::BreadthFirst;
  fromRoots.startDepth = 0;
  if (!variants) {
    // The per-level front sizes (Table 6.3) come from the breadth-first walk from the roots.
    timeOpenCl(shape, pose, fromRoots, 1, &breadthFirst, nullptr);
    row.stages.frontSizes = breadthFirst.frontSizes;
    return row;
  }
  row.variants = true;
  for (int k = 0; k < 3; ++k) {
    MeshBatchDeviceOptions o = fromRoots;
    o.startDepth = kStartDepths[k];
    row.startDepthMs[k] = timeOpenCl(shape, pose, o, runs, &breadthFirst, nullptr);
    if (k == 0) row.stages.frontSizes = breadthFirst.frontSizes;
  }
  for (int k = 0; k < 4; ++k) {
    MeshBatchDeviceOptions o;
    o.depthFirstStartDepth = kDepthFirstStartDepths[k];
    row.depthFirstMs[k] = timeOpenCl(shape, pose, o, runs, nullptr, nullptr);
  }
  MeshBatchDeviceOptions o;
  o.nearPrefilter = false;
  row.noEarlyOutMs = timeOpenCl(shape, pose, o, runs, nullptr, nullptr);
  o = MeshBatchDeviceOptions();
  o.candidateSort = CandidateSort::Device;
  row.deviceSortMs = timeOpenCl(shape, pose, o, runs, nullptr, nullptr);
  o = MeshBatchDeviceOptions();
  o.candidateSort = CandidateSort::Host;
  row.hostSortMs = timeOpenCl(shape, pose, o, runs, nullptr, nullptr);
  return row;
}

void printOpenClTables(const std::vector<OpenClRow>& rows, const std::string& device, int runs,
                       std::ostream& out) {
  out << std::fixed << std::setprecision(2);
  out << "\nOpenCL device: " << device << "; thesis scene, median of " << runs << " runs\n";
  out << "\nCPU vs OpenCL, end to end (thesis Tables 6.2, 6.5). CPU total and OpenCL total: the CPU path and "
         "the default OpenCL path (one wait for traversal, near kernel and readback) taking turns in blocks "
         "of "
         "calls, medians of the blocks' medians; OpenCL / CPU: the median of the blocks' ratios, and their "
         "range. OpenCL middle = upload + traversal + scan + sort and near = "
         "near kernel + compaction + readback come from runs that also wait after the traversal "
         "(splitTimes), whose total is given too\n";
  out << "| mesh | triangles | CPU middle ms | CPU near+reduction ms | CPU total ms | OpenCL middle ms | "
         "OpenCL near ms | OpenCL total, split ms | OpenCL total ms | OpenCL / CPU | blocks' OpenCL / CPU | "
         "first OpenCL call ms | same results |\n";
  out << "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|\n";
  for (const OpenClRow& r : rows) {
    const MeshBatchDeviceStats& s = r.stages;
    out << "| " << r.name << " | " << r.triangles << " | " << r.cpuMiddleMs << " | " << r.cpuNearMs << " | "
        << r.cpuTotalMs << " | " << s.uploadMs + s.traversalMs + s.scanMs + s.sortMs << " | "
        << s.prefilterMs + s.nearMs + s.compactionMs + s.readbackMs << " | " << r.clSplitTotalMs << " | "
        << r.clTotalMs << " | " << std::setprecision(1) << r.ratio << "x | " << r.ratioLow << "-"
        << r.ratioHigh << "x" << std::setprecision(2) << " | " << r.firstCallMs << " | "
        << (r.sameAsCpu ? "yes" : "NO") << " |\n";
  }
  out << "\nOpenCL time split (thesis Figs. 6.2-6.3), ms, with a wait after the traversal (splitTimes)\n";
  out << "| mesh | upload (transforms) | traversal | prefix sum | sort | early-out | near kernel | "
         "compaction | "
         "readback | node tests | candidates | intersecting |\n";
  out << "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
  for (const OpenClRow& r : rows) {
    const MeshBatchDeviceStats& s = r.stages;
    out << "| " << r.name << " | " << s.uploadMs << " | " << s.traversalMs << " | " << s.scanMs << " | "
        << s.sortMs << " | " << s.prefilterMs << " | " << s.nearMs << " | " << s.compactionMs << " | "
        << s.readbackMs << " | " << s.nodeTests << " | " << r.candidates << " | " << r.intersecting << " |\n";
  }
  out << "\nOverlapping node pairs per level of the breadth-first traversal (thesis Table 6.3; level 0 = "
         "roots)\n";
  for (const OpenClRow& r : rows) {
    out << "- " << r.name << ":";
    for (std::uint64_t f : r.stages.frontSizes) out << " " << f;
    out << "\n";
  }
  if (rows.empty() || !rows.front().variants) return;
  out << "\nOpenCL variants, end-to-end ms: the breadth-first traversal (thesis §5.4.2) from start depth d0 "
         "(thesis used 6), the depth-first one from a fixed start depth, without the early-out test, the "
         "candidates sorted on the device or on the host (the default takes one by the device's shape); the "
         "last column is the default\n";
  out << "| mesh | breadth-first d0=0 | d0=3 | d0=6 | depth-first d=6 | d=8 | d=10 | d=11 | no early-out | "
         "device sort | host sort | default |\n";
  out << "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
  for (const OpenClRow& r : rows) {
    out << "| " << r.name << " | " << r.startDepthMs[0] << " | " << r.startDepthMs[1] << " | "
        << r.startDepthMs[2] << " | " << r.depthFirstMs[0] << " | " << r.depthFirstMs[1] << " | "
        << r.depthFirstMs[2] << " | " << r.depthFirstMs[3] << " | " << r.noEarlyOutMs << " | " << r.deviceSortMs << " | " << r.hostSortMs << " | "
        << r.clTotalMs << " |\n";
  }
}

void runOpenCl(const MeshPairOptions& options) {
  Config cl;
  cl.meshBackend = Backend::OpenCL;
  MeshBatchDevice* device = sharedMeshBatchDevice(cl);
  if (device == nullptr) throw std::runtime_error("--backend opencl: no usable OpenCL device");
  std::vector<OpenClRow> rows;
  if (options.builtin) {
    rows.push_back(measureOpenCl("icosphere (5 levels)", scenes::makeIcosphere(1.0f, 5), options.runs,
                                 options.variants));
    rows.push_back(measureOpenCl("torus 256x64", scenes::makeTorus(1.0f, 0.3f, 256, 64), options.runs,
                                 options.variants));
  } else {
    for (const std::string& file : options.meshes) {
      const std::string path = options.meshDirectory + "/" + file;
      std::cout << "measuring " << path << " ..." << std::endl;
      rows.push_back(measureOpenCl(file, loadMesh(path), options.runs, options.variants));
    }
  }
  printOpenClTables(rows, device->deviceName(), options.runs, std::cout);
}

void run(const MeshPairOptions& options) {
  if (options.backend == "opencl") {
    runOpenCl(options);
    return;
  }
  std::vector<Row> rows;
  if (options.builtin) {
    std::cout << "built-in scene: procedural meshes, no files needed\n";
    rows.push_back(measure("icosphere (5 levels)", scenes::makeIcosphere(1.0f, 5), options.runs));
    rows.push_back(measure("torus 256x64", scenes::makeTorus(1.0f, 0.3f, 256, 64), options.runs));
  } else {
    for (const std::string& file : options.meshes) {
      const std::string path = options.meshDirectory + "/" + file;
      std::cout << "measuring " << path << " ..." << std::endl;
      rows.push_back(measure(file, loadMesh(path), options.runs));
    }
  }
  std::cout << "\nthesis scene, median of " << options.runs
            << " runs (gpucol total = collideMeshes end to end; gpucol and GImpact called one by one, "
               "taking turns; \"in blocks\": the two taking turns in "
            << options.runs << " blocks of " << kTurnCalls << " calls each, the first " << kTurnWarmCalls
            << " of a block not counted, medians of the blocks' medians, speed-up = median of the blocks' "
               "ratios)\n";
  printTable(rows, std::cout);
  if (!options.csvPath.empty()) writeCsv(rows, options.csvPath);
}

const CommandRegistration kRegistration([](CLI::App& app) {
  auto options = std::make_shared<MeshPairOptions>();
  CLI::App* command = app.add_subcommand("meshpair", "the thesis scene per mesh, gpucol beside GImpact");
  command->add_option("--mesh-dir", options->meshDirectory, "folder of the mesh files");
  command->add_option("--mesh", options->meshes, "mesh files in --mesh-dir (default: four armadillos)");
  command->add_flag("--builtin", options->builtin, "use built-in procedural meshes instead of files");
  command->add_option("--runs", options->runs, "runs per measurement; the median is reported")
      ->check(CLI::PositiveNumber);
  command->add_option("--csv", options->csvPath, "also write the rows to this CSV file (cpu backend)");
  command
      ->add_option(
          "--backend", options->backend,
          "cpu: gpucol beside GImpact; opencl: the OpenCL pipeline beside the CPU path, stage by stage")
      ->check(CLI::IsMember({"cpu", "opencl"}));
  command->add_flag("!--no-variants", options->variants,
                    "--backend opencl: skip the variants' table (breadth-first, start depths, no early-out, "
                    "device and host sorts)");
  command->callback([options] { run(*options); });
});

}  // namespace
}  // namespace gpucol::bench
