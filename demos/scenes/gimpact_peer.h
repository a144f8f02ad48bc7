#pragma once

#include <BulletCollision/CollisionShapes/btTriangleIndexVertexArray.h>
#include <BulletCollision/Gimpact/btGImpactShape.h>
#include <LinearMath/btTransform.h>

#include <cstdint>
#include <memory>
#include <vector>

#include <gpucol/triangle_mesh.h>

namespace gpucol::scenes {

/// A mesh as Bullet's GImpact sees it: a btGImpactMeshShape over the same vertex and index arrays, its
/// box tree built. The peer that benchmarks and regression tests measure gpucol against.
class GImpactMesh {
 public:
  /// Copies the arrays, builds the shape (margin 0, so its triangles are the mesh's own) and its tree.
  explicit GImpactMesh(const TriangleMesh& mesh);
  ~GImpactMesh();
  GImpactMesh(const GImpactMesh&) = delete;
  GImpactMesh& operator=(const GImpactMesh&) = delete;

  /// The shape.
  btGImpactMeshShape* shape() { return m_shape.get(); }
  /// Milliseconds that building the shape and its tree (updateBound) took.
  double buildMilliseconds() const { return m_buildMilliseconds; }

 private:
  std::vector<btScalar> m_vertices;
  std::vector<int> m_indices;
  std::unique_ptr<btTriangleIndexVertexArray> m_arrays;
  std::unique_ptr<btGImpactMeshShape> m_shape;
  double m_buildMilliseconds = 0;
};

/// One contact GImpact reported, with the triangles that made it (index into each mesh's triangle list).
struct GImpactContact {
  std::uint32_t triangleA = 0;  ///< Triangle of mesh A.
  std::uint32_t triangleB = 0;  ///< Triangle of mesh B.
  btVector3 pointOnB;           ///< World point on B.
  btVector3 normalOnB;          ///< World normal on B pointing towards A.
  btScalar depth = 0;           ///< Negative when penetrating.
};

/// Two GImpact meshes at fixed poses with a dispatcher of their own, so that repeated collide() calls time
/// only btGImpactCollisionAlgorithm's work.
class GImpactPair {
 public:
  /// Sets up the collision objects and a dispatcher with GImpact's algorithm registered.
  GImpactPair(GImpactMesh& a, const btTransform& transformA, GImpactMesh& b, const btTransform& transformB);
  ~GImpactPair();
  GImpactPair(const GImpactPair&) = delete;
  GImpactPair& operator=(const GImpactPair&) = delete;

  /// Runs btGImpactCollisionAlgorithm once and returns every contact it reports.
  std::vector<GImpactContact> collide();

 private:
  struct State;
  std::unique_ptr<State> m_state;
};

/// The thesis's test scene (§6): both copies centred on the mesh's vertex centroid, the second moved along x
/// by 0.3 × the largest side of the mesh's bounding box and turned 0.5 rad about y.
struct PairPose {
  btTransform a;  ///< Transform of the first copy.
  btTransform b;  ///< Transform of the second copy.
};

/// `mesh` moved so that the mean of its vertices is the origin.
TriangleMesh centredOnVertexCentroid(const TriangleMesh& mesh);

/// The thesis pose for two copies of a mesh that is already centred on its vertex centroid.
PairPose thesisPose(const TriangleMesh& centredMesh);

}  // namespace gpucol::scenes
