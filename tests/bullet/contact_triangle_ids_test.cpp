// Contacts say which triangles touched (issue 52): every contact of a MeshShape carries the part and triangle of
// each side that has triangles, in btManifoldPoint's m_partId0/1 and m_index0/1 and in gContactAddedCallback,
// the sides right whichever body is the pair's first, as Bullet's concave algorithms give them.
#include <BulletCollision/Gimpact/btGImpactCollisionAlgorithm.h>
#include <BulletCollision/Gimpact/btGImpactShape.h>
#include <btBulletDynamicsCommon.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <functional>
#include <memory>
#include <vector>

#include "scenes/procedural_meshes.h"
#include "test_world.h"

namespace gpucol {
namespace {

/// One call of gContactAddedCallback.
struct Seen {
  const btCollisionObject* object0;
  int part0, index0;
  const btCollisionObject* object1;
  int part1, index1;
  btVector3 onA, onB;
};

std::vector<Seen>& seen() {
  static std::vector<Seen> calls;
  return calls;
}

bool recordContact(btManifoldPoint& point, const btCollisionObjectWrapper* wrap0, int part0, int index0,
                   const btCollisionObjectWrapper* wrap1, int part1, int index1) {
  seen().push_back({wrap0->getCollisionObject(), part0, index0, wrap1->getCollisionObject(), part1, index1,
                    point.getPositionWorldOnA(), point.getPositionWorldOnB()});
  return false;
}

/// Sets Bullet's contact-added callback for the test's life.
struct CallbackGuard {
  CallbackGuard() {
    seen().clear();
    gContactAddedCallback = recordContact;
  }
  ~CallbackGuard() { gContactAddedCallback = nullptr; }
};

/// Distance from p to the triangle abc (closest point by the triangle's Voronoi regions).
btScalar distanceToTriangle(const btVector3& p, const btVector3& a, const btVector3& b, const btVector3& c) {
  const btVector3 ab = b - a, ac = c - a, ap = p - a;
  const btScalar d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return (p - a).length();
  const btVector3 bp = p - b;
  const btScalar d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return (p - b).length();
  const btScalar vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return (p - (a + ab * (d1 / (d1 - d3)))).length();
  const btVector3 cp = p - c;
  const btScalar d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return (p - c).length();
  const btScalar vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return (p - (a + ac * (d2 / (d2 - d6)))).length();
  const btScalar va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
    return (p - (b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6))))).length();
  const btScalar denom = btScalar(1) / (va + vb + vc);
  return (p - (a + ab * (vb * denom) + ac * (vc * denom))).length();
}

/// Distance between the segments pq and rs (closest points by clamped parameters).
btScalar distanceBetweenSegments(const btVector3& p, const btVector3& q, const btVector3& r, const btVector3& s) {
  const btVector3 d1 = q - p, d2 = s - r, w = p - r;
  const btScalar a = d1.dot(d1), e = d2.dot(d2), f = d2.dot(w);
  btScalar t1 = 0, t2 = 0;
  if (a <= SIMD_EPSILON && e <= SIMD_EPSILON) return w.length();
  if (a <= SIMD_EPSILON) {
    t2 = btClamped(f / e, btScalar(0), btScalar(1));
  } else {
    const btScalar c = d1.dot(w);
    if (e <= SIMD_EPSILON) {
      t1 = btClamped(-c / a, btScalar(0), btScalar(1));
    } else {
      const btScalar b = d1.dot(d2), denom = a * e - b * b;
      t1 = denom > 0 ? btClamped((b * f - c * e) / denom, btScalar(0), btScalar(1)) : 0;
      t2 = (b * t1 + f) / e;
      if (t2 < 0) t2 = 0, t1 = btClamped(-c / a, btScalar(0), btScalar(1));
      else if (t2 > 1) t2 = 1, t1 = btClamped((b - c) / a, btScalar(0), btScalar(1));
    }
  }
  return ((p + d1 * t1) - (r + d2 * t2)).length();
}

