#pragma once

#include <BulletCollision/CollisionShapes/btConcaveShape.h>
#include <LinearMath/btVector3.h>

#include <cstdint>
#include <memory>
#include <vector>

#include "gpucol/config.h"
#include "gpucol/triangle_mesh.h"

class btBvhTriangleMeshShape;
class btGImpactMeshShape;

namespace gpucol {

class AabbTree;

/// A triangle mesh as a Bullet collision shape (a btConcaveShape of type kMeshShapeType): the shared,
/// immutable mesh, its tree of non-updated AABBs (built once, in the mesh's own frame) and a local scaling.
///
/// Dynamic bodies may use it. Boxes, spheres and hulls collide with it through Bullet's own convex-concave
/// algorithm (processAllTriangles answers from the tree); mesh pairs, and a mesh against btStaticPlaneShape or
/// btBvhTriangleMeshShape, go through MeshMeshAlgorithm. The margin is 0 by default, as for Bullet's other
/// concave shapes; a margin m makes contacts report a distance m smaller, so bodies rest m apart.
ATTRIBUTE_ALIGNED16(class) MeshShape : public btConcaveShape {
 public:
  BT_DECLARE_ALIGNED_ALLOCATOR();

  /// Builds the tree of `mesh` with `config.trianglesPerLeaf` triangles per leaf; throws MeshError for a null mesh.
  explicit MeshShape(std::shared_ptr<const TriangleMesh> mesh, const Config& config = Config());
  ~MeshShape() override;

  /// A MeshShape with the triangles of a GImpact mesh (every part, TriangleMesh::fromStridingMesh), its local
  /// scaling and its triangles' margin (the parts', which GImpact collides with, not getMargin()'s). Parts
  /// scaled differently get their scaling in the vertices and the shape (1,1,1). Throws MeshError as
  /// fromStridingMesh.
  static std::unique_ptr<MeshShape> fromGImpact(const btGImpactMeshShape& shape,
                                                const Config& config = Config());
  /// A MeshShape with the triangles of a BVH mesh, its local scaling (its mesh interface's) and its margin.
  static std::unique_ptr<MeshShape> fromBvh(const btBvhTriangleMeshShape& shape,
                                            const Config& config = Config());

  /// The mesh this shape collides with.
  const TriangleMesh& mesh() const { return *m_mesh; }
  /// The shared mesh, for building another shape over it.
  const std::shared_ptr<const TriangleMesh>& sharedMesh() const { return m_mesh; }
  /// The tree of non-updated AABBs of the mesh.
  const AabbTree& tree() const { return *m_tree; }
  /// The mesh's triangles as a "triangle soup": the 9 unscaled coordinates of triangle t (its three vertices
  /// in index order, x y z each) at [9 t, 9 t + 9). Built with the shape, so the mesh pair query reads a
  /// triangle in one contiguous load instead of an index load followed by three vertex loads; it costs 36
  /// bytes per triangle held by each shape (14.4 MB for 400,000 triangles), on huge pages where the system
  /// gives them.
  const float* triangleSoup() const { return m_soup.get(); }
  /// Per edge of each triangle, the far vertex of the triangle across it (unscaled; NaN for an edge without
  /// exactly one such triangle): 9 floats per triangle t at [9 t, 9 t + 9), edge k (vertex k to k + 1) at
  /// 9 t + 3 k. An edge's contact may only push along the directions its two faces leave it (none at a
  /// concave or flat edge); 36 bytes per triangle.
  const float* edgeWings() const {
    return m_wings.data();
  }
  /// Per triangle, bit k set when edge k is a diagonal of a flat face (its wing lies in the triangle's plane,
  /// within 1e-4 of the edge's length): a contact over the triangle may lie over the triangle across it too.
  const std::uint8_t* flatDiagonals() const {
    return m_flatDiagonals.data();
  }
  /// The diagonal of the box around the flat face that triangle `triangle` belongs to (the triangles joined
  /// to it across flat diagonals), scaled: a box's side for one of its triangles, the triangle's own size on
  /// a curved surface. Two flat faces in contact share one support as wide as the smaller.
  btScalar flatFaceSize(std::uint32_t triangle) const;

  /// The largest ratio between the magnitudes of two local scaling components: beyond it the float transforms
  /// of the mesh pair query round the short axis so much that intersecting pairs are lost or made up.
  static constexpr btScalar kMaxScalingRatio = btScalar(1e5);

  /// Per-axis scale applied to the mesh (1,1,1 by default; negative components mirror). Each component must be
  /// a finite, non-zero normal float, no two may differ in magnitude by more than kMaxScalingRatio, and the
  /// scaled mesh must stay within TriangleMesh::kMaxCoordinate: anything else throws MeshError and keeps the
  /// previous scaling.
  void setLocalScaling(const btVector3& scaling) override;
  /// The current local scaling.
  const btVector3& getLocalScaling() const override { return m_localScaling; }

  /// World box of the scaled mesh under `t`: the tree's root box carried by |R|, widened by the margin.
  void getAabb(const btTransform& t, btVector3& aabbMin, btVector3& aabbMax) const override;
  /// Calls `callback` with every triangle (in the shape's scaled local frame) whose box overlaps the given
  /// box (also in that frame), found through the tree, with its part and index within the part
  /// (TriangleMesh::partTriangle); triangles come in ascending tree order.
  void processAllTriangles(btTriangleCallback* callback, const btVector3& aabbMin,
                           const btVector3& aabbMax) const override;
  /// Diagonal inertia of a solid of uniform density with this closed mesh as its surface (scaled), from the
  /// mass properties. The body frame must be the mesh's principal frame for this to be the full tensor; Bullet
  /// takes only a diagonal, so for any other mesh the tensor's diagonal is returned with a warning printed once:
  /// build such a body with principalMeshBody() (principal_mesh_body.h), which moves the mesh into its frame.
  /// An open mesh has no volume: the inertia of its bounding box is used, with a warning printed once. A mass of
  /// 0 (a static body) gives 0. Throws MeshError for a mass that is negative or not finite, and for an inertia
  /// that is not a normal float (overflowing, or so small it would turn the body's motion into NaN), computed in
  /// double from the scaled mesh before it is rounded to float.
  void calculateLocalInertia(btScalar mass, btVector3& inertia) const override;
  /// "gpucol::MeshShape".
  const char* getName() const override { return "gpucol::MeshShape"; }

  /// The size of the record serialize() writes: a btCompoundShapeData.
  int calculateSerializeBufferSize() const override;
  /// Writes the shape in a form stock Bullet reads back (btBulletWorldImporter): a compound shape whose one
  /// child, at the identity, is a BVH triangle mesh with the same triangles (one mesh part per part), the
  /// local scaling as its mesh interface's scaling and the margin. A compound, because the importer makes
  /// every body whose shape is concave static; the scaling in the mesh interface, because the importer
  /// rewrites a scaled BVH's record as it reads it. The child's name, "gpucol::MeshShape", lets WorldImporter
  /// bring back a MeshShape.
  const char* serialize(void* dataBuffer, btSerializer* serializer) const override;
  /// Writes the shape's record unless the serializer holds it already: btCollisionWorld writes every body's
  /// shape even when a compound wrote it as a child, and a second record under the same address breaks the
  /// file.
  void serializeSingleShape(btSerializer * serializer) const override;
  /// The name serialize() gives the compound's child; WorldImporter recognises a saved MeshShape by it.
  static constexpr const char* kSerializedName = "gpucol::MeshShape";

  /// The Bullet shape type of every MeshShape: FAST_CONCAVE_MESH_PROXYTYPE, a concave type Bullet itself never
  /// uses (CUSTOM_CONCAVE_SHAPE_TYPE is Bullet 3's SDF type, which its convex-concave algorithm special-cases).
  static constexpr int kMeshShapeType = FAST_CONCAVE_MESH_PROXYTYPE;

  /// True when `shape` is a gpucol MeshShape.
  static bool isMeshShape(const btCollisionShape* shape);

 private:
  std::shared_ptr<const TriangleMesh> m_mesh;
  std::shared_ptr<const AabbTree> m_tree;
  std::shared_ptr<const float[]> m_soup;
  std::vector<float> m_wings;
  std::vector<std::uint8_t> m_flatDiagonals;
  std::vector<float> m_flatFaceHalfExtents;  // 3 per triangle, unscaled (flatFaceHalfExtents)
  btVector3 m_localScaling{1, 1, 1};
};

}  // namespace gpucol
