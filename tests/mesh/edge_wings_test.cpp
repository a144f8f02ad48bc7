// buildEdgeWings: for each triangle edge, the far vertex of the one triangle across it, matched by position;
// findFlatDiagonals: which of those edges are diagonals of a flat face.
#include "mesh/edge_wings.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <vector>

#include "gpucol/triangle_mesh.h"
#include "scenes/procedural_meshes.h"

namespace gpucol {
namespace {

bool known(const std::vector<float>& wings, std::size_t t, int k) {
  return !std::isnan(wings[9 * t + 3 * k]);
}

// A closed box: every edge has exactly one triangle across it, and the wing is a vertex of that triangle, not
// on the edge itself.
TEST(EdgeWings, EveryEdgeOfAClosedBoxHasItsWing) {
  const TriangleMesh box = scenes::makeBox(1, 2, 3);
  const std::vector<float> wings = buildEdgeWings(box, matchEdges(box));
  ASSERT_EQ(wings.size(), 9 * box.triangleCount());
  for (std::size_t t = 0; t < box.triangleCount(); ++t) {
    for (int k = 0; k < 3; ++k) {
      ASSERT_TRUE(known(wings, t, k)) << t << ' ' << k;
      const float* w = &wings[9 * t + 3 * k];
      // Every vertex of the box is a corner: the wing is one too.
      EXPECT_EQ(std::fabs(w[0]), 1.0f);
      EXPECT_EQ(std::fabs(w[1]), 2.0f);
      EXPECT_EQ(std::fabs(w[2]), 3.0f);
      // Not an end of the edge.
      for (int end : {k, (k + 1) % 3}) {
        const std::uint32_t v = box.indices()[3 * t + end];
        const bool same = box.positions()[3 * v] == w[0] && box.positions()[3 * v + 1] == w[1] &&
                          box.positions()[3 * v + 2] == w[2];
        EXPECT_FALSE(same) << t << ' ' << k;
      }
    }
  }
}

// Two triangles sharing an edge, given as separate vertices (a face's own): matched by position. The outer
// edges have none.
TEST(EdgeWings, SharedEdgeOfUnweldedTriangles) {
  std::vector<float> xyz = {0, 0, 0, 1, 0, 0, 0, 1, 0,      // triangle 0: edge 1 from (1,0,0) to (0,1,0)
                            0, 1, 0, 1, 0, 0, 1, 1, 0.5f};  // triangle 1: runs it back, far vertex (1,1,0.5)
  const TriangleMesh mesh = TriangleMesh::fromArrays(xyz, {0, 1, 2, 3, 4, 5}, "two triangles");
  const std::vector<float> wings = buildEdgeWings(mesh, matchEdges(mesh));
  EXPECT_EQ(wings[9 * 0 + 3 * 1 + 0], 1.0f);
  EXPECT_EQ(wings[9 * 0 + 3 * 1 + 1], 1.0f);
  EXPECT_EQ(wings[9 * 0 + 3 * 1 + 2], 0.5f);
  EXPECT_EQ(wings[9 * 1 + 3 * 0 + 0], 0.0f);  // triangle 1's edge 0 ((0,1,0) to (1,0,0)): far vertex (0,0,0)
  EXPECT_EQ(wings[9 * 1 + 3 * 0 + 1], 0.0f);
  for (auto [t, k] : {std::pair{0, 0}, {0, 2}, {1, 1}, {1, 2}})
    EXPECT_FALSE(known(wings, t, k)) << t << ' ' << k;
}

// A triangle across that runs the edge the same way (its winding disagrees), and an edge of three triangles:
// no wing.
TEST(EdgeWings, NoWingAcrossDisagreeingOrNonManifoldEdges) {
  std::vector<float> xyz = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0, 0.5f, 0.5f, 1};
  const TriangleMesh flipped = TriangleMesh::fromArrays(xyz, {0, 1, 2, 1, 2, 3}, "disagreeing");
  std::vector<float> wings = buildEdgeWings(flipped, matchEdges(flipped));
  EXPECT_FALSE(known(wings, 0, 1));
  EXPECT_FALSE(known(wings, 1, 0));
  const TriangleMesh three = TriangleMesh::fromArrays(xyz, {0, 1, 2, 2, 1, 3, 2, 1, 4}, "three on an edge");
  wings = buildEdgeWings(three, matchEdges(three));
  EXPECT_FALSE(known(wings, 0, 1));
  EXPECT_FALSE(known(wings, 1, 0));
  EXPECT_FALSE(known(wings, 2, 0));
}

// findFlatDiagonals: a box of one quad per face has one flat diagonal per triangle, a box of 3 x 3 quads per
// face also flat edges between its quads; a tessellated sphere, none; a quad bent by 1e-3 of its size is not
// flat, one bent by 1e-6 is.
TEST(EdgeWings, FlatDiagonalsOfBoxesButNotOfBentFaces) {
  for (int detail : {1, 3}) {
    const TriangleMesh box = scenes::makeBox(1, 2, 3, detail);
    const std::vector<std::uint8_t> flat = findFlatDiagonals(box, buildEdgeWings(box, matchEdges(box)));
    ASSERT_EQ(flat.size(), box.triangleCount());
    std::size_t flatEdges = 0;
    for (std::uint8_t bits : flat) flatEdges += (bits & 1) + ((bits >> 1) & 1) + ((bits >> 2) & 1);
    // A face of d x d quads, each split by a diagonal, has 3 d^2 + 2 d edges, 4 d of them on its rim; the
    // others are flat and counted from both sides.
    const std::size_t d = std::size_t(detail);
    EXPECT_EQ(flatEdges, 6 * 2 * (3 * d * d - 2 * d)) << "detail " << detail;
  }
  const TriangleMesh sphere = scenes::makeIcosphere(1, 2);
  for (std::uint8_t bits : findFlatDiagonals(sphere, buildEdgeWings(sphere, matchEdges(sphere))))
    EXPECT_EQ(bits, 0);
  for (float bend : {1e-3f, 1e-6f}) {
    // Two triangles of a unit square, the far corner of the second lifted by `bend`.
    const TriangleMesh quad =
        TriangleMesh::fromArrays({0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, bend}, {0, 1, 2, 0, 2, 3}, "quad");
    const std::vector<std::uint8_t> flat = findFlatDiagonals(quad, buildEdgeWings(quad, matchEdges(quad)));
    // The shared edge is edge 2 of the first triangle (2 -> 0) and edge 0 of the second (0 -> 2).
    EXPECT_EQ(flat[0], bend < 1e-4f ? 4 : 0) << bend;
    EXPECT_EQ(flat[1], bend < 1e-4f ? 1 : 0) << bend;
  }
}

}  // namespace
}  // namespace gpucol
