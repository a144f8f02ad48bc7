#include "bullet/contact_manifold_set.h"

#include <BulletCollision/CollisionDispatch/btCollisionObject.h>

#include <cmath>

namespace gpucol {
namespace {

// Contacts whose normals are within 30° share a manifold. A resting face gives normals within a few degrees
// of each other; a box in a right-angled corner gives normals 90° apart, and a curved body on a floor all
// nearly one. 30° keeps the first in one manifold and splits the second.
const btScalar kSameManifoldCos = btCos(SIMD_PI / 6);

}  // namespace

std::vector<PairContact> swapSides(std::vector<PairContact> contacts) {
  for (PairContact& c : contacts) {
    // Body0's point is body1's point moved by the distance along body1's normal (Bullet's convention:
    // pointOnA = pointOnB + normalOnB * distance); the normal turns round.
    c.pointOnB = c.pointOnB + c.normalOnB * c.distance;
    c.normalOnB = -c.normalOnB;
  }
  return contacts;
}

ContactManifoldSet::~ContactManifoldSet() {
  for (const Group& g : m_groups) m_dispatcher->releaseManifold(g.manifold);
}

void ContactManifoldSet::write(const std::vector<PairContact>& contacts, const btCollisionObjectWrapper* body0,
                               const btCollisionObjectWrapper* body1, btManifoldResult* result) {
  btPersistentManifold* const original = result->getPersistentManifold();
  const btMatrix3x3& body1Basis = body1->getWorldTransform().getBasis();
  for (const PairContact& contact : contacts) {
    const btVector3 normalInBody1 = body1Basis.transpose() * contact.normalOnB;
    Group* group = nullptr;
    for (Group& g : m_groups) {
      if (g.normalInBody1.dot(normalInBody1) >= kSameManifoldCos) {
        group = &g;
        break;
      }
    }
    if (group == nullptr) {
      btPersistentManifold* manifold =
          m_dispatcher->getNewManifold(body0->getCollisionObject(), body1->getCollisionObject());
      m_groups.push_back({manifold, normalInBody1});
      group = &m_groups.back();
    }
    result->setPersistentManifold(group->manifold);
    result->addContactPoint(contact.normalOnB, contact.pointOnB, contact.distance);
  }
  // Every manifold is refreshed, not only those that got a contact: points of a face that separated must go.
  std::size_t kept = 0;
  for (std::size_t i = 0; i < m_groups.size(); ++i) {
    result->setPersistentManifold(m_groups[i].manifold);
    result->refreshContactPoints();
    if (m_groups[i].manifold->getNumContacts() == 0) {
      m_dispatcher->releaseManifold(m_groups[i].manifold);
    } else {
      m_groups[kept++] = m_groups[i];
    }
  }
  m_groups.resize(kept);
  result->setPersistentManifold(original);
}

void ContactManifoldSet::appendTo(btManifoldArray& manifolds) const {
  for (const Group& g : m_groups) manifolds.push_back(g.manifold);
}

}  // namespace gpucol
