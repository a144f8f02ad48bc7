#include "gpucol/world_importer.h"

#include <BulletCollision/CollisionShapes/btBvhTriangleMeshShape.h>
#include <BulletCollision/CollisionShapes/btCompoundShape.h>
#include <BulletCollision/CollisionShapes/btTriangleIndexVertexArray.h>
#include <BulletCollision/Gimpact/btGImpactShape.h>
#include <BulletDynamics/Dynamics/btDynamicsWorld.h>
#include <BulletDynamics/Dynamics/btRigidBody.h>
#include <BulletFileLoader/btBulletFile.h>

#include <cstring>
#include <exception>
#include <memory>
#include <string>
#include <utility>

#include "bullet/warn_once.h"
#include "gpucol/mesh_shape.h"

namespace gpucol {
namespace {

// A shape type no importer converts: a record is given it while the stock importer runs, so that it neither
// builds what gpucol has built (a BVH, for nothing) nor overwrites gpucol's shape in its map.
constexpr int kHiddenShapeType = MeshShape::kMeshShapeType;

// The BVH mesh MeshShape::serialize wrote, when `data` is that form: a compound with one child at the
// identity, a triangle mesh named "gpucol::MeshShape".
btTriangleMeshShapeData* savedMeshShape(btCollisionShapeData* data) {
  if (data == nullptr || data->m_shapeType != COMPOUND_SHAPE_PROXYTYPE) return nullptr;
  const auto* compound = reinterpret_cast<btCompoundShapeData*>(data);
  if (compound->m_numChildShapes != 1 || compound->m_childShapePtr == nullptr) return nullptr;
  const btCompoundShapeChildData& child = compound->m_childShapePtr[0];
  btTransform transform;
  transform.deSerializeFloat(child.m_transform);
  btCollisionShapeData* childData = child.m_childShape;
  if (childData == nullptr || childData->m_name == nullptr || !(transform == btTransform::getIdentity()))
    return nullptr;
  const bool hidden = childData->m_shapeType == kHiddenShapeType;
  if ((childData->m_shapeType != TRIANGLE_MESH_SHAPE_PROXYTYPE && !hidden) ||
      std::strcmp(childData->m_name, MeshShape::kSerializedName) != 0) {
    return nullptr;
  }
  return reinterpret_cast<btTriangleMeshShapeData*>(childData);
}

bool isGImpactMesh(btCollisionShapeData* data) {
  return data != nullptr && data->m_shapeType == GIMPACT_SHAPE_PROXYTYPE &&
         reinterpret_cast<btGImpactMeshShapeData*>(data)->m_gimpactSubType == CONST_GIMPACT_TRIMESH_SHAPE;
}

btScalar inverseOf(btScalar x) {
  return x != 0 ? btScalar(1) / x : btScalar(0);
}

}  // namespace

WorldImporter::WorldImporter(btDynamicsWorld* world, const Config& config)
    : btBulletWorldImporter(world), m_config(config) {}

WorldImporter::~WorldImporter() = default;

btCollisionShape* WorldImporter::gpucolShape(btCollisionShapeData* data) {
  const auto found = m_converted.find(data);
  if (found != m_converted.end()) return found->second;
  btCollisionShape* shape = nullptr;
  try {
    btStridingMeshInterfaceData* meshData = nullptr;
    btVector3 scaling(1, 1, 1);
    btScalar margin = 0;
    if (btTriangleMeshShapeData* saved = savedMeshShape(data)) {
      // The scaling is the mesh interface's (MeshShape::serialize).
      meshData = &saved->m_meshInterface;
      scaling.deSerializeFloat(saved->m_meshInterface.m_scaling);
      margin = btScalar(saved->m_collisionMargin);
    } else if (isGImpactMesh(data)) {
      auto* gimpact = reinterpret_cast<btGImpactMeshShapeData*>(data);
      meshData = &gimpact->m_meshInterface;
      scaling.deSerializeFloat(gimpact->m_localScaling);
      margin = btScalar(gimpact->m_collisionMargin);
    }
    if (meshData != nullptr) {
      // Bullet's own reading of the mesh parts (every index and vertex form it writes), then gpucol's checks.
      btTriangleIndexVertexArray* arrays = createMeshInterface(*createStridingMeshInterfaceData(meshData));
      const std::string name = data->m_name != nullptr ? data->m_name : "mesh of a .bullet file";
      auto mesh = std::make_unique<MeshShape>(
          std::make_shared<const TriangleMesh>(TriangleMesh::fromStridingMesh(*arrays, name)), m_config);
      mesh->setLocalScaling(scaling);
      mesh->setMargin(margin);
      shape = mesh.release();
      m_allocatedCollisionShapes.push_back(shape);
      ++m_meshShapesImported;
    } else if (data != nullptr && data->m_shapeType == COMPOUND_SHAPE_PROXYTYPE) {
      // A compound is rebuilt only when a child (at any depth) is a mesh gpucol brings back; the other
      // children are the stock importer's.
      auto* compoundData = reinterpret_cast<btCompoundShapeData*>(data);
      std::vector<btCollisionShape*> children(std::size_t(compoundData->m_numChildShapes), nullptr);
      bool any = false;
      for (int i = 0; i < compoundData->m_numChildShapes; ++i) {
        children[std::size_t(i)] = gpucolShape(compoundData->m_childShapePtr[i].m_childShape);
        any = any || children[std::size_t(i)] != nullptr;
      }
      if (any) {
        btCompoundShape* compound = createCompoundShape();
        for (int i = 0; i < compoundData->m_numChildShapes; ++i) {
          btCollisionShape* child = children[std::size_t(i)];
          if (child == nullptr) child = convertCollisionShape(compoundData->m_childShapePtr[i].m_childShape);
          if (child == nullptr) continue;  // as the stock importer: a child it cannot read is left out
          btTransform transform;
          transform.deSerializeFloat(compoundData->m_childShapePtr[i].m_transform);
          compound->addChildShape(transform, child);
        }
        shape = compound;
      }
    }
  } catch (const std::exception& e) {
    warnOnce("import " + std::string(data->m_name != nullptr ? data->m_name : ""),
             std::string("a mesh of a .bullet file is left to btBulletWorldImporter: ") + e.what());
    shape = nullptr;
  }
  if (shape != nullptr) m_ours.insert(shape);
  m_converted[data] = shape;
  return shape;
}

bool WorldImporter::convertAllObjects(bParse::btBulletFile* file) {
  m_converted.clear();
  m_meshShapesImported = 0;
  // gpucol's shapes first. Their records are hidden from the stock conversion (given a type it does not
  // convert) and given back after it.
  for (int i = 0; i < file->m_collisionShapes.size(); ++i) {
    gpucolShape(reinterpret_cast<btCollisionShapeData*>(file->m_collisionShapes[i]));
  }
  std::vector<std::pair<btCollisionShapeData*, int>> hidden;
  const auto hide = [&](btCollisionShapeData* data) {
    if (data->m_shapeType == kHiddenShapeType) return;
    hidden.emplace_back(data, data->m_shapeType);
    data->m_shapeType = kHiddenShapeType;
  };
  const auto unhide = [&] {
    for (auto it = hidden.rbegin(); it != hidden.rend(); ++it) it->first->m_shapeType = it->second;
  };
  for (const auto& [data, shape] : m_converted) {
    if (shape == nullptr) continue;
    // A saved MeshShape's BVH mesh is a record of its own in the file's list too.
    if (btTriangleMeshShapeData* saved = savedMeshShape(data)) hide(&saved->m_collisionShapeData);
    hide(data);
    if (data->m_name != nullptr) {
      char* name = duplicateName(data->m_name);
      m_objectNameMap.insert(shape, name);
      m_nameShapeMap.insert(name, shape);
    }
  }
  // The stock conversion empties its shape map before it converts the shapes, then looks the bodies' shapes
  // up in it: gpucol's go in during the shape loop, at its first compound. An empty compound record at the
  // end of the list makes sure there is one.
  btCompoundShapeData placeholder;
  std::memset(&placeholder, 0, sizeof(placeholder));
  placeholder.m_collisionShapeData.m_shapeType = COMPOUND_SHAPE_PROXYTYPE;
  file->m_collisionShapes.push_back(reinterpret_cast<bParse::bStructHandle*>(&placeholder));
  m_shapesPending = true;
  m_deferring = true;
  m_deferred.clear();
  bool ok = false;
  try {
    ok = btBulletWorldImporter::convertAllObjects(file);
  } catch (...) {
    m_deferring = m_shapesPending = false;
    file->m_collisionShapes.pop_back();
    unhide();
    throw;
  }
  m_deferring = m_shapesPending = false;
  file->m_collisionShapes.pop_back();
  unhide();
  // The placeholder's empty compound is nobody's.
  if (btCollisionShape** empty = m_shapeMap.find(&placeholder)) {
    m_allocatedCollisionShapes.remove(*empty);
    delete *empty;
    m_shapeMap.remove(&placeholder);
  }

  // Bodies of gpucol's shapes get the file's mass and inertia: the stock conversion made a concave one static
  // and gave a compound its box's inertia.
  const bool doubles = (file->getFlags() & bParse::FD_DOUBLE_PRECISION) != 0;
  for (int i = 0; i < m_bodyMap.size(); ++i) {
    btRigidBody* body = btRigidBody::upcast(*m_bodyMap.getAtIndex(i));
    if (body == nullptr || !m_ours.count(body->getCollisionShape())) continue;
    const void* record = m_bodyMap.getKeyAtIndex(i).getPointer();
    btScalar inverseMass;
    btVector3 inverseInertia;
    if (doubles) {
      const auto* d = static_cast<const btRigidBodyDoubleData*>(record);
      inverseMass = btScalar(d->m_inverseMass);
      inverseInertia.deSerializeDouble(d->m_invInertiaLocal);
    } else {
      const auto* f = static_cast<const btRigidBodyFloatData*>(record);
      inverseMass = btScalar(f->m_inverseMass);
      inverseInertia.deSerializeFloat(f->m_invInertiaLocal);
    }
    const btVector3 inertia(inverseOf(inverseInertia.x()), inverseOf(inverseInertia.y()),
                            inverseOf(inverseInertia.z()));
    body->setMassProps(inverseOf(inverseMass), inertia);
    body->updateInertiaTensor();
  }
  if (m_dynamicsWorld != nullptr) {
    for (btCollisionObject* object : m_deferred) {
      if (btRigidBody* body = btRigidBody::upcast(object)) {
        m_dynamicsWorld->addRigidBody(body);
      } else {
        m_dynamicsWorld->addCollisionObject(object);
      }
    }
  }
  m_deferred.clear();
  return ok;
}

btCompoundShape* WorldImporter::createCompoundShape() {
  btCompoundShape* compound = btBulletWorldImporter::createCompoundShape();
  if (m_shapesPending) {
    m_shapesPending = false;
    for (const auto& [data, shape] : m_converted) {
      if (shape != nullptr) m_shapeMap.insert(data, shape);
    }
  }
  return compound;
}

btRigidBody* WorldImporter::createRigidBody(bool isDynamic, btScalar mass, const btTransform& startTransform,
                                            btCollisionShape* shape, const char* bodyName) {
  if (!m_deferring)
    return btBulletWorldImporter::createRigidBody(isDynamic, mass, startTransform, shape, bodyName);
  btDynamicsWorld* world = std::exchange(m_dynamicsWorld, nullptr);
  btRigidBody* body =
      btBulletWorldImporter::createRigidBody(isDynamic, mass, startTransform, shape, bodyName);
  m_dynamicsWorld = world;
  m_deferred.push_back(body);
  return body;
}

btCollisionObject* WorldImporter::createCollisionObject(const btTransform& startTransform,
                                                        btCollisionShape* shape, const char* bodyName) {
  if (!m_deferring) return btBulletWorldImporter::createCollisionObject(startTransform, shape, bodyName);
  btDynamicsWorld* world = std::exchange(m_dynamicsWorld, nullptr);
  btCollisionObject* object = btBulletWorldImporter::createCollisionObject(startTransform, shape, bodyName);
  m_dynamicsWorld = world;
  m_deferred.push_back(object);
  return object;
}

void WorldImporter::deleteAllData() {
  m_converted.clear();
  m_ours.clear();
  m_deferred.clear();
  btBulletWorldImporter::deleteAllData();
}

}  // namespace gpucol
