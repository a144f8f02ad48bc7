// ContactManifoldSet, the pair's persistent manifolds, on Bullet's own btPersistentManifold: a face's corners
// stay in their points from step to step, of a dozen contacts on one patch the widest support goes in, the
// nearest of a fast pair's speculative contacts is held, contacts whose normals point other ways get
// manifolds of their own, a patch without a new contact keeps its points until they separate, and two flat
// faces in contact make one patch.
#include <gtest/gtest.h>

#include <BulletCollision/CollisionDispatch/btCollisionDispatcher.h>
#include <BulletCollision/CollisionDispatch/btCollisionObject.h>
#include <BulletCollision/CollisionDispatch/btCollisionObjectWrapper.h>
#include <BulletCollision/CollisionDispatch/btDefaultCollisionConfiguration.h>
#include <BulletCollision/CollisionDispatch/btManifoldResult.h>
#include <BulletCollision/CollisionShapes/btBoxShape.h>

#include <vector>

#include "bullet/contact_manifold_set.h"

namespace gpucol {
namespace {

// A 1 m box (body0) resting on a 10 m slab (body1) whose top face is y = 0: contacts have normal +y on body1.
class RestingPair : public ::testing::Test {
 protected:
  RestingPair()
      : dispatcher(&configuration),
        boxShape(btVector3(0.5f, 0.5f, 0.5f)),
        slabShape(btVector3(5, 0.5f, 5)),
        boxPose(btQuaternion::getIdentity(), btVector3(0, 0.5f, 0)),
        slabPose(btQuaternion::getIdentity(), btVector3(0, -0.5f, 0)),
        boxWrap(nullptr, &boxShape, &box, boxPose, -1, -1),
        slabWrap(nullptr, &slabShape, &slab, slabPose, -1, -1),
        manifolds(&dispatcher) {
    box.setCollisionShape(&boxShape);
    box.setWorldTransform(boxPose);
    slab.setCollisionShape(&slabShape);
    slab.setWorldTransform(slabPose);
  }

  // A contact on the slab's top face at (x, z), `distance` along +y (negative: the box is that deep).
  static PairContact onTop(btScalar x, btScalar z, btScalar distance) {
    PairContact c;
    c.pointOnB = btVector3(x, 0, z);
    c.normalOnB = btVector3(0, 1, 0);
    c.distance = distance;
    return c;
  }

  void write(const std::vector<PairContact>& contacts, btScalar speculativeDistance = 0) {
    btManifoldResult result(&boxWrap, &slabWrap);
    manifolds.write(contacts, &boxWrap, &slabWrap, &result, speculativeDistance);
  }

  std::vector<btPersistentManifold*> held() const {
    btManifoldArray array;
    manifolds.appendTo(array);
    std::vector<btPersistentManifold*> out;
    for (int i = 0; i < array.size(); ++i) out.push_back(array[i]);
    return out;
  }

  // The x, z of each point of every manifold, with its lifetime.
  struct Point {
    btScalar x, z;
    int lifeTime;
  };
  std::vector<Point> points() const {
    std::vector<Point> out;
    for (const btPersistentManifold* m : held()) {
      for (int k = 0; k < m->getNumContacts(); ++k) {
        const btManifoldPoint& p = m->getContactPoint(k);
        out.push_back({p.getPositionWorldOnB().x(), p.getPositionWorldOnB().z(), p.getLifeTime()});
      }
    }
    return out;
  }

  static bool has(const std::vector<Point>& ps, btScalar x, btScalar z) {
    for (const Point& p : ps) {
      if (btFabs(p.x - x) < 1e-4f && btFabs(p.z - z) < 1e-4f) return true;
    }
    return false;
  }

  // The box's four bottom corners, 1 mm deep, written `steps` times: a full manifold of a face at rest.
  void restOnCorners(int steps) {
    for (int i = 0; i < steps; ++i) {
      write({onTop(-0.5f, -0.5f, -1e-3f), onTop(0.5f, -0.5f, -1e-3f), onTop(0.5f, 0.5f, -1e-3f),
             onTop(-0.5f, 0.5f, -1e-3f)});
    }
  }

