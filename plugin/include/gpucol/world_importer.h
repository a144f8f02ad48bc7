#pragma once

#include <BulletWorldImporter/btBulletWorldImporter.h>

#include <unordered_map>
#include <unordered_set>
#include <vector>

#include "gpucol/config.h"

struct btCollisionShapeData;

namespace gpucol {

/// Bullet's .bullet file importer (btBulletWorldImporter, libbullet-extras) that brings mesh bodies back as
/// MeshShapes: the form MeshShape::serialize writes (a compound holding a BVH mesh named
/// "gpucol::MeshShape"), and btGImpactMeshShape records (which Debian's importer, built without GImpact,
/// drops). Compounds that hold either get MeshShape children. Each such body keeps the mass and the inertia
/// saved in the file (the stock importer makes a body with a concave shape static and computes a compound's
/// inertia from its box). Everything else is btBulletWorldImporter's, and every object it creates, MeshShapes
/// included, is deleted by deleteAllData().
class WorldImporter : public btBulletWorldImporter {
 public:
  /// Objects go into `world` when it is not null, in the file's order; `config` builds the MeshShapes' trees.
  explicit WorldImporter(btDynamicsWorld* world = nullptr, const Config& config = Config());
  ~WorldImporter() override;

  /// Converts the file's shapes (mesh shapes as MeshShapes), bodies and constraints.
  bool convertAllObjects(bParse::btBulletFile* file) override;
  /// As btBulletWorldImporter's, except that during convertAllObjects the body joins the world only at the
  /// end, once its mass and inertia are the file's.
  btRigidBody* createRigidBody(bool isDynamic, btScalar mass, const btTransform& startTransform,
                               btCollisionShape* shape, const char* bodyName) override;
  /// As btBulletWorldImporter's, joining the world at the end of convertAllObjects, in order with the bodies.
  btCollisionObject* createCollisionObject(const btTransform& startTransform, btCollisionShape* shape,
                                           const char* bodyName) override;
  /// As btBulletWorldImporter's; during convertAllObjects the first call also enters gpucol's shapes in the
  /// importer's shape map (which the stock conversion empties first).
  btCompoundShape* createCompoundShape() override;
  /// Deletes every object the importer created (as btBulletWorldImporter's).
  void deleteAllData() override;

  /// Mesh shapes brought back as MeshShapes by the last convertAllObjects (top level and compound children).
  int meshShapesImported() const { return m_meshShapesImported; }

 private:
  btCollisionShape* gpucolShape(btCollisionShapeData* data);

  Config m_config;
  bool m_deferring = false;
  bool m_shapesPending = false;
  std::vector<btCollisionObject*> m_deferred;
  // Per file record: the shape built for it (null: the stock importer's), filled by gpucolShape.
  std::unordered_map<btCollisionShapeData*, btCollisionShape*> m_converted;
  std::unordered_set<const btCollisionShape*> m_ours;
  int m_meshShapesImported = 0;
};

}  // namespace gpucol
