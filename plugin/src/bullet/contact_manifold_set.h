#pragma once

#include <BulletCollision/BroadphaseCollision/btCollisionAlgorithm.h>
#include <BulletCollision/BroadphaseCollision/btDispatcher.h>
#include <BulletCollision/CollisionDispatch/btCollisionObjectWrapper.h>
#include <BulletCollision/CollisionDispatch/btManifoldResult.h>
#include <BulletCollision/NarrowPhaseCollision/btPersistentManifold.h>

#include <vector>

namespace gpucol {

/// One contact of a pair as Bullet's manifolds take it, with "B" the pair's second body (body1).
struct PairContact {
  btVector3 pointOnB;   ///< World point on body1's surface (margin included).
  btVector3 normalOnB;  ///< Unit world normal on body1 pointing towards body0.
  btScalar distance;    ///< Signed distance along the normal, negative when penetrating (margins included).
  /// The part and triangle of body0's and body1's shape that made the contact (btManifoldPoint's m_partId0/1
  /// and m_index0/1, as Bullet's concave algorithms give them); -1 on a side without triangles (a plane).
  int partId0 = -1, index0 = -1, partId1 = -1, index1 = -1;
  /// How far the flat surface both sides have around the contact reaches: the smaller of the two triangles'
  /// flat faces (MeshShape::flatFaceSize; a plane's is unbounded). 0 where unknown.
  btScalar flatSize = 0;
};

/// The same contacts seen from the other side: body0 and body1 swap roles.
std::vector<PairContact> swapSides(std::vector<PairContact> contacts);

/// The persistent manifolds of one pair, one per direction of contact normal and patch of contact. Bullet
/// keeps at most 4 points in a manifold, chosen for the largest area around the deepest point; contacts whose
/// normals point different ways (a body in a corner, a peg in a hole) would fight over those 4 places, and a
/// patch without a contact this step would lose its held points to the patches that have one. A contact joins
/// the manifold whose reference normal (the first contact's normal, kept in body1's frame so that it turns
/// with the body) is within 30° of its own and whose first contact lies within a quarter of the smaller
/// body's bounding radius of it (kept in that body's frame), or within the flat surface either contact lies
/// on (two box faces resting on each other make one patch, as Bullet's box pair has one manifold); otherwise
/// it starts a new one. Manifolds live across steps: Bullet matches each new contact with a point already
/// held (within the breaking threshold) and keeps that point's impulse, so the solver warm starts;
/// refreshContactPoints drops points that drifted apart. A manifold left with no point at the end of a step
/// is released.
class ContactManifoldSet {
 public:
  /// Manifolds come from and go back to `dispatcher`.
  explicit ContactManifoldSet(btDispatcher* dispatcher) : m_dispatcher(dispatcher) {}
  ~ContactManifoldSet();
  ContactManifoldSet(const ContactManifoldSet&) = delete;
  ContactManifoldSet& operator=(const ContactManifoldSet&) = delete;

  /// Writes this step's contacts into the manifolds through `result` (whose body wrappers are body0 and
  /// body1), refreshes every manifold, releases the empty ones. `result`'s own manifold pointer is restored
  /// after. Speculative contacts up to `speculativeDistance` apart are kept: a manifold's breaking threshold
  /// is Bullet's for the pair, or that distance when it is larger, for this step.
  void write(const std::vector<PairContact>& contacts, const btCollisionObjectWrapper* body0,
             const btCollisionObjectWrapper* body1, btManifoldResult* result,
             btScalar speculativeDistance = 0);

  /// Appends the pair's manifolds.
  void appendTo(btManifoldArray& manifolds) const;

 private:
  struct Group {
    btPersistentManifold* manifold;
    btVector3 normalInBody1;  // reference normal, in body1's frame
    btScalar breakingThreshold;  // Bullet's, as the dispatcher made the manifold
    btVector3 anchor;            // the first contact's point, in the smaller body's frame (the patch's place)
    btScalar reach2;             // squared reach of the patch from its anchor
  };
  btDispatcher* m_dispatcher;
  std::vector<Group> m_groups;
};

}  // namespace gpucol
