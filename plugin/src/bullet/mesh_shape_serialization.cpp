// MeshShape::serialize: a MeshShape written as a compound shape holding one BVH triangle mesh, the form stock
// Bullet's btBulletWorldImporter reads back with its triangles, scaling, margin and a dynamic body's mass.
#include <BulletCollision/CollisionShapes/btBvhTriangleMeshShape.h>
#include <BulletCollision/CollisionShapes/btCompoundShape.h>
#include <BulletCollision/CollisionShapes/btTriangleIndexVertexArray.h>
#include <LinearMath/btSerializer.h>

#include <cstring>
#include <vector>

#include "gpucol/mesh_shape.h"

namespace gpucol {

int MeshShape::calculateSerializeBufferSize() const {
  return int(sizeof(btCompoundShapeData));
}

void MeshShape::serializeSingleShape(btSerializer* serializer) const {
  if (serializer->findPointer(const_cast<MeshShape*>(this)) != nullptr) return;
  btConcaveShape::serializeSingleShape(serializer);
}

const char* MeshShape::serialize(void* dataBuffer, btSerializer* serializer) const {
  // The compound: the shape's own record (its user's name, if any, stays on it).
  auto* compound = static_cast<btCompoundShapeData*>(dataBuffer);
  btCollisionShape::serialize(&compound->m_collisionShapeData, serializer);
  compound->m_collisionShapeData.m_shapeType = COMPOUND_SHAPE_PROXYTYPE;
  compound->m_collisionMargin = float(getMargin());
  compound->m_numChildShapes = 1;

  // The BVH mesh child has no object of its own: the soup's address names its record, unique to this shape.
  const void* childKey = m_soup.get();
  btChunk* childrenChunk = serializer->allocate(sizeof(btCompoundShapeChildData), 1);
  auto* child = static_cast<btCompoundShapeChildData*>(childrenChunk->m_oldPtr);
  compound->m_childShapePtr = static_cast<btCompoundShapeChildData*>(serializer->getUniquePointer(child));
  btTransform::getIdentity().serializeFloat(child->m_transform);
  child->m_childShape =
      static_cast<btCollisionShapeData*>(serializer->getUniquePointer(const_cast<void*>(childKey)));
  child->m_childShapeType = TRIANGLE_MESH_SHAPE_PROXYTYPE;
  child->m_childMargin = float(getMargin());
  serializer->finalizeChunk(childrenChunk, "btCompoundShapeChildData", BT_ARRAY_CODE,
                            childrenChunk->m_oldPtr);

  // The mesh as Bullet's own interface writes it, one mesh part per part, indices local to the part.
  const TriangleMesh& mesh = *m_mesh;
  std::vector<std::vector<int>> partIndices(mesh.parts().size());
  btTriangleIndexVertexArray arrays;
  for (std::size_t p = 0; p < mesh.parts().size(); ++p) {
    const MeshPart& part = mesh.parts()[p];
    std::vector<int>& local = partIndices[p];
    local.resize(3 * std::size_t(part.triangleCount));
    for (std::size_t i = 0; i < local.size(); ++i) {
      local[i] = int(mesh.indices()[3 * std::size_t(part.firstTriangle) + i] - part.firstVertex);
    }
    btIndexedMesh indexed;
    indexed.m_numTriangles = int(part.triangleCount);
    indexed.m_triangleIndexBase = reinterpret_cast<const unsigned char*>(local.data());
    indexed.m_triangleIndexStride = 3 * int(sizeof(int));
    indexed.m_numVertices = int(part.vertexCount);
    indexed.m_vertexBase =
        reinterpret_cast<const unsigned char*>(mesh.positions().data() + 3 * std::size_t(part.firstVertex));
    indexed.m_vertexStride = 3 * int(sizeof(float));
    indexed.m_indexType = PHY_INTEGER;
    indexed.m_vertexType = PHY_FLOAT;
    arrays.addIndexedMesh(indexed, PHY_INTEGER);
  }
  arrays.setScaling(m_localScaling);

  btChunk* meshChunk = serializer->allocate(sizeof(btTriangleMeshShapeData), 1);
  auto* meshData = static_cast<btTriangleMeshShapeData*>(meshChunk->m_oldPtr);
  std::memset(meshData, 0, sizeof(*meshData));
  meshData->m_collisionShapeData.m_shapeType = TRIANGLE_MESH_SHAPE_PROXYTYPE;
  meshData->m_collisionShapeData.m_name =
      static_cast<char*>(serializer->getUniquePointer(const_cast<char*>(kSerializedName)));
  serializer->serializeName(kSerializedName);
  arrays.serialize(&meshData->m_meshInterface, serializer);
  meshData->m_collisionMargin = float(getMargin());
  // No quantized BVH: the importer builds its own over the scaled triangles (one read from a file would be
  // taken at scale 1).
  serializer->finalizeChunk(meshChunk, "btTriangleMeshShapeData", BT_SHAPE_CODE, const_cast<void*>(childKey));
  return "btCompoundShapeData";
}

}  // namespace gpucol
