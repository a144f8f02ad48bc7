// Meshes from Bullet's mesh interfaces and shapes (issue 54): TriangleMesh::fromStridingMesh reads every part
// of btTriangleMesh and btTriangleIndexVertexArray (8/16/32-bit indices, float and double vertices), keeps
// each triangle's part, and names the part and element of bad input; MeshShape::fromGImpact and fromBvh keep
// the triangles, scaling and margin.
#include <BulletCollision/CollisionShapes/btTriangleCallback.h>
#include <BulletCollision/Gimpact/btGImpactShape.h>
#include <btBulletDynamicsCommon.h>
#include <gpucol/gpucol.h>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "scenes/procedural_meshes.h"

namespace gpucol {
namespace {

/// The message of the MeshError that `f` throws ("" when it throws none).
template <typename F>
std::string errorOf(F f) {
  try {
    f();
  } catch (const MeshError& e) {
    return e.what();
  }
  return "";
}

/// Every triangle of `mesh` by (part, index within the part), its corners in order.
std::map<std::pair<int, int>, std::vector<float>> trianglesOf(const TriangleMesh& mesh) {
  std::map<std::pair<int, int>, std::vector<float>> out;
  for (std::uint32_t t = 0; t < mesh.triangleCount(); ++t) {
    const PartTriangle id = mesh.partTriangle(t);
    std::vector<float>& corners = out[{id.part, id.index}];
    for (int k = 0; k < 3; ++k) {
      const float* p = &mesh.positions()[3 * std::size_t(mesh.indices()[3 * t + k])];
      corners.insert(corners.end(), p, p + 3);
    }
  }
  return out;
}

/// Every triangle a Bullet interface gives, by (part, index), as Bullet itself reads them (unscaled).
std::map<std::pair<int, int>, std::vector<float>> trianglesOf(const btStridingMeshInterface& mesh) {
  struct Collector : btInternalTriangleIndexCallback {
    void internalProcessTriangleIndex(btVector3* triangle, int part, int index) override {
      std::vector<float>& corners = out[{part, index}];
      for (int k = 0; k < 3; ++k) {
        for (int axis = 0; axis < 3; ++axis) corners.push_back(float(triangle[k][axis]));
      }
    }
    std::map<std::pair<int, int>, std::vector<float>> out;
  } collector;
  const btVector3 big(1e30f, 1e30f, 1e30f);
  mesh.InternalProcessAllTriangles(&collector, -big, big);
  return collector.out;
}

TEST(FromStridingMesh, ReadsBtTriangleMeshWith32And16BitIndices) {
  const TriangleMesh box = scenes::makeBox(0.5f, 1, 2, 2);
  for (const bool use32 : {true, false}) {
    for (const bool use4 : {true, false}) {
      SCOPED_TRACE(std::to_string(use32) + " " + std::to_string(use4));
      btTriangleMesh bullet(use32, use4);
      for (std::size_t v = 0; v < box.vertexCount(); ++v) {
        bullet.findOrAddVertex(
            btVector3(box.positions()[3 * v], box.positions()[3 * v + 1], box.positions()[3 * v + 2]), false);
      }
      for (std::size_t t = 0; t < box.triangleCount(); ++t) {
        bullet.addTriangleIndices(int(box.indices()[3 * t]), int(box.indices()[3 * t + 1]),
                                  int(box.indices()[3 * t + 2]));
      }
      const TriangleMesh mesh = TriangleMesh::fromStridingMesh(bullet);
      EXPECT_EQ(mesh.positions(), box.positions());
      EXPECT_EQ(mesh.indices(), box.indices());
      ASSERT_EQ(mesh.parts().size(), 1u);
      EXPECT_EQ(trianglesOf(mesh), trianglesOf(bullet));
    }
  }
}

/// Two parts of Bullet arrays: part 0 a box with 16-bit indices and double vertices, part 1 a torus with
/// 32-bit indices and float vertices (padded to 4 floats), part 2 a box with 8-bit indices.
struct TwoKindsOfArrays {
  TwoKindsOfArrays() {
    const TriangleMesh box = scenes::makeBox(0.5f, 0.5f, 0.5f, 1), torus = scenes::makeTorus(1, 0.25f, 12, 6);
    for (float x : box.positions()) doubles.push_back(double(x) + 3);
    for (std::uint32_t i : box.indices()) shorts.push_back(static_cast<unsigned short>(i));
    for (std::size_t v = 0; v < torus.vertexCount(); ++v) {
      for (int k = 0; k < 3; ++k) floats.push_back(torus.positions()[3 * v + k]);
      floats.push_back(-1);
    }
    for (std::uint32_t i : torus.indices()) ints.push_back(int(i));
    for (float x : box.positions()) floats2.push_back(x - 3);
    for (std::uint32_t i : box.indices()) bytes.push_back(static_cast<unsigned char>(i));
    add(box.triangleCount(), shorts.data(), 3 * sizeof(unsigned short), PHY_SHORT, box.vertexCount(),
        doubles.data(), 3 * sizeof(double), PHY_DOUBLE);
    add(torus.triangleCount(), ints.data(), 3 * sizeof(int), PHY_INTEGER, torus.vertexCount(), floats.data(),
        4 * sizeof(float), PHY_FLOAT);
    add(box.triangleCount(), bytes.data(), 3, PHY_UCHAR, box.vertexCount(), floats2.data(), 3 * sizeof(float),
        PHY_FLOAT);
  }
  /// Appends one part to `arrays`.
  void add(std::size_t triangles, const void* indices, int indexStride, PHY_ScalarType indexType,
           std::size_t vertices, const void* positions, int vertexStride, PHY_ScalarType vertexType) {
    btIndexedMesh part;
    part.m_numTriangles = int(triangles);
    part.m_triangleIndexBase = static_cast<const unsigned char*>(indices);
    part.m_triangleIndexStride = indexStride;
    part.m_numVertices = int(vertices);
    part.m_vertexBase = static_cast<const unsigned char*>(positions);
    part.m_vertexStride = vertexStride;
    part.m_vertexType = vertexType;
    arrays.addIndexedMesh(part, indexType);
  }
  std::vector<double> doubles;
  std::vector<unsigned short> shorts;
  std::vector<float> floats, floats2;
  std::vector<int> ints;
  std::vector<unsigned char> bytes;
  btTriangleIndexVertexArray arrays;
};

TEST(FromStridingMesh, KeepsEveryPartAndNamesTrianglesAsBulletDoes) {
  TwoKindsOfArrays source;
  const TriangleMesh mesh = TriangleMesh::fromStridingMesh(source.arrays, "three parts");
  ASSERT_EQ(mesh.parts().size(), 3u);
  EXPECT_EQ(mesh.parts()[1].firstTriangle, 12u);
  EXPECT_EQ(mesh.parts()[1].firstVertex, 8u);
  EXPECT_EQ(mesh.triangleCount(), 12u + 144u + 12u);
  EXPECT_EQ(trianglesOf(mesh), trianglesOf(source.arrays));
  const PartTriangle last = mesh.partTriangle(std::uint32_t(mesh.triangleCount() - 1));
  EXPECT_EQ(last.part, 2);
  EXPECT_EQ(last.index, 11);
  // A MeshShape's processAllTriangles names them the same way.
  MeshShape shape(std::make_shared<const TriangleMesh>(mesh));
  struct Ids : btTriangleCallback {
    void processTriangle(btVector3*, int part, int index) override { seen.insert({part, index}); }
    std::set<std::pair<int, int>> seen;
  } ids;
  shape.processAllTriangles(&ids, btVector3(-10, -10, -10), btVector3(10, 10, 10));
  std::set<std::pair<int, int>> expected;
  for (const auto& entry : trianglesOf(source.arrays)) expected.insert(entry.first);
  EXPECT_EQ(ids.seen, expected);
}

TEST(FromStridingMesh, BadInputNamesThePartAndTheElement) {
  {
    TwoKindsOfArrays source;
    source.ints[3 * 5 + 1] = int(source.floats.size() / 4);  // part 1, triangle 5, corner 1
    const std::string message = errorOf([&] { TriangleMesh::fromStridingMesh(source.arrays, "arrays"); });
    EXPECT_NE(message.find("part 1 triangle 5 corner 1 has vertex index 72"), std::string::npos) << message;
  }
  {
    TwoKindsOfArrays source;
    source.ints[3 * 7 + 2] = -4;
    const std::string message = errorOf([&] { TriangleMesh::fromStridingMesh(source.arrays); });
    EXPECT_NE(message.find("part 1 triangle 7 corner 2 has vertex index -4"), std::string::npos) << message;
  }
  {
    TwoKindsOfArrays source;
    source.shorts[3 * 2] = source.shorts[3 * 2 + 1];
    const std::string message = errorOf([&] { TriangleMesh::fromStridingMesh(source.arrays); });
    EXPECT_NE(message.find("part 0 triangle 2 repeats vertex index"), std::string::npos) << message;
  }
  {
    TwoKindsOfArrays source;
    source.doubles[3 * 6 + 2] = std::numeric_limits<double>::quiet_NaN();
    const std::string message = errorOf([&] { TriangleMesh::fromStridingMesh(source.arrays); });
    EXPECT_NE(message.find("part 0 vertex 6 has coordinate z = nan, not finite"), std::string::npos)
        << message;
  }
  {
    TwoKindsOfArrays source;
    source.doubles[3 * 4] = 1e300;
    const std::string message = errorOf([&] { TriangleMesh::fromStridingMesh(source.arrays); });
    EXPECT_NE(message.find("part 0 vertex 4 has coordinate x = 1e+300, too large for float"),
              std::string::npos)
        << message;
  }
  {
    TwoKindsOfArrays source;
    source.floats[4 * 3 + 1] = std::numeric_limits<float>::infinity();
    const std::string message = errorOf([&] { TriangleMesh::fromStridingMesh(source.arrays); });
    EXPECT_NE(message.find("part 1 vertex 3 has coordinate y = inf"), std::string::npos) << message;
  }
  {
    TwoKindsOfArrays source;
    source.arrays.getIndexedMeshArray()[2].m_indexType = PHY_FIXEDPOINT88;
    const std::string message = errorOf([&] { TriangleMesh::fromStridingMesh(source.arrays); });
    EXPECT_NE(message.find("part 2 has indices of PHY_FIXEDPOINT88"), std::string::npos) << message;
  }
  {
    TwoKindsOfArrays source;
    source.arrays.getIndexedMeshArray()[1].m_vertexType = PHY_SHORT;
    const std::string message = errorOf([&] { TriangleMesh::fromStridingMesh(source.arrays); });
    EXPECT_NE(message.find("part 1 has vertices of PHY_SHORT"), std::string::npos) << message;
  }
  {
    btTriangleIndexVertexArray empty;
    EXPECT_NE(errorOf([&] { TriangleMesh::fromStridingMesh(empty); }).find("no parts"), std::string::npos);
  }
}

TEST(MeshShapeFromBullet, GImpactKeepsTrianglesScalingAndTheTrianglesMargin) {
  TwoKindsOfArrays source;
  btGImpactMeshShape gimpact(&source.arrays);
  gimpact.setLocalScaling(btVector3(2, 0.5f, -1));
  gimpact.setMargin(0.03f);
  gimpact.updateBound();
  const std::unique_ptr<MeshShape> shape = MeshShape::fromGImpact(gimpact);
  EXPECT_EQ(trianglesOf(shape->mesh()), trianglesOf(source.arrays));
  EXPECT_EQ(shape->getLocalScaling(), btVector3(2, 0.5f, -1));
  EXPECT_FLOAT_EQ(shape->getMargin(), 0.03f);
  // The same world box as GImpact's own (GImpact's is widened by its margin, as MeshShape's).
  btVector3 lo, hi, gLo, gHi;
  shape->getAabb(btTransform::getIdentity(), lo, hi);
  gimpact.getAabb(btTransform::getIdentity(), gLo, gHi);
  EXPECT_LT((lo - gLo).length(), 1e-4f);
  EXPECT_LT((hi - gHi).length(), 1e-4f);

  // A GImpact mesh left at its defaults collides with its parts' margin (0.01), not getMargin()'s 0.
  btGImpactMeshShape plain(&source.arrays);
  EXPECT_FLOAT_EQ(MeshShape::fromGImpact(plain)->getMargin(), plain.getMeshPart(0)->getMargin());

  // Parts scaled differently: the scaling goes into the vertices.
  gimpact.getMeshPart(1)->setLocalScaling(btVector3(3, 3, 3));
  const std::unique_ptr<MeshShape> baked = MeshShape::fromGImpact(gimpact);
  EXPECT_EQ(baked->getLocalScaling(), btVector3(1, 1, 1));
  const auto ours = trianglesOf(baked->mesh());
  for (const auto& [id, corners] : trianglesOf(source.arrays)) {
    const btVector3 s = gimpact.getMeshPart(id.first)->getLocalScaling();
    const std::vector<float>& got = ours.at(id);
    // A mirroring scale swaps the last two corners to keep the winding outward.
    const bool mirrored = s.x() * s.y() * s.z() < 0;
    for (int k = 0; k < 3; ++k) {
      const int from = mirrored && k > 0 ? 3 - k : k;
      for (int axis = 0; axis < 3; ++axis)
        EXPECT_FLOAT_EQ(got[3 * k + axis], corners[3 * from + axis] * s[axis]);
    }
  }
}

TEST(MeshShapeFromBullet, BvhKeepsTrianglesScalingAndMargin) {
  TwoKindsOfArrays source;
  const auto unscaled = trianglesOf(source.arrays);
  btBvhTriangleMeshShape bvh(&source.arrays, true);
  // A BVH's scaling is its mesh interface's: the triangles the interface gives are scaled from here on.
  bvh.setLocalScaling(btVector3(1.5f, 2, 1));
  bvh.setMargin(0.02f);
  const std::unique_ptr<MeshShape> shape = MeshShape::fromBvh(bvh);
  EXPECT_EQ(trianglesOf(shape->mesh()), unscaled);
  EXPECT_EQ(shape->getLocalScaling(), btVector3(1.5f, 2, 1));
  EXPECT_FLOAT_EQ(shape->getMargin(), 0.02f);
}

}  // namespace
}  // namespace gpucol