/// True when the segment pq crosses the triangle abc (Möller–Trumbore, the ends included).
bool segmentCrossesTriangle(const btVector3& p, const btVector3& q, const btVector3& a, const btVector3& b,
                            const btVector3& c) {
  const btVector3 dir = q - p, e1 = b - a, e2 = c - a, h = dir.cross(e2);
  const btScalar det = e1.dot(h);
  if (btFabs(det) < SIMD_EPSILON) return false;
  const btVector3 s = p - a;
  const btScalar u = s.dot(h) / det;
  const btVector3 qv = s.cross(e1);
  const btScalar v = dir.dot(qv) / det, t = e2.dot(qv) / det;
  return u >= 0 && v >= 0 && u + v <= 1 && t >= 0 && t <= 1;
}

/// Distance between two triangles: 0 where an edge of one crosses the other, else the least of the corners'
/// distances to the other triangle and the edges' distances to each other.
btScalar distanceBetweenTriangles(const std::array<btVector3, 3>& t0, const std::array<btVector3, 3>& t1) {
  btScalar best = BT_LARGE_FLOAT;
  for (int i = 0; i < 3; ++i) {
    const int j = (i + 1) % 3;
    if (segmentCrossesTriangle(t0[i], t0[j], t1[0], t1[1], t1[2]) ||
        segmentCrossesTriangle(t1[i], t1[j], t0[0], t0[1], t0[2]))
      return 0;
    best = btMin(best, distanceToTriangle(t0[i], t1[0], t1[1], t1[2]));
    best = btMin(best, distanceToTriangle(t1[i], t0[0], t0[1], t0[2]));
    for (int k = 0; k < 3; ++k) best = btMin(best, distanceBetweenSegments(t0[i], t0[j], t1[k], t1[(k + 1) % 3]));
  }
  return best;
}

/// The world corners of triangle (part, index) of `object`'s shape: a MeshShape (its parts), or the mesh
/// interface of a btBvhTriangleMeshShape or a btGImpactMeshShape. False for an id that names no triangle.
bool worldTriangle(const btCollisionObject* object, int part, int index, std::array<btVector3, 3>& corners) {
  const btCollisionShape* shape = object->getCollisionShape();
  const btTransform& t = object->getWorldTransform();
  if (MeshShape::isMeshShape(shape)) {
    const TriangleMesh& mesh = static_cast<const MeshShape*>(shape)->mesh();
    if (part < 0 || std::size_t(part) >= mesh.parts().size() || index < 0 ||
        std::uint32_t(index) >= mesh.parts()[std::size_t(part)].triangleCount)
      return false;
    const std::size_t triangle = mesh.parts()[std::size_t(part)].firstTriangle + std::size_t(index);
    for (int i = 0; i < 3; ++i) {
      const float* p = mesh.positions().data() + 3 * std::size_t(mesh.indices()[3 * triangle + i]);
      corners[i] = t(btVector3(p[0], p[1], p[2]) * shape->getLocalScaling());
    }
    return true;
  }
  // A BVH mesh scales by its mesh interface's scaling, a GImpact mesh by its parts'.
  const btStridingMeshInterface* meshInterface = nullptr;
  btVector3 scaling = shape->getLocalScaling();
  if (shape->getShapeType() == TRIANGLE_MESH_SHAPE_PROXYTYPE) {
    meshInterface = static_cast<const btBvhTriangleMeshShape*>(shape)->getMeshInterface();
  } else if (shape->getShapeType() == GIMPACT_SHAPE_PROXYTYPE) {
    const auto* gimpact = static_cast<const btGImpactMeshShape*>(shape);
    meshInterface = gimpact->getMeshInterface();
    if (part < 0 || part >= gimpact->getMeshPartCount()) return false;
    scaling = gimpact->getMeshPart(part)->getLocalScaling();
  } else {
    return false;
  }
  if (part < 0 || part >= meshInterface->getNumSubParts()) return false;
  const unsigned char *vertices, *indices;
  int vertexCount, faceCount, vertexStride, indexStride;
  PHY_ScalarType vertexType, indexType;
  meshInterface->getLockedReadOnlyVertexIndexBase(&vertices, vertexCount, vertexType, vertexStride, &indices,
                                                  indexStride, faceCount, indexType, part);
  const bool valid = index >= 0 && index < faceCount && vertexType == PHY_FLOAT && indexType == PHY_INTEGER;
  if (valid) {
    const int* face = reinterpret_cast<const int*>(indices + std::size_t(index) * indexStride);
    for (int i = 0; i < 3; ++i) {
      const float* p = reinterpret_cast<const float*>(vertices + std::size_t(face[i]) * vertexStride);
      corners[i] = t(btVector3(p[0], p[1], p[2]) * scaling);
    }
  }
  meshInterface->unLockReadOnlyVertexBase(part);
  return valid;
}

