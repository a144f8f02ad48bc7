#include "scenes/gimpact_peer.h"

#include <BulletCollision/CollisionDispatch/btCollisionDispatcher.h>
#include <BulletCollision/CollisionDispatch/btCollisionObject.h>
#include <BulletCollision/CollisionDispatch/btCollisionObjectWrapper.h>
#include <BulletCollision/CollisionDispatch/btDefaultCollisionConfiguration.h>
#include <BulletCollision/CollisionDispatch/btManifoldResult.h>
#include <BulletCollision/Gimpact/btGImpactCollisionAlgorithm.h>

#include <algorithm>
#include <chrono>

namespace gpucol::scenes {

GImpactMesh::GImpactMesh(const TriangleMesh& mesh)
    : m_vertices(mesh.positions().begin(), mesh.positions().end()),
      m_indices(mesh.indices().begin(), mesh.indices().end()) {
  const auto start = std::chrono::steady_clock::now();
  m_arrays = std::make_unique<btTriangleIndexVertexArray>(
      static_cast<int>(mesh.triangleCount()), m_indices.data(), 3 * static_cast<int>(sizeof(int)),
      static_cast<int>(mesh.vertexCount()), m_vertices.data(), 3 * static_cast<int>(sizeof(btScalar)));
  m_shape = std::make_unique<btGImpactMeshShape>(m_arrays.get());
  m_shape->setMargin(0);
  m_shape->updateBound();  // The first refit builds GImpact's box tree.
  m_buildMilliseconds =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

GImpactMesh::~GImpactMesh() = default;

namespace {

// Records GImpact's contacts with the triangle ids it sets through setShapeIdentifiersA/B before each one.
class RecordingResult : public btManifoldResult {
 public:
  RecordingResult(const btCollisionObjectWrapper* a, const btCollisionObjectWrapper* b) : btManifoldResult(a, b) {}

  void addContactPoint(const btVector3& normalOnBInWorld, const btVector3& pointInWorld, btScalar depth) override {
    GImpactContact c;
    c.triangleA = static_cast<std::uint32_t>(m_index0);
    c.triangleB = static_cast<std::uint32_t>(m_index1);
    c.pointOnB = pointInWorld;
    c.normalOnB = normalOnBInWorld;
    c.depth = depth;
    contacts.push_back(c);
  }

  std::vector<GImpactContact> contacts;
};

}  // namespace

struct GImpactPair::State {
  State(GImpactMesh& a, const btTransform& transformA, GImpactMesh& b, const btTransform& transformB)
      : dispatcher(&configuration),
        wrapA(nullptr, a.shape(), &objectA, objectA.getWorldTransform(), -1, -1),
        wrapB(nullptr, b.shape(), &objectB, objectB.getWorldTransform(), -1, -1) {
    btGImpactCollisionAlgorithm::registerAlgorithm(&dispatcher);
    objectA.setCollisionShape(a.shape());
    objectA.setWorldTransform(transformA);
    objectB.setCollisionShape(b.shape());
    objectB.setWorldTransform(transformB);
  }

  btDefaultCollisionConfiguration configuration;
  btCollisionDispatcher dispatcher;
  btCollisionObject objectA, objectB;
  // The wrappers keep a reference to the objects' world transforms, so they are declared after them.
  btCollisionObjectWrapper wrapA, wrapB;
};

GImpactPair::GImpactPair(GImpactMesh& a, const btTransform& transformA, GImpactMesh& b,
                         const btTransform& transformB)
    : m_state(std::make_unique<State>(a, transformA, b, transformB)) {}

GImpactPair::~GImpactPair() = default;

std::vector<GImpactContact> GImpactPair::collide() {
  btCollisionAlgorithm* algorithm =
      m_state->dispatcher.findAlgorithm(&m_state->wrapA, &m_state->wrapB, nullptr, BT_CONTACT_POINT_ALGORITHMS);
  RecordingResult result(&m_state->wrapA, &m_state->wrapB);
  btDispatcherInfo info;
  algorithm->processCollision(&m_state->wrapA, &m_state->wrapB, info, &result);
  algorithm->~btCollisionAlgorithm();
  m_state->dispatcher.freeCollisionAlgorithm(algorithm);
  return std::move(result.contacts);
}

TriangleMesh centredOnVertexCentroid(const TriangleMesh& mesh) {
  double sum[3] = {0, 0, 0};
  const std::vector<float>& xyz = mesh.positions();
  for (std::size_t i = 0; i < xyz.size(); ++i) sum[i % 3] += xyz[i];
  const double n = static_cast<double>(mesh.vertexCount());
  return mesh.transformed({1, 0, 0, 0, 1, 0, 0, 0, 1}, {-sum[0] / n, -sum[1] / n, -sum[2] / n});
}

PairPose thesisPose(const TriangleMesh& centredMesh) {
  float lo[3] = {1e30f, 1e30f, 1e30f}, hi[3] = {-1e30f, -1e30f, -1e30f};
  const std::vector<float>& xyz = centredMesh.positions();
  for (std::size_t i = 0; i < xyz.size(); ++i) {
    lo[i % 3] = std::min(lo[i % 3], xyz[i]);
    hi[i % 3] = std::max(hi[i % 3], xyz[i]);
  }
  const float largestSide = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]});
  PairPose pose;
  pose.a.setIdentity();
  pose.b.setIdentity();
  pose.b.setOrigin(btVector3(0.3f * largestSide, 0, 0));
  pose.b.setRotation(btQuaternion(btVector3(0, 1, 0), 0.5f));
  return pose;
}

}  // namespace gpucol::scenes
