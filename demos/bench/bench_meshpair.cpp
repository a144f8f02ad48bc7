// gpucol-bench meshpair: the thesis's scene (two copies of a mesh, the second moved along x by 0.3 × the
// largest side and turned 0.5 rad about y), gpucol beside btGImpactCollisionAlgorithm in the same run.
#include <algorithm>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <memory>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include <gpucol/gpucol.h>

#include "bench_commands.h"
#include "bench_stats.h"
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
};

struct Row {
  std::string name;
  std::size_t triangles = 0;
  double gpucolBuildMs = 0, gimpactBuildMs = 0;
  double middleMs = 0, nearMs = 0, reductionMs = 0, gpucolTotalMs = 0, gimpactMs = 0;
  std::uint64_t nodeTests = 0;
  std::size_t candidates = 0, intersecting = 0, contacts = 0, reduced = 0, gimpactContacts = 0;
  std::size_t gimpactPairsMissed = 0;     // GImpact pairs whose triangles' boxes overlap, not among candidates.
  std::size_t gimpactPairsApart = 0;      // GImpact pairs whose triangles' boxes do not even overlap.
};

// World-space box of triangle `t` of `mesh` under `transform`, in double.
void worldTriangleBox(const TriangleMesh& mesh, const btTransform& transform, std::uint32_t t, double (&lo)[3],
                      double (&hi)[3]) {
  for (int axis = 0; axis < 3; ++axis) {
    lo[axis] = 1e300;
    hi[axis] = -1e300;
  }
  for (int corner = 0; corner < 3; ++corner) {
    const float* p = mesh.positions().data() + 3 * std::size_t(mesh.indices()[3 * std::size_t(t) + corner]);
    for (int r = 0; r < 3; ++r) {
      double w = transform.getOrigin()[r];
      for (int c = 0; c < 3; ++c) w += double(transform.getBasis()[r][c]) * double(p[c]);
      lo[r] = std::min(lo[r], w);
      hi[r] = std::max(hi[r], w);
    }
  }
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

  // Every triangle pair GImpact made a contact from and whose triangles' boxes overlap (in double, world space)
  // must be among gpucol's candidates: the middle phase loses nothing. Pairs whose boxes miss cannot touch;
  // GImpact's contacts from such pairs are counted apart. Whether a pair truly intersects is the exact
  // test's call, checked against a double-precision reference in the test suite.
  const std::set<TrianglePair> candidates(result.candidatePairs.begin(), result.candidatePairs.end());
  std::set<TrianglePair> peerPairs;
  for (const auto& c : peerContacts) peerPairs.insert({c.triangleA, c.triangleB});
  for (const auto& p : peerPairs) {
    double loA[3], hiA[3], loB[3], hiB[3];
    worldTriangleBox(*mesh, pose.a, p.triangleA, loA, hiA);
    worldTriangleBox(*mesh, pose.b, p.triangleB, loB, hiB);
    bool boxesOverlap = true;
    for (int axis = 0; axis < 3; ++axis) boxesOverlap &= loA[axis] <= hiB[axis] && loB[axis] <= hiA[axis];
    if (!boxesOverlap) {
      ++row.gimpactPairsApart;
    } else if (!candidates.count(p)) {
      ++row.gimpactPairsMissed;
    }
  }
  return row;
}

void printTable(const std::vector<Row>& rows, std::ostream& out) {
  out << std::fixed << std::setprecision(2);
  out << "| mesh | triangles | build gpucol / GImpact ms | middle ms | near ms | reduction ms | gpucol total ms "
         "| GImpact ms | speed-up | node tests | candidates | intersecting | contacts | reduced | GImpact "
         "contacts | GImpact pairs missed by gpucol | GImpact pairs whose triangles are apart |\n";
  out << "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
  for (const Row& r : rows) {
    out << "| " << r.name << " | " << r.triangles << " | " << r.gpucolBuildMs << " / " << r.gimpactBuildMs
        << " | " << r.middleMs << " | " << r.nearMs << " | " << r.reductionMs << " | " << r.gpucolTotalMs
        << " | " << r.gimpactMs << " | " << std::setprecision(1) << r.gimpactMs / r.gpucolTotalMs << "x"
        << std::setprecision(2) << " | " << r.nodeTests << " | " << r.candidates << " | " << r.intersecting
        << " | " << r.contacts << " | " << r.reduced << " | " << r.gimpactContacts << " | "
        << r.gimpactPairsMissed << " | " << r.gimpactPairsApart << " |\n";
  }
}

void writeCsv(const std::vector<Row>& rows, const std::string& path) {
  std::ofstream csv(path);
  if (!csv) throw std::runtime_error("cannot write " + path);
  csv << "mesh,triangles,gpucol_build_ms,gimpact_build_ms,middle_ms,near_ms,reduction_ms,gpucol_total_ms,"
         "gimpact_ms,node_tests,candidates,intersecting,contacts,reduced,gimpact_contacts,gimpact_pairs_missed,gimpact_pairs_apart\n";
  for (const Row& r : rows) {
    csv << r.name << ',' << r.triangles << ',' << r.gpucolBuildMs << ',' << r.gimpactBuildMs << ',' << r.middleMs
        << ',' << r.nearMs << ',' << r.reductionMs << ',' << r.gpucolTotalMs << ',' << r.gimpactMs << ','
        << r.nodeTests << ',' << r.candidates << ',' << r.intersecting << ',' << r.contacts << ',' << r.reduced
        << ',' << r.gimpactContacts << ',' << r.gimpactPairsMissed << ',' << r.gimpactPairsApart << '\n';
  }
}

void run(const MeshPairOptions& options) {
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
  std::cout << "\nthesis scene, median of " << options.runs << " runs (gpucol total = collideMeshes end to end)\n";
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
  command->add_option("--csv", options->csvPath, "also write the rows to this CSV file");
  command->callback([options] { run(*options); });
});

}  // namespace
}  // namespace gpucol::bench