/// Every contact seen names, on each side with triangles, a triangle of that body: where both sides have
/// triangles, two that touch or cross (within `tolerance`: a contact comes from an intersecting pair); where one
/// side is a plane, a triangle within `tolerance` of the mesh's point, and -1 for the plane. Returns the contacts
/// checked.
std::size_t expectTouchingTriangles(btScalar tolerance,
                                    const std::function<bool(const btCollisionObject*)>& hasTriangles) {
  for (const Seen& s : seen()) {
    const btCollisionObject* objects[2] = {s.object0, s.object1};
    const int parts[2] = {s.part0, s.part1}, indices[2] = {s.index0, s.index1};
    const btVector3 points[2] = {s.onA, s.onB};
    std::array<btVector3, 3> corners[2];
    bool named[2] = {false, false};
    for (int side = 0; side < 2; ++side) {
      if (!hasTriangles(objects[side])) {
        EXPECT_EQ(indices[side], -1) << "side " << side;
        EXPECT_EQ(parts[side], -1) << "side " << side;
        continue;
      }
      named[side] = worldTriangle(objects[side], parts[side], indices[side], corners[side]);
      EXPECT_TRUE(named[side]) << "side " << side << ": part " << parts[side] << ", index " << indices[side]
                               << " names no triangle";
    }
    if (named[0] && named[1]) {
      EXPECT_LE(distanceBetweenTriangles(corners[0], corners[1]), tolerance)
          << "triangles " << parts[0] << "/" << indices[0] << " and " << parts[1] << "/" << indices[1];
    } else {
      for (int side = 0; side < 2; ++side) {
        if (!named[side]) continue;
        EXPECT_LE(distanceToTriangle(points[side], corners[side][0], corners[side][1], corners[side][2]), tolerance)
            << "side " << side << ": triangle " << indices[side];
      }
    }
  }
  return seen().size();
}

std::shared_ptr<MeshShape> meshBox(float half, int subdivisions) {
  return std::make_shared<MeshShape>(
      std::make_shared<const TriangleMesh>(scenes::makeBox(half, half, half, subdivisions)));
}

btTransform at(const btVector3& origin, btScalar angle = 0) {
  return btTransform(btQuaternion(btVector3(0, 1, 0), angle), origin);
}

bool isMesh(const btCollisionObject* o) { return MeshShape::isMeshShape(o->getCollisionShape()); }

TEST(ContactTriangleIds, MeshOnMeshInBothOrdersNameTheTouchingTriangles) {
  std::vector<bool> boxIsObject0;
  for (const bool groundFirst : {true, false}) {
    CallbackGuard guard;
    test::TestWorld world(test::DispatchKind::Gpucol);
    btRigidBody *ground = nullptr, *box = nullptr;
    const auto addGround = [&] { ground = world.add(meshBox(2.0f, 4), 0, at(btVector3(0, -2, 0))); };
    const auto addBox = [&] { box = world.add(meshBox(0.5f, 2), 1, at(btVector3(0.3f, 0.48f, 0.1f), 0.3f)); };
    if (groundFirst) addGround(), addBox(); else addBox(), addGround();
    box->setCollisionFlags(box->getCollisionFlags() | btCollisionObject::CF_CUSTOM_MATERIAL_CALLBACK);
    world.step(30);
    const std::size_t checked = expectTouchingTriangles(0.02f, isMesh);
    EXPECT_GT(checked, 4u) << (groundFirst ? "ground first" : "box first");
    ASSERT_FALSE(seen().empty());
    boxIsObject0.push_back(seen().front().object0 == box);
  }
  // The two orders of adding the bodies put the box on either side of the pair.
  EXPECT_NE(boxIsObject0[0], boxIsObject0[1]);
}

