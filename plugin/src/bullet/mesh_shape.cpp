#include "gpucol/mesh_shape.h"

#include <algorithm>
#include <array>
#include <cfloat>
#include <cmath>
#include <sstream>

#include "bullet/warn_once.h"
#include "bvh/aabb_tree.h"
#include "bvh/tree_query.h"
#include "gpucol/mesh_error.h"
#include "memory/large_array_allocator.h"
#include "mesh/edge_wings.h"
#include "mesh/flat_faces.h"
#include "mesh/mesh_analysis.h"

namespace gpucol {
namespace {

/// The soup of triangleSoup(), in a large-array mapping: the near phase reads a large mesh's triangles at
/// random, and on huge pages most of those reads stop missing the TLB.
std::shared_ptr<const float[]> buildTriangleSoup(const TriangleMesh& mesh) {
  const std::vector<float>& positions = mesh.positions();
  const std::vector<std::uint32_t>& indices = mesh.indices();
  const std::size_t size = 3 * indices.size();
  float* const soup = LargeArrayAllocator<float>().allocate(size);
  std::shared_ptr<const float[]> held(
      soup, [size](const float* p) { LargeArrayAllocator<float>().deallocate(const_cast<float*>(p), size); });
  for (std::size_t k = 0; k < indices.size(); ++k) {
    for (std::size_t c = 0; c < 3; ++c) soup[3 * k + c] = positions[3 * std::size_t(indices[k]) + c];
  }
  return held;
}

}  // namespace

MeshShape::MeshShape(std::shared_ptr<const TriangleMesh> mesh, const Config& config) : m_mesh(std::move(mesh)) {
  if (!m_mesh) throw MeshError("MeshShape: the mesh pointer is null");
  m_tree = std::make_shared<const AabbTree>(AabbTree::build(*m_mesh, config.trianglesPerLeaf));
  m_soup = buildTriangleSoup(*m_mesh);
  const std::vector<std::uint32_t> across = matchEdges(*m_mesh);
  m_wings = buildEdgeWings(*m_mesh, across);
  m_flatDiagonals = findFlatDiagonals(*m_mesh, m_wings);
  m_flatFaceHalfExtents = flatFaceHalfExtents(*m_mesh, across, m_flatDiagonals);
  // Not CUSTOM_CONCAVE_SHAPE_TYPE: Bullet 3 gives that value to SDF_SHAPE_PROXYTYPE too, and its convex-concave
  // algorithm treats every shape of that type as a btSdfCollisionShape (boxes would fall through a mesh).
  // FAST_CONCAVE_MESH_PROXYTYPE is a concave type that nothing in Bullet special-cases, so Bullet's generic
  // concave paths (processAllTriangles) serve it.
  m_shapeType = kMeshShapeType;
}

MeshShape::~MeshShape() = default;

bool MeshShape::isMeshShape(const btCollisionShape* shape) {
  return shape != nullptr && shape->getShapeType() == kMeshShapeType &&
         dynamic_cast<const MeshShape*>(shape) != nullptr;
}

void MeshShape::setLocalScaling(const btVector3& scaling) {
  const auto refuse = [&](const std::string& why) {
    std::ostringstream message;
    message << "MeshShape '" << m_mesh->name() << "': local scaling (" << scaling.x() << ", " << scaling.y()
            << ", " << scaling.z() << ") refused: " << why;
    throw MeshError(message.str());
  };
  for (int axis = 0; axis < 3; ++axis) {
    const btScalar s = scaling[axis];
    if (!std::isfinite(s) || !std::isnormal(s)) {
      std::ostringstream why;
      why << "component " << axis << " is " << s << "; it must be finite and non-zero (a normal float)";
      refuse(why.str());
    }
  }
  const btVector3 magnitude = scaling.absolute();
  const btScalar smallest = magnitude[magnitude.minAxis()], largest = magnitude[magnitude.maxAxis()];
  if (largest > kMaxScalingRatio * smallest) {
    std::ostringstream why;
    why << "its components differ in magnitude by " << largest / smallest << ", more than the limit of "
        << kMaxScalingRatio;
    refuse(why.str());
  }
  for (int axis = 0; axis < 3; ++axis) {
    // In double: the scaled coordinate may overflow float, which is what is being refused.
    const double extent =
        std::max(std::abs(double(m_tree->rootMin()[axis])), std::abs(double(m_tree->rootMax()[axis])));
    if (extent * double(magnitude[axis]) > double(TriangleMesh::kMaxCoordinate)) {
      std::ostringstream why;
      why << "the scaled mesh reaches " << extent * double(magnitude[axis]) << " on axis " << axis
          << ", beyond gpucol's limit of +-" << TriangleMesh::kMaxCoordinate;
      refuse(why.str());
    }
  }
  m_localScaling = scaling;
}

btScalar MeshShape::flatFaceSize(std::uint32_t triangle) const {
  const float* half = m_flatFaceHalfExtents.data() + 3 * std::size_t(triangle);
  return 2 * (btVector3(half[0], half[1], half[2]) * m_localScaling).length();
}

void MeshShape::getAabb(const btTransform& t, btVector3& aabbMin, btVector3& aabbMax) const {
  const AabbNode& root = m_tree->node(0);
  // The scaled root box, then carried by the body's rotation: centre by R, half extents by |R| (an exact box
  // of the rotated box).
  const btVector3 lo = btVector3(root.min[0], root.min[1], root.min[2]) * m_localScaling;
  const btVector3 hi = btVector3(root.max[0], root.max[1], root.max[2]) * m_localScaling;
  const btVector3 centre = btScalar(0.5) * (lo + hi);
  const btVector3 halfExtent = (btScalar(0.5) * (hi - lo)).absolute() + btVector3(getMargin(), getMargin(), getMargin());
  const btMatrix3x3 absBasis = t.getBasis().absolute();
  const btVector3 worldCentre = t(centre);
  const btVector3 worldExtent(absBasis[0].dot(halfExtent), absBasis[1].dot(halfExtent), absBasis[2].dot(halfExtent));
  aabbMin = worldCentre - worldExtent;
  aabbMax = worldCentre + worldExtent;
}

void MeshShape::processAllTriangles(btTriangleCallback* callback, const btVector3& aabbMin,
                                    const btVector3& aabbMax) const {
  // The query box comes in the scaled frame; the tree lives in the unscaled one. Dividing by the scale maps the
  // box over (a negative scale swaps its corners).
  float queryMin[3], queryMax[3];
  for (int axis = 0; axis < 3; ++axis) {
    const float a = float(aabbMin[axis] / m_localScaling[axis]);
    const float b = float(aabbMax[axis] / m_localScaling[axis]);
    queryMin[axis] = std::min(a, b);
    queryMax[axis] = std::max(a, b);
  }
  const auto overlaps = [&](const float* min, const float* max) {
    return min[0] <= queryMax[0] && max[0] >= queryMin[0] && min[1] <= queryMax[1] && max[1] >= queryMin[1] &&
           min[2] <= queryMax[2] && max[2] >= queryMin[2];
  };
  const float* positions = m_mesh->positions().data();
  const std::uint32_t* indices = m_mesh->indices().data();
  visitTreeTriangles(*m_tree, overlaps, [&](std::uint32_t t) {
    btVector3 corners[3];
    for (int i = 0; i < 3; ++i) {
      const float* p = positions + 3 * std::size_t(indices[3 * std::size_t(t) + i]);
      corners[i] = btVector3(p[0], p[1], p[2]) * m_localScaling;
    }
    const PartTriangle id = m_mesh->partTriangle(t);
    callback->processTriangle(corners, id.part, id.index);
  });
}

void MeshShape::calculateLocalInertia(btScalar mass, btVector3& inertia) const {
  const std::string& name = m_mesh->name();
  if (!std::isfinite(mass) || mass < 0) {
    std::ostringstream message;
    message << "MeshShape '" << name << "': calculateLocalInertia needs a finite mass >= 0, got " << mass;
    throw MeshError(message.str());
  }
  if (mass == 0) {  // a static body: Bullet ignores its inertia
    inertia.setValue(0, 0, 0);
    return;
  }
  // Mass properties of the scaled mesh in double, for a density giving `mass`; only the inertia handed to
  // Bullet must fit float, not the volume or the unit-density moments on the way.
  const btVector3& s = m_localScaling;
  const std::array<double, 3> scale = {double(s.x()), double(s.y()), double(s.z())};
  double diagonal[3];
  try {
    const MassProperties unitDensity =
        integrateMassProperties(m_mesh->positions(), m_mesh->indices(), m_mesh->report(), 1.0, name, scale);
    const double density = double(mass) / unitDensity.volume;
    const auto& I = unitDensity.inertia;
    for (int axis = 0; axis < 3; ++axis) diagonal[axis] = I[std::size_t(4 * axis)] * density;
    const double offDiagonal = std::max({std::abs(I[1]), std::abs(I[2]), std::abs(I[5])});
    const double largest = std::max({I[0], I[4], I[8]});
    const auto& c = unitDensity.centerOfMass;
    double size = 0;
    for (int axis = 0; axis < 3; ++axis) {
      const double d =
          (double(m_tree->rootMax()[axis]) - double(m_tree->rootMin()[axis])) * scale[std::size_t(axis)];
      size += d * d;
    }
    size = std::sqrt(size);
    // 1e-3 relative: far above the rounding of the double integrals, far below an inertia that matters.
    if (offDiagonal > 1e-3 * largest || std::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]) > 1e-3 * size) {
      warnOnce(
          "inertia frame " + name,
          "MeshShape '" + name +
              "': the mesh is not in its principal frame (centre of mass off the origin or a non-diagonal "
              "inertia tensor); the body gets the tensor's diagonal. Build the body with principalMeshBody().");
    }
  } catch (const MeshError& e) {
    // No volume to integrate: the box of the scaled mesh stands in, as btCollisionShape's default would.
    warnOnce("inertia box " + name, std::string(e.what()) + "; using the inertia of its bounding box");
    double d[3];
    for (int axis = 0; axis < 3; ++axis)
      d[axis] = (double(m_tree->rootMax()[axis]) - double(m_tree->rootMin()[axis])) *
                    std::abs(scale[std::size_t(axis)]) +
                2 * double(getMargin());
    diagonal[0] = double(mass) / 12 * (d[1] * d[1] + d[2] * d[2]);
    diagonal[1] = double(mass) / 12 * (d[0] * d[0] + d[2] * d[2]);
    diagonal[2] = double(mass) / 12 * (d[0] * d[0] + d[1] * d[1]);
  }
  // Bullet inverts the inertia in float: inf gives a body that never turns, a denormal or 0 an infinite
  // inverse, and its motion turns NaN after one step.
  for (int axis = 0; axis < 3; ++axis) {
    if (!(diagonal[axis] >= double(FLT_MIN) && diagonal[axis] <= double(FLT_MAX))) {
      std::ostringstream message;
      message << "MeshShape '" << name << "': the inertia about "
              << "xyz"[axis] << " for mass " << mass << " at local scaling (" << s.x() << ", " << s.y()
              << ", " << s.z() << ") is " << diagonal[axis] << ", outside float's normal range (" << FLT_MIN
              << " to " << FLT_MAX << "); scale the mesh or the mass so that it fits";
      throw MeshError(message.str());
    }
  }
  inertia.setValue(btScalar(diagonal[0]), btScalar(diagonal[1]), btScalar(diagonal[2]));
}

}  // namespace gpucol
