// Validation of TriangleMesh::fromArrays and fromParts (thesis §5.3.1): every bad input gives a MeshError
// whose message names the source, the element (and its part) and the value; valid but poor input is kept and
// reported.
#include "gpucol/triangle_mesh.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

#include "gpucol/mesh_error.h"
#include "mesh_test_util.h"

namespace gpucol {
namespace {

using test::MeshArrays;

/// The message of the MeshError that fromArrays throws, or a test failure if it does not throw one.
std::string errorOf(std::vector<float> xyz, std::vector<std::uint32_t> indices,
                    const std::string& name = "probe") {
  try {
    TriangleMesh::fromArrays(std::move(xyz), std::move(indices), name);
  } catch (const MeshError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no MeshError";
  return {};
}

const std::vector<float> kQuad = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};

TEST(TriangleMeshValidation, EmptyInput) {
  EXPECT_EQ(errorOf({}, {}, "nothing"), "nothing: empty mesh (0 vertices, 0 triangles)");
  EXPECT_EQ(errorOf(kQuad, {}, "points"), "points: empty mesh (4 vertices, 0 triangles)");
}

TEST(TriangleMeshValidation, ArrayLengths) {
  EXPECT_EQ(errorOf({0, 0, 0, 1, 0, 0, 1}, {0, 1, 2}),
            "probe: the coordinate array has 7 floats, not a multiple of 3 (x y z per vertex)");
  EXPECT_EQ(errorOf(kQuad, {0, 1, 2, 0}),
            "probe: the index array has 4 entries, not a multiple of 3 (three per triangle)");
}

TEST(TriangleMeshValidation, NonFiniteCoordinates) {
  std::vector<float> xyz = kQuad;
  xyz[3 * 2 + 1] = std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(errorOf(xyz, {0, 1, 2, 0, 2, 3}, "part.ply"),
            "part.ply: vertex 2 has a non-finite coordinate y = nan");
  xyz = kQuad;
  xyz[3 * 3 + 2] = -std::numeric_limits<float>::infinity();
  EXPECT_EQ(errorOf(xyz, {0, 1, 2, 0, 2, 3}), "probe: vertex 3 has a non-finite coordinate z = -inf");
  // An unreferenced vertex is still checked: its coordinates are part of the mesh.
  xyz = kQuad;
  xyz.insert(xyz.end(), {0, std::numeric_limits<float>::infinity(), 0});
  EXPECT_EQ(errorOf(xyz, {0, 1, 2}), "probe: vertex 4 has a non-finite coordinate y = inf");
}

TEST(TriangleMeshValidation, CoordinatesBeyondTheLimitAreRefused) {
  // Near 3e38 the mesh's box overflowed float (an infinite AABB that never collides); Bullet squares lengths
  // in float, so the limit is 1e18.
  std::vector<float> xyz = kQuad;
  xyz[3 * 1] = 3e38f;
  EXPECT_EQ(errorOf(xyz, {0, 1, 2, 0, 2, 3}),
            "probe: vertex 1 has the coordinate x = 3e+38, beyond gpucol's limit of +-1e+18 (Bullet squares "
            "lengths "
            "in float)");
  xyz = kQuad;
  xyz[3 * 2 + 2] = -std::nextafter(TriangleMesh::kMaxCoordinate, INFINITY);
  EXPECT_NE(errorOf(xyz, {0, 1, 2, 0, 2, 3}).find("probe: vertex 2 has the coordinate z = -1e+18, beyond"),
            std::string::npos);
  xyz = {-1e18f, 0, 0, 1e18f, 0, 0, 0, 1e18f, 0};
  EXPECT_EQ(TriangleMesh::fromArrays(xyz, {0, 1, 2}).vertexCount(), 3u);
}

TEST(TriangleMeshValidation, IndexOutOfRange) {
  EXPECT_EQ(errorOf(kQuad, {0, 1, 2, 0, 2, 4}),
            "probe: triangle 1 corner 2 has vertex index 4, out of range for 4 vertices");
  EXPECT_EQ(errorOf(kQuad, {0, 1, 2, 0xFFFFFFFFu, 2, 3}),
            "probe: triangle 1 corner 0 has vertex index 4294967295, out of range for 4 vertices");
}

TEST(TriangleMeshValidation, RepeatedIndex) {
  EXPECT_EQ(errorOf(kQuad, {0, 1, 2, 3, 2, 2}), "probe: triangle 1 repeats vertex index 2 (corners 1 and 2)");
  EXPECT_EQ(errorOf(kQuad, {0, 1, 2, 3, 1, 3}), "probe: triangle 1 repeats vertex index 3 (corners 0 and 2)");
  EXPECT_EQ(errorOf(kQuad, {1, 1, 2}), "probe: triangle 0 repeats vertex index 1 (corners 0 and 1)");
}

TEST(TriangleMeshValidation, DegenerateTriangleIsKeptAndReported) {
  // Triangle 2 has three collinear corners, triangle 3 two coincident positions (distinct indices):
  // valid input, kept in the mesh, listed by the report.
  std::vector<float> xyz = kQuad;
  xyz.insert(xyz.end(), {2, 0, 0, 3, 0, 0, 4, 0, 0, 0, 0, 0});
  const TriangleMesh mesh = TriangleMesh::fromArrays(xyz, {0, 1, 2, 0, 2, 3, 4, 5, 6, 0, 7, 1});
  EXPECT_EQ(mesh.triangleCount(), 4u);
  EXPECT_EQ(mesh.report().degenerateTriangles, (std::vector<std::uint32_t>{2, 3}));
}

TEST(TriangleMeshValidation, KeepsArraysAndName) {
  const MeshArrays box = test::boxArrays({1, 2, 3}, {0, 0, 0}, 2);
  const TriangleMesh mesh = TriangleMesh::fromArrays(box.xyz, box.indices, "box");
  EXPECT_EQ(mesh.positions(), box.xyz);
  EXPECT_EQ(mesh.indices(), box.indices);
  EXPECT_EQ(mesh.name(), "box");
  EXPECT_EQ(mesh.vertexCount(), box.xyz.size() / 3);
  EXPECT_EQ(mesh.triangleCount(), box.indices.size() / 3);
}

TEST(TriangleMeshTransform, RejectsWhatIsNotAProperRotation) {
  const MeshArrays box = test::boxArrays({1, 1, 1});
  const TriangleMesh mesh = TriangleMesh::fromArrays(box.xyz, box.indices, "box");
  EXPECT_THROW(mesh.transformed({2, 0, 0, 0, 1, 0, 0, 0, 1}, {0, 0, 0}), MeshError);   // scale
  EXPECT_THROW(mesh.transformed({-1, 0, 0, 0, 1, 0, 0, 0, 1}, {0, 0, 0}), MeshError);  // mirror
  EXPECT_THROW(mesh.transformed({1, 0, 0, 0, 1, 0, 0, 0, 1}, {0, NAN, 0}), MeshError);
  // A translation that overflows float is caught by validation of the result, naming the vertex.
  try {
    mesh.transformed({1, 0, 0, 0, 1, 0, 0, 0, 1}, {1e39, 0, 0});
    ADD_FAILURE() << "no MeshError";
  } catch (const MeshError& e) {
    EXPECT_NE(std::string(e.what()).find("box: vertex 0 has a non-finite coordinate x = inf"),
              std::string::npos)
        << e.what();
  }
}

TEST(TriangleMeshTransform, MapsEveryVertex) {
  const MeshArrays box = test::boxArrays({1, 2, 3}, {0.5, 0, 0}, 3);
  const TriangleMesh mesh = TriangleMesh::fromArrays(box.xyz, box.indices, "box");
  const auto r = test::axisAngle({1, 2, 3}, 0.7);
  const std::array<double, 3> t = {10, -20, 30};
  const TriangleMesh moved = mesh.transformed(r, t);
  ASSERT_EQ(moved.indices(), mesh.indices());
  for (std::size_t v = 0; v < mesh.vertexCount(); ++v) {
    for (int i = 0; i < 3; ++i) {
      double expected = t[i];
      for (int j = 0; j < 3; ++j) expected += r[3 * i + j] * double(mesh.positions()[3 * v + j]);
      EXPECT_NEAR(moved.positions()[3 * v + i], expected, 4e-6)
          << "vertex " << v;  // float rounding at |x| ~ 30
    }
  }
}

/// The message of the MeshError that fromParts throws ("" when it throws none).
std::string partsErrorOf(std::vector<float> xyz, std::vector<std::uint32_t> indices,
                         std::vector<MeshPart> parts) {
  try {
    TriangleMesh::fromParts(std::move(xyz), std::move(indices), std::move(parts), "parts");
  } catch (const MeshError& e) {
    return e.what();
  }
  return {};
}

/// Two quads, each a part with its own four vertices.
struct TwoQuads {
  TwoQuads() {
    xyz = kQuad;
    for (std::size_t i = 0; i < kQuad.size(); ++i) xyz.push_back(kQuad[i] + (i % 3 == 2 ? 1.0f : 0.0f));
    indices = {0, 1, 2, 0, 2, 3, 4, 5, 6, 4, 6, 7};
  }
  std::vector<float> xyz;
  std::vector<std::uint32_t> indices;
  std::vector<MeshPart> parts = {{0, 2, 0, 4}, {2, 2, 4, 4}};
};

TEST(TriangleMeshParts, NameEachTriangleByItsPartAndItsIndexInThePart) {
  TwoQuads q;
  const TriangleMesh mesh = TriangleMesh::fromParts(q.xyz, q.indices, q.parts);
  ASSERT_EQ(mesh.parts().size(), 2u);
  const int expected[4][2] = {{0, 0}, {0, 1}, {1, 0}, {1, 1}};
  for (std::uint32_t t = 0; t < 4; ++t) {
    EXPECT_EQ(mesh.partTriangle(t).part, expected[t][0]) << t;
    EXPECT_EQ(mesh.partTriangle(t).index, expected[t][1]) << t;
  }
  // A mesh from arrays is one part; moving a mesh keeps its parts.
  const TriangleMesh single = TriangleMesh::fromArrays(q.xyz, q.indices);
  ASSERT_EQ(single.parts().size(), 1u);
  EXPECT_EQ(single.partTriangle(3).part, 0);
  EXPECT_EQ(single.partTriangle(3).index, 3);
  const TriangleMesh moved = mesh.transformed({0, -1, 0, 1, 0, 0, 0, 0, 1}, {1, 2, 3});
  ASSERT_EQ(moved.parts().size(), 2u);
  EXPECT_EQ(moved.parts()[1].firstTriangle, 2u);
  EXPECT_EQ(moved.parts()[1].firstVertex, 4u);
}

TEST(TriangleMeshParts, RefuseWhatDoesNotTileTheMeshAndNameThePart) {
  {
    TwoQuads q;
    q.parts[1].firstTriangle = 1;
    EXPECT_NE(partsErrorOf(q.xyz, q.indices, q.parts).find("part 1 starts at triangle 1"), std::string::npos);
  }
  {
    TwoQuads q;
    q.parts[1].vertexCount = 3;
    EXPECT_NE(
        partsErrorOf(q.xyz, q.indices, q.parts).find("the parts cover 4 triangles and 7 vertices of 4 and 8"),
        std::string::npos);
  }
  {
    // Triangle 0 of part 1 uses a vertex of part 0.
    TwoQuads q;
    q.indices[6] = 0;
    const std::string message = partsErrorOf(q.xyz, q.indices, q.parts);
    EXPECT_NE(
        message.find(
            "part 1 triangle 0 corner 0 has vertex index 0, out of range for the part's vertices 4 to 7"),
        std::string::npos)
        << message;
  }
  {
    TwoQuads q;
    q.xyz[3 * 5 + 1] = std::numeric_limits<float>::quiet_NaN();
    const std::string message = partsErrorOf(q.xyz, q.indices, q.parts);
    EXPECT_NE(message.find("part 1 vertex 1 has a non-finite coordinate y"), std::string::npos) << message;
  }
  {
    TwoQuads q;
    q.indices[10] = q.indices[11];
    const std::string message = partsErrorOf(q.xyz, q.indices, q.parts);
    EXPECT_NE(message.find("part 1 triangle 1 repeats vertex index 7"), std::string::npos) << message;
  }
  EXPECT_NE(partsErrorOf(kQuad, {0, 1, 2}, {}).find("no parts given"), std::string::npos);
}

}  // namespace
}  // namespace gpucol