/// Two 4 x 4 m quads side by side at y = 0, each a part of two triangles, as Bullet's mesh interface.
std::shared_ptr<btTriangleIndexVertexArray> twoPartGround() {
  static const float vertices[2][12] = {{-4, 0, -2, 0, 0, -2, 0, 0, 2, -4, 0, 2},
                                        {0, 0, -2, 4, 0, -2, 4, 0, 2, 0, 0, 2}};
  static const int faces[6] = {0, 2, 1, 0, 3, 2};
  auto meshInterface = std::make_shared<btTriangleIndexVertexArray>();
  for (int part = 0; part < 2; ++part) {
    btIndexedMesh m;
    m.m_numTriangles = 2;
    m.m_triangleIndexBase = reinterpret_cast<const unsigned char*>(faces);
    m.m_triangleIndexStride = 3 * sizeof(int);
    m.m_numVertices = 4;
    m.m_vertexBase = reinterpret_cast<const unsigned char*>(vertices[part]);
    m.m_vertexStride = 3 * sizeof(float);
    meshInterface->addIndexedMesh(m, PHY_INTEGER);
  }
  return meshInterface;
}

TEST(ContactTriangleIds, MeshOnABvhOfTwoPartsNamesThePartAndTriangle) {
  // A ground of two parts: a box resting across the seam touches triangles of both parts.
  const auto meshInterface = twoPartGround();
  CallbackGuard guard;
  test::TestWorld world(test::DispatchKind::Gpucol);
  world.add(std::make_shared<btBvhTriangleMeshShape>(meshInterface.get(), true), 0, at(btVector3(0, 0, 0)));
  btRigidBody* box = world.add(meshBox(0.5f, 2), 1, at(btVector3(0, 0.49f, 0.3f), 0.2f));
  box->setCollisionFlags(box->getCollisionFlags() | btCollisionObject::CF_CUSTOM_MATERIAL_CALLBACK);
  world.step(30);
  const std::size_t checked = expectTouchingTriangles(0.02f, [](const btCollisionObject*) { return true; });
  EXPECT_GT(checked, 4u);
  bool parts[2] = {false, false};
  for (const Seen& s : seen()) {
    const int groundPart = isMesh(s.object0) ? s.part1 : s.part0;
    if (groundPart == 0 || groundPart == 1) parts[groundPart] = true;
  }
  EXPECT_TRUE(parts[0] && parts[1]) << "the box across the seam touches both parts";
}

