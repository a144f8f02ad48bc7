// flatFaceHalfExtents: each triangle's flat face (the triangles joined to it across flat diagonals) and the
// half extents of the box around it.
#include "mesh/flat_faces.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <vector>

#include "gpucol/triangle_mesh.h"
#include "mesh/edge_wings.h"
#include "scenes/procedural_meshes.h"

namespace gpucol {
namespace {

std::vector<float> halfExtentsOf(const TriangleMesh& mesh) {
  const std::vector<std::uint32_t> across = matchEdges(mesh);
  return flatFaceHalfExtents(mesh, across, findFlatDiagonals(mesh, buildEdgeWings(mesh, across)));
}

// The box around a triangle's own three vertices.
std::vector<float> ownHalfExtents(const TriangleMesh& mesh, std::size_t t) {
  std::vector<float> half(3);
  for (int c = 0; c < 3; ++c) {
    float lo = INFINITY, hi = -INFINITY;
    for (int i = 0; i < 3; ++i) {
      const float v = mesh.positions()[3 * std::size_t(mesh.indices()[3 * t + i]) + c];
      lo = std::min(lo, v);
      hi = std::max(hi, v);
    }
    half[std::size_t(c)] = 0.5f * (hi - lo);
  }
  return half;
}

// Every triangle of a box, subdivided or not, belongs to its whole side: the side's box is the box's own,
// flattened along the side's normal.
TEST(FlatFaces, EveryTriangleOfABoxSpansItsWholeSide) {
  for (int detail : {1, 3}) {
    const TriangleMesh box = scenes::makeBox(1, 2, 3, detail);
    const std::vector<float> half = halfExtentsOf(box);
    ASSERT_EQ(half.size(), 3 * box.triangleCount());
    for (std::size_t t = 0; t < box.triangleCount(); ++t) {
      int flatAxes = 0;
      const float full[3] = {1, 2, 3};
      for (int c = 0; c < 3; ++c) {
        const float h = half[3 * t + std::size_t(c)];
        if (h == 0) {
          ++flatAxes;
        } else {
          EXPECT_FLOAT_EQ(h, full[c]) << "detail " << detail << " triangle " << t << " axis " << c;
        }
      }
      EXPECT_EQ(flatAxes, 1) << "detail " << detail << " triangle " << t;
    }
  }
}

// A plus-shaped prism's caps are one flat face each (the arms and the centre, not convex), its sides
// rectangles of their own.
TEST(FlatFaces, ACrossCapIsOneFaceOverAllItsArms) {
  const TriangleMesh cross = scenes::makeCross(0.4f, 0.08f, 0.08f);
  const std::vector<float> half = halfExtentsOf(cross);
  std::size_t caps = 0;
  for (std::size_t t = 0; t < cross.triangleCount(); ++t) {
    if (half[3 * t + 2] != 0) continue;  // not flat across z: a side
    ++caps;
    EXPECT_FLOAT_EQ(half[3 * t], 0.4f) << t;
    EXPECT_FLOAT_EQ(half[3 * t + 1], 0.4f) << t;
  }
  EXPECT_GT(caps, 4u);
}

// A tessellated sphere has no flat diagonal: each triangle is a face of its own; a quad bent by 1e-3 of its
// size is two faces, one bent by 1e-6 is one.
TEST(FlatFaces, CurvedAndBentSurfacesKeepTheirTriangles) {
  const TriangleMesh sphere = scenes::makeIcosphere(1, 2);
  const std::vector<float> half = halfExtentsOf(sphere);
  for (std::size_t t = 0; t < sphere.triangleCount(); ++t) {
    const std::vector<float> own = ownHalfExtents(sphere, t);
    for (int c = 0; c < 3; ++c) EXPECT_EQ(half[3 * t + std::size_t(c)], own[std::size_t(c)]) << t;
  }
  for (float bend : {1e-3f, 1e-6f}) {
    const TriangleMesh quad =
        TriangleMesh::fromArrays({0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, bend}, {0, 1, 2, 0, 2, 3}, "quad");
    const std::vector<float> h = halfExtentsOf(quad);
    // Joined, each triangle spans the whole unit square; apart, its own half of it (still 0.5 by 0.5).
    EXPECT_EQ(h[0], 0.5f) << bend;
    EXPECT_EQ(h[1], 0.5f) << bend;
    const std::vector<float> own0 = ownHalfExtents(quad, 0), own1 = ownHalfExtents(quad, 1);
    if (bend < 1e-4f) {
      EXPECT_EQ(h[2], 0.5f * bend);  // the first triangle's box reaches the lifted corner
    } else {
      EXPECT_EQ(h[2], own0[2]);
      EXPECT_EQ(h[5], own1[2]);
    }
  }
}

}  // namespace
}  // namespace gpucol