  btDefaultCollisionConfiguration configuration;
  btCollisionDispatcher dispatcher;
  btBoxShape boxShape, slabShape;
  btCollisionObject box, slab;
  btTransform boxPose, slabPose;  // the wrappers hold references to them
  btCollisionObjectWrapper boxWrap, slabWrap;
  ContactManifoldSet manifolds;
};

TEST_F(RestingPair, AFaceIsHeldAtItsCornersFromStepToStep) {
  restOnCorners(5);
  const std::vector<Point> ps = points();
  ASSERT_EQ(ps.size(), 4u);
  for (const Point& p : ps) EXPECT_EQ(p.lifeTime, 5) << p.x << ", " << p.z;
}

TEST_F(RestingPair, OfManyContactsOnAPatchTheCornersGoIn) {
  // Bullet keeps 4 points per manifold and a new point always takes a place: fed one by one, the points
  // inside a patch after its corners would push corners out. The deepest is kept as well (a corner here). The
  // patch, 0.15 m square, lies within a quarter of the box's bounding radius of its first contact: one
  // manifold.
  const btScalar h = 0.075f;
  std::vector<PairContact> contacts{onTop(h, h, -2e-3f), onTop(-h, -h, -1e-3f), onTop(h, -h, -1e-3f),
                                    onTop(-h, h, -1e-3f)};
  for (btScalar x : {-0.045f, 0.0f, 0.045f}) {
    for (btScalar z : {-0.03f, 0.03f}) contacts.push_back(onTop(x, z, -1e-3f));
  }
  write(contacts);
  ASSERT_EQ(held().size(), 1u);
  const std::vector<Point> ps = points();
  ASSERT_EQ(ps.size(), 4u);
  EXPECT_TRUE(has(ps, -h, -h) && has(ps, h, -h) && has(ps, h, h) && has(ps, -h, h));
}

TEST_F(RestingPair, NearestSpeculativeContactOfAFastPairIsHeld) {
  // A fast pair's manifold keeps points up to the step's reach (here 0.1 m) apart, and Bullet takes a new
  // point for a held one within that reach: contacts a few centimetres apart overwrite each other as they go
  // in. The nearest (2 cm) bounds how far the box may close this step; with it lost, the solver would let the
  // box move 5 cm into the slab.
  write({onTop(-0.5f, -0.5f, 0.02f), onTop(-0.45f, -0.5f, 0.05f), onTop(-0.5f, -0.45f, 0.06f),
         onTop(-0.46f, -0.46f, 0.07f)},
        0.1f);
  const std::vector<btPersistentManifold*> m = held();
  ASSERT_EQ(m.size(), 1u);
  btScalar nearest = BT_LARGE_FLOAT;
  for (int k = 0; k < m[0]->getNumContacts(); ++k)
    nearest = btMin(nearest, m[0]->getContactPoint(k).getDistance());
  EXPECT_NEAR(nearest, 0.02f, 1e-5f);
}

TEST_F(RestingPair, ContactsOfAnotherDirectionGetTheirOwnManifold) {
  // The wall's contact lies 0.1 m from the floor's two, within their patch, but its normal is 90 degrees from
  // theirs: it gets a manifold of its own.
  write({onTop(0.5f, -0.1f, -1e-3f), onTop(0.5f, 0.1f, -1e-3f)});
  PairContact wall = onTop(0.5f, 0.0f, -1e-3f);
  wall.normalOnB = btVector3(-1, 0, 0);
  write({onTop(0.5f, -0.1f, -1e-3f), onTop(0.5f, 0.1f, -1e-3f), wall});
  const std::vector<btPersistentManifold*> m = held();
  ASSERT_EQ(m.size(), 2u);
  for (const btPersistentManifold* manifold : m) {
    const btVector3 first = manifold->getContactPoint(0).m_normalWorldOnB;
    for (int k = 1; k < manifold->getNumContacts(); ++k) {
      EXPECT_GT(manifold->getContactPoint(k).m_normalWorldOnB.dot(first), 0.99f);
    }
  }
  EXPECT_EQ(points().size(), 3u);
}

TEST_F(RestingPair, APatchWithoutANewContactKeepsItsPointsUntilTheySeparate) {
  // A ring on a floor crosses it along one arc a step: the far side's points must stay while they touch, or
  // the body tips onto the side it no longer holds. Here the box's corners rest for 3 steps, then only the
  // side at z = -0.5 gets contacts, four of them: in one manifold they would take all of Bullet's 4 places.
  restOnCorners(3);
  const std::vector<PairContact> nearSide{onTop(-0.5f, -0.5f, -1e-3f), onTop(0.5f, -0.5f, -1e-3f),
                                          onTop(-0.2f, -0.45f, -1e-3f), onTop(0.2f, -0.45f, -1e-3f)};
  write(nearSide);
  std::vector<Point> ps = points();
  EXPECT_EQ(ps.size(), 6u);
  EXPECT_TRUE(has(ps, -0.5f, 0.5f) && has(ps, 0.5f, 0.5f));
  // Tipped about its edge at z = -0.5 until the far corners are 5 cm up, beyond Bullet's breaking threshold,
  // the box loses their points at the refresh; the near corners' stay.
  const btTransform pivot(btQuaternion::getIdentity(), btVector3(0, 0, -0.5f));
  boxPose = pivot * btTransform(btQuaternion(btVector3(1, 0, 0), -btAsin(0.05f))) * pivot.inverse() * boxPose;
  box.setWorldTransform(boxPose);
  write(nearSide);
  ps = points();
  EXPECT_EQ(ps.size(), 4u);
  EXPECT_FALSE(has(ps, -0.5f, 0.5f) || has(ps, 0.5f, 0.5f));
}

TEST_F(RestingPair, TwoFlatFacesInContactMakeOnePatch) {
  // The box's bottom corners, 1 m apart, lie farther apart than a quarter of its bounding radius: on a curved
  // surface each would be a patch of its own. On the box's flat bottom face resting on the slab's flat top
  // they are one support, as Bullet's box pair holds them in one manifold.
  std::vector<PairContact> corners{onTop(-0.5f, -0.5f, -1e-3f), onTop(0.5f, -0.5f, -1e-3f),
                                   onTop(0.5f, 0.5f, -1e-3f), onTop(-0.5f, 0.5f, -1e-3f)};
  write(corners);
  EXPECT_EQ(held().size(), 4u);
  for (PairContact& c : corners) c.flatSize = btSqrt(btScalar(2));  // the box face's diagonal
  ContactManifoldSet flat(&dispatcher);
  btManifoldResult result(&boxWrap, &slabWrap);
  flat.write(corners, &boxWrap, &slabWrap, &result);
  btManifoldArray array;
  flat.appendTo(array);
  ASSERT_EQ(array.size(), 1);
  EXPECT_EQ(array[0]->getNumContacts(), 4);
}

}  // namespace
}  // namespace gpucol