TEST(ContactTriangleIds, GImpactMeshesNameTheirPartAndTriangleAsGImpactDoes) {
  // Under gpucol::CollisionDispatcher (GImpact registered after it, as a world moved over keeps it), a
  // GImpact box and a MeshShape box made of two parts rest across the seam of a two-part GImpact ground: each
  // contact names the part and the triangle within it on both sides, and the two triangles touch; so do
  // GImpact's own contacts.
  const auto ground = twoPartGround();
  const TriangleMesh boxMesh = scenes::makeBox(0.5f, 0.5f, 0.5f, 2);
  std::vector<float> boxXyz(boxMesh.positions().begin(), boxMesh.positions().end());
  std::vector<int> boxFaces(boxMesh.indices().begin(), boxMesh.indices().end());
  btTriangleIndexVertexArray boxArrays(int(boxMesh.triangleCount()), boxFaces.data(), 3 * sizeof(int),
                                       int(boxMesh.vertexCount()), boxXyz.data(), 3 * sizeof(float));
  // The MeshShape box: the same box in two parts, its first triangle alone and the rest (each part with its
  // own copy of the vertices), so that its bottom's triangles are named from 1 triangle into the mesh.
  std::vector<float> twoXyz(boxXyz);
  twoXyz.insert(twoXyz.end(), boxXyz.begin(), boxXyz.end());
  std::vector<std::uint32_t> twoIndices(boxMesh.indices().begin(), boxMesh.indices().end());
  const std::uint32_t rest = std::uint32_t(boxMesh.triangleCount() - 1),
                      verts = std::uint32_t(boxMesh.vertexCount());
  for (std::size_t i = 3; i < twoIndices.size(); ++i) twoIndices[i] += verts;
  const std::vector<MeshPart> parts = {{0, 1, 0, verts}, {1, rest, verts, verts}};

  // GImpact's own algorithm first, alone with the GImpact box: its ids read the same way (part, index in
  // part).
  for (const bool gpucol : {false, true}) {
    SCOPED_TRACE(gpucol ? "gpucol::CollisionDispatcher" : "btCollisionDispatcher and GImpact");
    CallbackGuard guard;
    test::TestWorld world(gpucol ? test::DispatchKind::Gpucol : test::DispatchKind::Stock);
    btGImpactCollisionAlgorithm::registerAlgorithm(&world.dispatcher());
    auto groundShape = std::make_shared<btGImpactMeshShape>(ground.get());
    groundShape->setMargin(0.005f);
    groundShape->updateBound();
    world.add(groundShape, 0, at(btVector3(0, 0, 0)));
    auto boxShape = std::make_shared<btGImpactMeshShape>(&boxArrays);
    boxShape->setMargin(0.005f);
    boxShape->updateBound();
    std::vector<btRigidBody*> boxes = {world.add(boxShape, 1, at(btVector3(0, 0.52f, 0.8f), 0.2f))};
    if (gpucol) {
      boxes.push_back(world.add(std::make_shared<MeshShape>(std::make_shared<const TriangleMesh>(
                                    TriangleMesh::fromParts(twoXyz, twoIndices, parts))),
                                1, at(btVector3(0.1f, 0.52f, -0.9f), -0.3f)));
    }
    for (btRigidBody* b : boxes)
      b->setCollisionFlags(b->getCollisionFlags() | btCollisionObject::CF_CUSTOM_MATERIAL_CALLBACK);
    world.step(30);
    EXPECT_GT(expectTouchingTriangles(0.03f, [](const btCollisionObject*) { return true; }), 4u);
    bool groundParts[2] = {false, false}, meshParts[2] = {false, false};
    for (const Seen& s : seen()) {
      const bool groundFirst = s.object0->getCollisionShape() == groundShape.get();
      const int groundPart = groundFirst ? s.part0 : s.part1, otherPart = groundFirst ? s.part1 : s.part0;
      const btCollisionObject* other = groundFirst ? s.object1 : s.object0;
      if (groundPart == 0 || groundPart == 1) groundParts[groundPart] = true;
      if (MeshShape::isMeshShape(other->getCollisionShape()) && (otherPart == 0 || otherPart == 1))
        meshParts[otherPart] = true;
    }
    EXPECT_TRUE(groundParts[0] && groundParts[1])
        << "the boxes across the seam touch both parts of the ground";
    if (!gpucol) continue;
    EXPECT_TRUE(meshParts[1]) << "the MeshShape box's bottom is in its second part";
    const auto& stats = static_cast<CollisionDispatcher&>(world.dispatcher()).lastStepStats();
    EXPECT_EQ(stats.gimpactPairs, 2u) << "both boxes against the GImpact ground, in the batch";
  }
}

TEST(ContactTriangleIds, MeshOnAPlaneNamesTheMeshTriangleAndNoPlaneTriangle) {
  CallbackGuard guard;
  test::TestWorld world(test::DispatchKind::Gpucol);
  world.add(std::make_shared<btStaticPlaneShape>(btVector3(0, 1, 0), 0), 0, at(btVector3(0, 0, 0)));
  btRigidBody* box = world.add(meshBox(0.5f, 2), 1, at(btVector3(0, 0.49f, 0), 0.4f));
  box->setCollisionFlags(box->getCollisionFlags() | btCollisionObject::CF_CUSTOM_MATERIAL_CALLBACK);
  world.step(30);
  EXPECT_GT(expectTouchingTriangles(0.02f, isMesh), 4u);
}

}  // namespace
}  // namespace gpucol
