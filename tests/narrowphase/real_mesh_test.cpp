// The near phase on real meshes: every pair of triangles whose boxes overlap, for a mesh against itself
// (adjacent triangles share vertices exactly: touching) and against a rotated, shifted copy of itself,
// compared with the double-precision reference.

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <iostream>
#include <random>
#include <vector>

#include "gpucol/triangle_mesh.h"
#include "narrowphase/triangle_contact.h"
#include "narrowphase/triangle_intersection.h"
#include "random_triangles.h"
#include "reference_triangles.h"
#include "support/test_paths.h"

namespace gpucol {
namespace {

using test::TriangleF;

/// The triangles of a mesh file, read with the plugin's loader, at most `limit` of them.
std::vector<TriangleF> loadTriangles(const std::string& path, std::size_t limit) {
  const TriangleMesh mesh = loadMesh(path);
  std::vector<TriangleF> triangles;
  for (std::size_t t = 0; t < mesh.triangleCount() && triangles.size() < limit; ++t) {
    TriangleF triangle;
    for (int k = 0; k < 3; ++k) {
      const float* v = mesh.positions().data() + 3 * std::size_t(mesh.indices()[3 * t + k]);
      triangle[k] = Eigen::Vector3f(v[0], v[1], v[2]);
    }
    triangles.push_back(triangle);
  }
  return triangles;
}

struct Box {
  Eigen::Vector3f lower, upper;
};

Box boxOf(const TriangleF& t) {
  return {t[0].cwiseMin(t[1]).cwiseMin(t[2]), t[0].cwiseMax(t[1]).cwiseMax(t[2])};
}

bool overlap(const Box& a, const Box& b) {
  return (a.lower.array() <= b.upper.array()).all() && (b.lower.array() <= a.upper.array()).all();
}

struct Counts {
  long pairs = 0, intersecting = 0, disagreements = 0, contacts = 0;
};

/// Brute force over all box-overlapping pairs; checks the test against the reference and the contacts.
Counts checkAllPairs(const std::vector<TriangleF>& meshA, const std::vector<TriangleF>& meshB) {
  constexpr double kBand = 1e-6;
  Counts counts;
  std::vector<Box> boxesB(meshB.size());
  for (std::size_t j = 0; j < meshB.size(); ++j) boxesB[j] = boxOf(meshB[j]);
  for (std::size_t i = 0; i < meshA.size(); ++i) {
    const TriangleF& a = meshA[i];
    const Box boxA = boxOf(a);
    const test::TriangleD da = test::toDouble(a);
    for (std::size_t j = 0; j < meshB.size(); ++j) {
      if (!overlap(boxA, boxesB[j])) continue;
      const TriangleF& b = meshB[j];
      const test::TriangleD db = test::toDouble(b);
      ++counts.pairs;
      // Real meshes may hold slivers; the test calls those degenerate only below sin^2 = 1e-12.
      const bool actual = trianglesIntersect(a[0], a[1], a[2], b[0], b[1], b[2]);
      const bool expected = test::referenceIntersect(da, db);
      counts.intersecting += expected;
      const double scale = test::pairScale(da, db);
      if (actual != expected) {
        ++counts.disagreements;
        const double separation = test::signedSeparation(da, db) / scale;
        EXPECT_LE(std::fabs(separation), kBand)
            << "triangles " << i << ", " << j << ": reference " << expected;
      }
      const Eigen::Vector3f pa[3] = {a[0], a[1], a[2]};
      const Eigen::Vector3f pb[3] = {b[0], b[1], b[2]};
      const std::optional<TriangleContact> c = generateContact(pa, pb);
      if (!c) continue;
      ++counts.contacts;
      EXPECT_TRUE(actual) << "contact without intersection: " << i << ", " << j;
      EXPECT_LE(c->depth, 0.0f);
      EXPECT_NEAR(c->normalOnB.norm(), 1.0f, 1e-5f);
      EXPECT_LT(test::pointTriangleDistance(c->point.cast<double>(), da), 1e-5 * scale) << i << ", " << j;
      EXPECT_LT(test::pointTriangleDistance(c->point.cast<double>(), db), 1e-5 * scale) << i << ", " << j;
    }
  }
  return counts;
}

void checkMesh(const std::string& file, std::size_t limit) {
  const std::string path = test::meshPath(file);
  const std::vector<TriangleF> mesh = loadTriangles(path, limit);
  ASSERT_FALSE(mesh.empty()) << "could not read " << path;

  // Against itself: neighbours share vertices exactly, so they touch and must be reported intersecting.
  const Counts self = checkAllPairs(mesh, mesh);
  EXPECT_EQ(self.disagreements, 0);
  EXPECT_GE(self.intersecting, static_cast<long>(mesh.size()));  // at least each triangle with itself

  // Against a copy turned by a random rotation about its centre and shifted by 5% of its size.
  Eigen::Vector3f lower = mesh[0][0], upper = mesh[0][0];
  for (const TriangleF& t : mesh) {
    for (const Eigen::Vector3f& v : t) lower = lower.cwiseMin(v), upper = upper.cwiseMax(v);
  }
  const Eigen::Vector3d centre = (0.5f * (lower + upper)).cast<double>();
  std::mt19937_64 rng(11);
  const Eigen::Matrix3d rotation = test::randomRotation(rng);
  const Eigen::Vector3d shift =
      0.05 * (upper - lower).cast<double>().norm() * Eigen::Vector3d(0.3, -0.5, 0.8).normalized();
  std::vector<TriangleF> moved = mesh;
  for (TriangleF& t : moved) {
    for (Eigen::Vector3f& v : t) v = (rotation * (v.cast<double>() - centre) + centre + shift).cast<float>();
  }
  const Counts pair = checkAllPairs(mesh, moved);
  EXPECT_GT(pair.intersecting, 0);
  std::cout << "  " << file << " (" << mesh.size() << " triangles): self " << self.pairs << " box pairs, "
            << self.intersecting << " intersecting, " << self.disagreements << " disagreements, "
            << self.contacts << " contacts; moved copy " << pair.pairs << " box pairs, " << pair.intersecting
            << " intersecting, " << pair.disagreements << " disagreements (all within 1e-6 of touching), "
            << pair.contacts << " contacts\n";
}

TEST(NearPhaseRealMeshes, Bunny) {
  GPUCOL_REQUIRE_MESH(path, "bunny-948.ply");
  checkMesh("bunny-948.ply", 1000);
}

TEST(NearPhaseRealMeshes, Torus) {
  GPUCOL_REQUIRE_MESH(path, "torus-1152.ply");
  checkMesh("torus-1152.ply", 1200);
}

TEST(NearPhaseRealMeshes, FandiskFlatFaces) {
  // A CAD part: large flat regions, so many exactly or nearly coplanar neighbours.
  GPUCOL_REQUIRE_MESH(path, "fandisk-12946.ply");
  checkMesh("fandisk-12946.ply", 3000);
}

}  // namespace
}  // namespace gpucol
