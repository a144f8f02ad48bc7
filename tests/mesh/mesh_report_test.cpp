// MeshReport against a brute-force reference on random meshes, against hand-made cases, and against
// manifest.json on the real meshes.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <random>
#include <set>

#include "gpucol/triangle_mesh.h"
#include "mesh_test_util.h"
#include "support/test_paths.h"

namespace gpucol {
namespace {

/// Deliberately plain reference: an ordered map keyed by the vertex pair, a quadratic
/// scan for duplicates, and the flatness ratio computed directly in long double.
MeshReport referenceReport(const std::vector<float>& xyz, const std::vector<std::uint32_t>& idx) {
  MeshReport r;
  r.vertexCount = xyz.size() / 3;
  r.triangleCount = idx.size() / 3;
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::pair<int, int>> edges;  // (uses, forward uses)
  for (std::size_t t = 0; t < r.triangleCount; ++t) {
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = idx[3 * t + k], b = idx[3 * t + (k + 1) % 3];
      auto& e = edges[std::minmax(a, b)];
      ++e.first;
      e.second += a < b ? 1 : 0;
    }
  }
  r.edgeCount = edges.size();
  for (const auto& [key, e] : edges) {
    r.boundaryEdges += e.first == 1;
    r.nonManifoldEdges += e.first > 2;
    r.inconsistentEdges += e.first == 2 && e.second != 1;
  }
  r.closed = r.boundaryEdges == 0 && r.nonManifoldEdges == 0;
  r.edgeCountMatchesClosedManifold = 2 * r.edgeCount == 3 * r.triangleCount;
  for (std::size_t t = 0; t < r.triangleCount; ++t) {
    std::set<std::uint32_t> mine(&idx[3 * t], &idx[3 * t] + 3);
    for (std::size_t s = 0; s < t; ++s) {
      if (std::set<std::uint32_t>(&idx[3 * s], &idx[3 * s] + 3) == mine) {
        r.duplicateTriangles.push_back(std::uint32_t(t));
        break;
      }
    }
    long double p[3][3];
    for (int k = 0; k < 3; ++k)
      for (int j = 0; j < 3; ++j) p[k][j] = xyz[3 * idx[3 * t + k] + j];
    long double e[3][3], n[3];
    for (int j = 0; j < 3; ++j) {
      e[0][j] = p[1][j] - p[0][j];
      e[1][j] = p[2][j] - p[0][j];
      e[2][j] = p[2][j] - p[1][j];
    }
    n[0] = e[0][1] * e[1][2] - e[0][2] * e[1][1];
    n[1] = e[0][2] * e[1][0] - e[0][0] * e[1][2];
    n[2] = e[0][0] * e[1][1] - e[0][1] * e[1][0];
    long double longest = 0;
    for (auto& edge : e)
      longest = std::max(longest, edge[0] * edge[0] + edge[1] * edge[1] + edge[2] * edge[2]);
    const long double area2 = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (longest == 0 || area2 <= kDegenerateTriangleRatio * longest)
      r.degenerateTriangles.push_back(std::uint32_t(t));
  }
  std::vector<bool> used(r.vertexCount);
  for (auto v : idx) used[v] = true;
  r.unreferencedVertices = std::size_t(std::count(used.begin(), used.end(), false));
  return r;
}

void expectSameReport(const MeshReport& a, const MeshReport& b, const std::string& what) {
  EXPECT_EQ(a.vertexCount, b.vertexCount) << what;
  EXPECT_EQ(a.triangleCount, b.triangleCount) << what;
  EXPECT_EQ(a.edgeCount, b.edgeCount) << what;
  EXPECT_EQ(a.boundaryEdges, b.boundaryEdges) << what;
  EXPECT_EQ(a.nonManifoldEdges, b.nonManifoldEdges) << what;
  EXPECT_EQ(a.inconsistentEdges, b.inconsistentEdges) << what;
  EXPECT_EQ(a.edgeCountMatchesClosedManifold, b.edgeCountMatchesClosedManifold) << what;
  EXPECT_EQ(a.degenerateTriangles, b.degenerateTriangles) << what;
  EXPECT_EQ(a.duplicateTriangles, b.duplicateTriangles) << what;
  EXPECT_EQ(a.unreferencedVertices, b.unreferencedVertices) << what;
  EXPECT_EQ(a.closed, b.closed) << what;
}

TEST(MeshReport, RandomMeshesMatchBruteForce) {
  // Few vertices and many triangles, so shared, non-manifold, duplicate and reversed edges all occur;
  // some positions sit on a line so degenerate triangles occur too.
  std::mt19937 rng(12345);
  for (int trial = 0; trial < 200; ++trial) {
    const std::uint32_t vertices = 4 + rng() % 12;
    const std::size_t triangles = 1 + rng() % 40;
    std::vector<float> xyz;
    std::uniform_real_distribution<float> u(-1, 1);
    for (std::uint32_t v = 0; v < vertices; ++v) {
      if (rng() % 4 == 0) {
        const float s = u(rng);
        xyz.insert(xyz.end(), {s, 2 * s, -s});  // on one line through the origin
      } else {
        xyz.insert(xyz.end(), {u(rng), u(rng), u(rng)});
      }
    }
    std::vector<std::uint32_t> idx;
    while (idx.size() < 3 * triangles) {
      const std::uint32_t a = rng() % vertices, b = rng() % vertices, c = rng() % vertices;
      if (a != b && b != c && a != c) idx.insert(idx.end(), {a, b, c});
    }
    const TriangleMesh mesh = TriangleMesh::fromArrays(xyz, idx, "random");
    expectSameReport(mesh.report(), referenceReport(xyz, idx), "trial " + std::to_string(trial));
  }
}

TEST(MeshReport, ClosedBoxAndOpenBox) {
  const auto box = test::boxArrays({1, 2, 3}, {0, 0, 0}, 2);
  const MeshReport closed = TriangleMesh::fromArrays(box.xyz, box.indices).report();
  EXPECT_TRUE(closed.closed);
  EXPECT_TRUE(closed.edgeCountMatchesClosedManifold);
  EXPECT_EQ(closed.triangleCount, 48u);
  EXPECT_EQ(closed.edgeCount, 72u);  // E = 3F/2
  EXPECT_EQ(closed.vertexCount, 26u);
  EXPECT_EQ(closed.boundaryEdges + closed.nonManifoldEdges + closed.inconsistentEdges, 0u);
  EXPECT_EQ(closed.summary(),
            "48 triangles, 26 vertices, 72 edges, closed 2-manifold, 0 degenerate, 0 duplicate triangles");

  auto open = box;
  open.indices.resize(open.indices.size() - 6);  // remove one quad: a square hole of 4 edges
  open.xyz.insert(open.xyz.end(), {9, 9, 9});    // and an unused vertex
  const MeshReport r = TriangleMesh::fromArrays(open.xyz, open.indices).report();
  EXPECT_FALSE(r.closed);
  EXPECT_FALSE(r.edgeCountMatchesClosedManifold);
  EXPECT_EQ(r.boundaryEdges, 4u);
  EXPECT_EQ(r.unreferencedVertices, 1u);
  EXPECT_EQ(
      r.summary(),
      "46 triangles, 27 vertices, 71 edges, open (4 boundary edges), 0 degenerate, 0 duplicate triangles, "
      "1 unreferenced vertices");
}

TEST(MeshReport, DuplicateTrianglesInAnyOrderOrWinding) {
  auto box = test::boxArrays({1, 1, 1});
  const std::uint32_t a = box.indices[3], b = box.indices[4], c = box.indices[5];
  box.indices.insert(box.indices.end(), {c, a, b, b, a, c, a, b, c});  // rotated, reversed, identical
  const MeshReport r = TriangleMesh::fromArrays(box.xyz, box.indices).report();
  EXPECT_EQ(r.duplicateTriangles, (std::vector<std::uint32_t>{12, 13, 14}));
  EXPECT_EQ(r.nonManifoldEdges, 3u);  // triangle 1's edges are now used 5 times
  EXPECT_FALSE(r.closed);
}

TEST(MeshReport, DegenerateThreshold) {
  // Flatness = height / longest edge. Heights just above and below 1e-6 of a unit edge.
  const std::vector<float> xyz = {0, 0, 0, 1, 0, 0, 0.5f, 2e-6f, 0, 0.5f, 5e-7f, 0, 0.5f, 0, 0};
  const MeshReport r = TriangleMesh::fromArrays(xyz, {0, 1, 2, 0, 1, 3, 0, 1, 4}).report();
  EXPECT_EQ(r.degenerateTriangles, (std::vector<std::uint32_t>{1, 2}));
}

struct ManifestEntry {
  const char* file;
  std::size_t vertices, triangles, edges, boundary, nonManifold, duplicates, unreferenced;
  bool closed;
};

// From ../shared/data/meshes/manifest.json ("stats"); the derived armadillos from SOURCES.md.
const ManifestEntry kManifest[] = {
    {"armadillo-5000.ply", 2502, 5000, 7500, 0, 0, 0, 0, true},
    {"armadillo-25000.ply", 12502, 25000, 37500, 0, 0, 0, 0, true},
    {"armadillo-29170.ply", 14587, 29170, 43755, 0, 0, 0, 0, true},
    {"bunny-69451.ply", 35947, 69451, 104288, 223, 0, 0, 1113, false},
    {"bunny-16301.ply", 8171, 16301, 24363, 123, 150, 87, 25, false},
    {"bunny-3851.ply", 1889, 3851, 5661, 60, 141, 83, 2, false},
    {"bunny-948.ply", 453, 948, 1363, 26, 70, 40, 0, false},
    {"torus-1152.ply", 576, 1152, 1728, 0, 0, 0, 0, true},
    {"teapot-6320.ply", 3644, 6320, 9998, 1036, 0, 0, 0, false},
    {"fandisk-12946.ply", 6475, 12946, 19419, 0, 0, 0, 0, true},
    {"rocker-arm-20088.ply", 10044, 20088, 30132, 0, 0, 0, 0, true},
    {"dragon-20000.ply", 10002, 20000, 30000, 0, 0, 0, 0, true},
};

TEST(MeshReport, RealMeshesMatchManifest) {
  std::size_t found = 0;
  for (const ManifestEntry& m : kManifest) {
    const std::string path = test::meshPath(m.file);
    if (path.empty()) continue;
    ++found;
    const MeshReport r = loadMesh(path).report();
    EXPECT_EQ(r.vertexCount, m.vertices) << m.file;
    EXPECT_EQ(r.triangleCount, m.triangles) << m.file;
    EXPECT_EQ(r.edgeCount, m.edges) << m.file;
    EXPECT_EQ(r.boundaryEdges, m.boundary) << m.file;
    EXPECT_EQ(r.nonManifoldEdges, m.nonManifold) << m.file;
    EXPECT_EQ(r.duplicateTriangles.size(), m.duplicates) << m.file;
    EXPECT_EQ(r.unreferencedVertices, m.unreferenced) << m.file;
    EXPECT_EQ(r.closed, m.closed) << m.file;
    EXPECT_EQ(r.edgeCountMatchesClosedManifold, m.closed) << m.file;
    EXPECT_EQ(r.inconsistentEdges, 0u) << m.file;          // manifest: no inconsistently oriented edges
    EXPECT_TRUE(r.degenerateTriangles.empty()) << m.file;  // manifest: no zero-area triangles
  }
  if (found == 0) GTEST_SKIP() << "no real meshes in " << test::meshDirectory();
}

TEST(MeshReport, DerivedArmadillosAreSlightlyDirty) {
  // SOURCES.md: the decimated 2766 and 27674 have 2 and 3 edges not shared by exactly two triangles.
  for (const auto& [file, bad] : {std::pair<const char*, std::size_t>{"armadillo-2766.ply", 2},
                                  std::pair<const char*, std::size_t>{"armadillo-27674.ply", 3}}) {
    GPUCOL_REQUIRE_MESH(path, file);
    const MeshReport r = loadMesh(path).report();
    EXPECT_EQ(r.boundaryEdges + r.nonManifoldEdges, bad) << file << ": " << r.summary();
    EXPECT_FALSE(r.closed) << file;
  }
  // Edges shared by three triangles but no hole: the summary must not call it open.
  GPUCOL_REQUIRE_MESH(path, "armadillo-27674.ply");
  const MeshReport r = loadMesh(path).report();
  EXPECT_EQ(r.boundaryEdges, 0u);
  EXPECT_EQ(r.summary(),
            "27674 triangles, 13839 vertices, 41508 edges, not closed, 3 non-manifold edges, "
            "0 degenerate, 3 duplicate triangles");
}

TEST(MeshReport, LargeMeshLoadsAndReportsQuickly) {
  GPUCOL_REQUIRE_MESH(path, "armadillo-399904.ply");
  const auto start = std::chrono::steady_clock::now();
  const TriangleMesh mesh = loadMesh(path);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_EQ(mesh.vertexCount(), 199954u);
  EXPECT_EQ(mesh.triangleCount(), 399904u);
  EXPECT_TRUE(mesh.report().closed) << mesh.report().summary();
  EXPECT_EQ(mesh.report().edgeCount, 599856u);
  std::printf("[ info ] armadillo-399904: load + validation + report %.3f s\n", seconds);
#if defined(NDEBUG) && !defined(__SANITIZE_ADDRESS__)
  // Optimised builds only: measured 0.2 to 0.55 s on a shared 2-core machine; 3 s leaves room for load.
  EXPECT_LT(seconds, 3.0) << "load + report took " << seconds << " s";
#endif
}

}  // namespace
}  // namespace gpucol
