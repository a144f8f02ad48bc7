#include "demo/collision_triangles.h"

#include <BulletCollision/CollisionDispatch/btCollisionWorld.h>
#include <BulletCollision/CollisionShapes/btCompoundShape.h>
#include <BulletCollision/CollisionShapes/btConcaveShape.h>
#include <BulletCollision/CollisionShapes/btConvexShape.h>
#include <BulletCollision/CollisionShapes/btShapeHull.h>
#include <BulletCollision/CollisionShapes/btTriangleCallback.h>

#include <algorithm>

namespace gpucol::demo {
namespace {

// Half the side of the box that bounds what is drawn of an unbounded shape (metres).
constexpr btScalar kUnboundedHalfSide = 500;

class Collector : public btTriangleCallback {
 public:
  Collector(std::vector<WorldTriangle>& out, const btTransform& transform, int object)
      : m_out(out), m_transform(transform), m_object(object) {}

  void processTriangle(btVector3* triangle, int, int) override {
    m_out.push_back({m_transform(triangle[0]), m_transform(triangle[1]), m_transform(triangle[2]), m_object});
  }

 private:
  std::vector<WorldTriangle>& m_out;
  btTransform m_transform;
  int m_object;
};

void addShape(const btCollisionShape& shape, const btTransform& transform, int object,
              std::vector<WorldTriangle>& out) {
  if (shape.isCompound()) {
    const auto& compound = static_cast<const btCompoundShape&>(shape);
    for (int i = 0; i < compound.getNumChildShapes(); ++i) {
      addShape(*compound.getChildShape(i), transform * compound.getChildTransform(i), object, out);
    }
  } else if (shape.isConcave()) {
    btVector3 low, high;
    shape.getAabb(btTransform::getIdentity(), low, high);
    const btVector3 limit(kUnboundedHalfSide, kUnboundedHalfSide, kUnboundedHalfSide);
    low.setMax(-limit);
    high.setMin(limit);
    // A hair wider than the shape's own box, so triangles on its faces are not lost to a touching test.
    const btVector3 pad = 1e-3f * (high - low) + btVector3(1e-4f, 1e-4f, 1e-4f);
    Collector collector(out, transform, object);
    static_cast<const btConcaveShape&>(shape).processAllTriangles(&collector, low - pad, high + pad);
  } else if (shape.isConvex()) {
    btShapeHull hull(static_cast<const btConvexShape*>(&shape));
    if (!hull.buildHull(shape.getMargin())) return;
    const btVector3* vertices = hull.getVertexPointer();
    const unsigned int* indices = hull.getIndexPointer();
    for (int i = 0; i + 2 < hull.numIndices(); i += 3) {
      out.push_back({transform(vertices[indices[i]]), transform(vertices[indices[i + 1]]),
                     transform(vertices[indices[i + 2]]), object});
    }
  }
}

}  // namespace

std::vector<WorldTriangle> collisionTriangles(const btCollisionWorld& world) {
  std::vector<WorldTriangle> out;
  const btCollisionObjectArray& objects = world.getCollisionObjectArray();
  for (int i = 0; i < objects.size(); ++i) {
    addShape(*objects[i]->getCollisionShape(), objects[i]->getWorldTransform(), i, out);
  }
  return out;
}

}  // namespace gpucol::demo
