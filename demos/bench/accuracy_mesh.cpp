// The mesh pipeline's studies of `gpucol-bench accuracy`: contact reduction and tessellation against analytic
// answers (a box resting on a box, two overlapping spheres), leaf size and near phase precision against a
// double-precision separating-axis reference over every triangle pair.
#include <algorithm>
#include <cmath>
#include <iostream>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include <gpucol/gpucol.h>

#include "accuracy_row.h"
#include "bench_stats.h"
#include "narrowphase/triangle_intersection.h"
#include "narrowphase/triangle_intersection_float.h"
#include "random_triangles.h"
#include "reference_triangles.h"
#include "scenes/gimpact_peer.h"
#include "scenes/procedural_meshes.h"

namespace gpucol::bench {
namespace {

constexpr double kPi = 3.14159265358979323846;

// A mesh pair with a known answer: A pressed into B by `penetration` along `normal` (on B, towards A).
struct AnalyticPair {
  std::string name;
  std::shared_ptr<MeshShape> a, b;
  btTransform transformA, transformB;
  btVector3 normal;
  double penetration = 0;
};

// A 1 m cube resting on a 4 m × 1 m × 4 m slab, 1 cm into it, turned 0.3 rad about the vertical: the answer is
// depth -0.01 along +y whatever the tessellation (flat faces are exact at any subdivision).
AnalyticPair boxOnBox(int subdivisions, const Config& config) {
  AnalyticPair pair;
  pair.name = "box-on-box n=" + std::to_string(subdivisions);
  pair.a = std::make_shared<MeshShape>(std::make_shared<const TriangleMesh>(scenes::makeBox(0.5f, 0.5f, 0.5f, subdivisions)), config);
  pair.b = std::make_shared<MeshShape>(std::make_shared<const TriangleMesh>(scenes::makeBox(2.0f, 0.5f, 2.0f, subdivisions)), config);
  pair.penetration = 0.01;
  pair.transformB.setIdentity();
  pair.transformA.setIdentity();
  pair.transformA.setRotation(btQuaternion(btVector3(0, 1, 0), 0.3f));
  pair.transformA.setOrigin(btVector3(0.1f, 0.5f + 0.5f - float(pair.penetration), -0.2f));
  pair.normal = btVector3(0, 1, 0);
  return pair;
}

// Two spheres of radius 0.5 (icospheres of `levels` subdivisions) whose centres are 0.95 m apart along a
// direction that is no axis: the smooth spheres overlap by 5 cm along the line of centres. The tessellated
// ones are inside the smooth ones, so their error shrinks with the level.
AnalyticPair spherePair(int levels, const Config& config) {
  AnalyticPair pair;
  pair.name = "spheres level " + std::to_string(levels);
  auto sphere = std::make_shared<MeshShape>(std::make_shared<const TriangleMesh>(scenes::makeIcosphere(0.5f, levels)), config);
  pair.a = sphere;
  pair.b = sphere;
  pair.penetration = 0.05;
  pair.normal = btVector3(1.0f, 2.0f, 0.5f).normalized();
  pair.transformB.setIdentity();
  pair.transformA.setIdentity();
  pair.transformA.setRotation(btQuaternion(btVector3(0.3f, 1, 0.2f).normalized(), 0.7f));
  pair.transformA.setOrigin(pair.normal * float(1.0 - pair.penetration));
  return pair;
}

// Times the pair's query (median of `runs`) and measures its reduced contacts against the analytic answer.
AccuracyRow measureAnalytic(const AnalyticPair& pair, const Config& config, int runs) {
  AccuracyRow row;
  row.scene = pair.name;
  MeshPairResult result;
  std::vector<double> samples;
  for (int i = 0; i < runs; ++i) {
    samples.push_back(millisecondsOf(
        [&] { result = collideMeshes(*pair.a, pair.transformA, *pair.b, pair.transformB, config); }));
  }
  row.timeMs = median(samples);
  row.contacts = double(result.reducedContacts.size());
  if (result.reducedContacts.empty()) {
    row.depthError = -pair.penetration;  // Nothing found: the whole penetration is missed.
    return row;
  }
  // The deepest contact is what the solver resolves first; the depth-weighted sum of normals is the direction
  // the contacts push A in together.
  double deepest = 0;
  btVector3 push(0, 0, 0);
  for (const MeshContact& c : result.reducedContacts) {
    deepest = std::max(deepest, -double(c.depth));
    push += c.normalWorldOnB * std::max(-c.depth, btScalar(1e-9));
  }
  // Signed: the §5.3.4 depth of a triangle pair is local to the two triangles, so it cannot exceed what the
  // triangles' own extent allows; with triangles smaller than the overlap it reports less than the bodies'.
  row.depthError = deepest - pair.penetration;
  const double cosine = std::clamp(double(push.normalized().dot(pair.normal)), -1.0, 1.0);
  row.normalErrorDeg = std::acos(cosine) * 180.0 / kPi;
  return row;
}

void study(std::vector<AccuracyRow>& rows, AccuracyRow row, const std::string& name, const std::string& setting,
           bool isDefault) {
  row.study = name;
  row.setting = setting;
  row.isDefault = isDefault;
  printAccuracyRow(row);
  rows.push_back(std::move(row));
}

void reductionStudy(const AccuracyContext& context, std::vector<AccuracyRow>& rows) {
  const Config defaults;
  for (int resolution : {0, 1, 2, 3, 4, 6, 8}) {
    Config config;
    config.reductionResolution = resolution;
    for (const AnalyticPair& pair : {boxOnBox(4, config), spherePair(context.quick ? 2 : 4, config)}) {
      AccuracyRow row = measureAnalytic(pair, config, std::max(context.runs, 11));
      row.reductionResolution = std::to_string(resolution);
      study(rows, row, "reduction", std::to_string(resolution), resolution == defaults.reductionResolution);
    }
  }
}

void tessellationStudy(const AccuracyContext& context, std::vector<AccuracyRow>& rows) {
  const Config config;
  for (int level = 1; level <= (context.quick ? 3 : 5); ++level) {
    AccuracyRow row = measureAnalytic(spherePair(level, config), config, std::max(context.runs, 11));
    study(rows, row, "tessellation", "level " + std::to_string(level), false);
  }
  for (int n : {1, 2, 4, 8, 16}) {
    AccuracyRow row = measureAnalytic(boxOnBox(n, config), config, std::max(context.runs, 11));
    study(rows, row, "tessellation", "n=" + std::to_string(n), false);
  }
}

// Triangle t of `mesh` under the rigid `transform` of its body followed by `toFrame`, in double.
test::TriangleD carriedTriangle(const TriangleMesh& mesh, std::uint32_t t, const btTransform& toFrame) {
  test::TriangleD out;
  for (int k = 0; k < 3; ++k) {
    const float* p = mesh.positions().data() + 3 * std::size_t(mesh.indices()[3 * std::size_t(t) + k]);
    for (int r = 0; r < 3; ++r) {
      double v = toFrame.getOrigin()[r];
      for (int c = 0; c < 3; ++c) v += double(toFrame.getBasis()[r][c]) * double(p[c]);
      out[k][r] = v;
    }
  }
  return out;
}

// Every intersecting triangle pair of two placed meshes, in double: B carried into A's frame exactly, boxes
// first, then the separating-axis reference of the test suite.
std::set<TrianglePair> bruteForceIntersecting(const TriangleMesh& meshA, const btTransform& transformA,
                                              const TriangleMesh& meshB, const btTransform& transformB) {
  const btTransform identity = btTransform::getIdentity();
  const btTransform bToA = transformA.inverse() * transformB;
  std::vector<test::TriangleD> a(meshA.triangleCount()), b(meshB.triangleCount());
  std::vector<Eigen::AlignedBox3d> boxA(a.size()), boxB(b.size());
  for (std::uint32_t i = 0; i < a.size(); ++i) {
    a[i] = carriedTriangle(meshA, i, identity);
    for (const auto& v : a[i]) boxA[i].extend(v);
  }
  for (std::uint32_t j = 0; j < b.size(); ++j) {
    b[j] = carriedTriangle(meshB, j, bToA);
    for (const auto& v : b[j]) boxB[j].extend(v);
  }
  std::set<TrianglePair> found;
  for (std::uint32_t i = 0; i < a.size(); ++i) {
    for (std::uint32_t j = 0; j < b.size(); ++j) {
      if (boxA[i].intersects(boxB[j]) && test::referenceIntersect(a[i], b[j])) found.insert({i, j});
    }
  }
  return found;
}

// Missed and false pairs of `found` against `reference`.
void countDifferences(const std::set<TrianglePair>& reference, const std::vector<TrianglePair>& found,
                      AccuracyRow& row) {
  const std::set<TrianglePair> got(found.begin(), found.end());
  double missed = 0, extra = 0;
  for (const TrianglePair& p : reference) missed += !got.count(p);
  for (const TrianglePair& p : got) extra += !reference.count(p);
  row.missedPairs = missed;
  row.falsePairs = extra;
}

struct ThesisScene {
  std::string name;
  std::shared_ptr<const TriangleMesh> mesh;
  scenes::PairPose pose;
};

ThesisScene thesisScene(const AccuracyContext& context, const std::string& file) {
  ThesisScene scene;
  scene.name = file.substr(0, file.find('.')) + " thesis";
  scene.mesh = std::make_shared<const TriangleMesh>(
      scenes::centredOnVertexCentroid(loadMesh(context.meshDirectory + "/" + file)));
  scene.pose = scenes::thesisPose(*scene.mesh);
  return scene;
}

void leafSizeStudy(const AccuracyContext& context, std::vector<AccuracyRow>& rows, const ThesisScene& small,
                   const std::set<TrianglePair>& smallReference, const ThesisScene* large) {
  const Config defaults;
  for (int leaf : {1, 2, 4, 8, 16}) {
    Config config;
    config.trianglesPerLeaf = leaf;
    for (const ThesisScene* scene : {&small, large}) {
      if (scene == nullptr) continue;
      const MeshShape shape(scene->mesh, config);
      MeshPairResult result;
      std::vector<double> samples;
      for (int i = 0; i < context.runs; ++i) {
        samples.push_back(
            millisecondsOf([&] { result = collideMeshes(shape, scene->pose.a, shape, scene->pose.b, config); }));
      }
      AccuracyRow row;
      row.scene = scene->name;
      row.timeMs = median(samples);
      row.contacts = double(result.reducedContacts.size());
      if (scene == &small) countDifferences(smallReference, result.intersectingPairs, row);
      row.trianglesPerLeaf = std::to_string(leaf);
      study(rows, row, "leaf_size", std::to_string(leaf), leaf == defaults.trianglesPerLeaf);
    }
  }
}

// The triangles of candidate pairs as the near phase sees them: A in its own frame, B carried in float.
struct CandidateTriangles {
  std::vector<test::TriangleF> a, b;
};

CandidateTriangles candidateTriangles(const ThesisScene& scene, const std::vector<TrianglePair>& candidates) {
  const btTransform bToA = scene.pose.a.inverse() * scene.pose.b;
  CandidateTriangles out;
  for (const TrianglePair& p : candidates) {
    test::TriangleF a, b;
    for (int k = 0; k < 3; ++k) {
      const float* pa = scene.mesh->positions().data() + 3 * std::size_t(scene.mesh->indices()[3 * std::size_t(p.triangleA) + k]);
      const float* pb = scene.mesh->positions().data() + 3 * std::size_t(scene.mesh->indices()[3 * std::size_t(p.triangleB) + k]);
      a[k] = Eigen::Vector3f(pa[0], pa[1], pa[2]);
      const btVector3 carried = bToA * btVector3(pb[0], pb[1], pb[2]);
      b[k] = Eigen::Vector3f(carried.x(), carried.y(), carried.z());
    }
    out.a.push_back(a);
    out.b.push_back(b);
  }
  return out;
}

// Random pairs of every family of the near phase tests (near-coplanar, touching, shared vertices...): where
// float and double part ways.
CandidateTriangles randomFamilyTriangles(int perFamily) {
  std::mt19937_64 rng(4242);
  CandidateTriangles out;
  for (int f = 0; f < static_cast<int>(test::PairFamily::Count); ++f) {
    for (int i = 0; i < perFamily; ++i) {
      test::TriangleF a, b;
      test::randomPair(static_cast<test::PairFamily>(f), rng, a, b);
      out.a.push_back(a);
      out.b.push_back(b);
    }
  }
  return out;
}

void precisionStudy(const AccuracyContext& context, std::vector<AccuracyRow>& rows,
                    const std::vector<std::pair<std::string, CandidateTriangles>>& sets) {
  for (const auto& [name, set] : sets) {
    std::vector<bool> reference(set.a.size());
    for (std::size_t i = 0; i < set.a.size(); ++i) {
      reference[i] = test::referenceIntersect(test::toDouble(set.a[i]), test::toDouble(set.b[i]));
    }
    for (const bool useFloat : {false, true}) {
      std::vector<bool> answers(set.a.size());
      std::vector<double> samples;
      for (int run = 0; run < context.runs; ++run) {
        samples.push_back(millisecondsOf([&] {
          for (std::size_t i = 0; i < set.a.size(); ++i) {
            const test::TriangleF& a = set.a[i];
            const test::TriangleF& b = set.b[i];
            answers[i] = useFloat ? trianglesIntersectFloat(a[0], a[1], a[2], b[0], b[1], b[2])
                                  : trianglesIntersect(a[0], a[1], a[2], b[0], b[1], b[2]);
          }
        }));
      }
      AccuracyRow row;
      row.scene = name;
      row.timeMs = median(samples);
      double missed = 0, extra = 0;
      for (std::size_t i = 0; i < answers.size(); ++i) {
        missed += reference[i] && !answers[i];
        extra += !reference[i] && answers[i];
      }
      row.missedPairs = missed;
      row.falsePairs = extra;
      row.precision = useFloat ? "float" : "double";
      study(rows, row, "precision", row.precision, !useFloat);
    }
  }
}

}  // namespace

void runMeshAccuracyStudies(const AccuracyContext& context, std::vector<AccuracyRow>& rows) {
  std::cout << "reduction: contacts of a box on a box and of two spheres, against the analytic answer\n";
  reductionStudy(context, rows);
  std::cout << "tessellation: the same at several tessellations (default configuration)\n";
  tessellationStudy(context, rows);

  const ThesisScene small = thesisScene(context, "armadillo-2766.ply");
  std::cout << "brute force over every triangle pair of " << small.name << " (double, separating axes) ..."
            << std::endl;
  const std::set<TrianglePair> smallReference =
      bruteForceIntersecting(*small.mesh, small.pose.a, *small.mesh, small.pose.b);
  std::unique_ptr<ThesisScene> large;
  if (!context.quick) large = std::make_unique<ThesisScene>(thesisScene(context, "armadillo-27674.ply"));
  std::cout << "leaf_size: triangles per tree leaf, intersecting pairs against the brute force\n";
  leafSizeStudy(context, rows, small, smallReference, large.get());

  std::cout << "precision: the exact test in double (gpucol) or float alone, on the middle phase's candidates\n";
  std::vector<std::pair<std::string, CandidateTriangles>> sets;
  const MeshShape smallShape(small.mesh);
  sets.emplace_back(small.name, candidateTriangles(small, collideMeshes(smallShape, small.pose.a, smallShape,
                                                                        small.pose.b).candidatePairs));
  if (large) {
    const MeshShape largeShape(large->mesh);
    sets.emplace_back(large->name, candidateTriangles(*large, collideMeshes(largeShape, large->pose.a, largeShape,
                                                                            large->pose.b).candidatePairs));
  }
  sets.emplace_back("random families", randomFamilyTriangles(context.quick ? 2000 : 20000));
  precisionStudy(context, rows, sets);
}

}  // namespace gpucol::bench
