#pragma once

#include <LinearMath/btVector3.h>

#include <vector>

class btCollisionWorld;

namespace gpucol::demo {

/// One triangle of a collision object's shape, in world coordinates.
struct WorldTriangle {
  btVector3 a;     ///< First corner.
  btVector3 b;     ///< Second corner.
  btVector3 c;     ///< Third corner.
  int object = 0;  ///< Index of the object in the world's collision object array.
};

/// Every triangle of every collision object of `world`, as its collision shape sees it, placed by the
/// object's world transform: what collides is what is drawn. Concave shapes (gpucol::MeshShape, GImpact
/// meshes, Bullet's triangle meshes) give their triangles through processAllTriangles over their whole box;
/// compound shapes give their children's; convex shapes (boxes, spheres, hulls) give the triangles of their
/// hull (btShapeHull, margin included). A shape without finite bounds (a static plane) is cut to a 1 km box
/// around the origin. Other shapes give nothing.
std::vector<WorldTriangle> collisionTriangles(const btCollisionWorld& world);

}  // namespace gpucol::demo
