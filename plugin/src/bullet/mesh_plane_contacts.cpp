#include "bullet/mesh_plane_contacts.h"

#include <algorithm>

#include "bvh/aabb_tree.h"
#include "bvh/tree_query.h"
#include "narrowphase/contact_reduction.h"

namespace gpucol {

std::vector<PairContact> meshPlaneContacts(const MeshShape& mesh, const btTransform& meshTransform,
                                           const btStaticPlaneShape& plane, const btTransform& planeTransform,
                                           int reductionResolution) {
  const btScalar margins = mesh.getMargin() + plane.getMargin();
  // The plane in the mesh's unscaled frame, where the tree lives: a point p of the mesh is at world
  // T(S p), and its distance to the plane is nWorld . T(S p) - cWorld = (S R^T nWorld) . p + (nWorld . t - cWorld).
  const btVector3 normalWorld = planeTransform.getBasis() * plane.getPlaneNormal();
  const btScalar constantWorld = normalWorld.dot(planeTransform(plane.getPlaneNormal() * plane.getPlaneConstant()));
  const btVector3 normalInMesh = (meshTransform.getBasis().transpose() * normalWorld) * mesh.getLocalScaling();
  const btScalar offset = normalWorld.dot(meshTransform.getOrigin()) - constantWorld;
  // Only vertices that touch or cross the plane (margins counted) give contacts, as triangles that cross give
  // the mesh pairs theirs. Vertices merely near it would fill Bullet's 4 places per manifold with points that
  // carry no load and push out the real supports (a mesh resting on a plane then never comes to rest); the
  // manifold's own refresh keeps points that lift off by less than the breaking threshold.
  const btScalar reach = margins;

  // A box can hold a vertex within reach only if its lowest corner along the plane normal is within reach.
  const auto boxNearPlane = [&](const float* min, const float* max) {
    btScalar lowest = offset;
    for (int axis = 0; axis < 3; ++axis) lowest += normalInMesh[axis] * (normalInMesh[axis] > 0 ? min[axis] : max[axis]);
    return lowest <= reach;
  };
  const std::uint32_t* indices = mesh.mesh().indices().data();
  const float* positions = mesh.mesh().positions().data();
  // (vertex, triangle) of every triangle near the plane.
  std::vector<std::uint64_t> vertices;
  visitTreeTriangles(mesh.tree(), boxNearPlane, [&](std::uint32_t t) {
    for (int i = 0; i < 3; ++i) vertices.push_back((std::uint64_t(indices[3 * std::size_t(t) + i]) << 32) | t);
  });
  // A vertex is shared by several triangles: it gives one contact, named by the lowest of them, whose flat
  // surface is the widest of their flat faces (a box's corner lies on its bottom face).
  std::sort(vertices.begin(), vertices.end());
  std::vector<PairContact> contacts;
  std::vector<ReductionInput> binned;
  for (std::size_t first = 0, next = 0; first < vertices.size(); first = next) {
    const std::uint32_t v = std::uint32_t(vertices[first] >> 32);
    btScalar flatSize = 0;
    for (next = first; next < vertices.size() && std::uint32_t(vertices[next] >> 32) == v; ++next) {
      flatSize = btMax(flatSize, mesh.flatFaceSize(std::uint32_t(vertices[next])));
    }
    const float* p = positions + 3 * std::size_t(v);
    const btScalar distance = normalInMesh.dot(btVector3(p[0], p[1], p[2])) + offset;
    if (distance > reach) continue;
    const btVector3 world = meshTransform(btVector3(p[0], p[1], p[2]) * mesh.getLocalScaling());
    // On the plane's margin surface; the distance counts both margins, so bodies rest `margins` apart.
    const btVector3 onPlane = world - normalWorld * (distance - plane.getMargin());
    PairContact contact{onPlane, normalWorld, distance - margins};
    // The mesh's part and triangle; the plane has none.
    const PartTriangle triangle = mesh.mesh().partTriangle(std::uint32_t(vertices[first]));
    contact.partId0 = triangle.part;
    contact.index0 = triangle.index;
    contact.flatSize = flatSize;
    contacts.push_back(contact);
    binned.push_back({Eigen::Vector3f(float(world.x()), float(world.y()), float(world.z())),
                      Eigen::Vector3f(float(normalWorld.x()), float(normalWorld.y()), float(normalWorld.z())),
                      float(distance - margins)});
  }
  std::vector<PairContact> reduced;
  for (std::uint32_t kept : reduceContacts(binned, reductionResolution)) reduced.push_back(contacts[kept]);
  return reduced;
}

}  // namespace gpucol
