#include "bullet/contact_manifold_set.h"

#include <BulletCollision/CollisionDispatch/btCollisionObject.h>
#include <BulletCollision/CollisionShapes/btCollisionShape.h>

#include <algorithm>
#include <cmath>
#include <utility>

namespace gpucol {
namespace {

// Contacts whose normals are within 30° share a manifold. A resting face gives normals within a few degrees
// of each other; a box in a right-angled corner gives normals 90° apart, and a curved body on a floor all
// nearly one. 30° keeps the first in one manifold and splits the second.
const btScalar kSameManifoldCos = btCos(SIMD_PI / 6);

// A manifold also covers one patch: contacts farther than this share of the smaller body's bounding radius
// from a manifold's first contact start another, as a convex piece of a compound shape would have its own.
// Bullet holds a manifold's points until they separate, but this pair's 4 places are chosen from the step's
// contacts alone, and a margin-free mesh gives contacts only where triangles cross: a ring lying on a floor,
// crossing it along one arc a step, lost its other arcs' points and rocked onto them (measured-results,
// "Why the pile of real meshes stays awake"). Each patch keeps its points while it has no new contact.
constexpr btScalar kPatchOfRadius = 0.25f;

// Two flat faces in contact make one patch, reaching over the smaller face's box diagonal (contact to the
// opposite corner, the farthest two contacts on it lie apart) and a quarter more, for contacts a little off
// the face (by their depth, or over the other face's rim).
constexpr btScalar kFlatFaceReach = 1.25f;

// The at most 4 contacts of one manifold's group that span the widest support: the deepest, the one farthest
// from it, the one farthest from the line through those two, and the one farthest on the line's other side.
// Bullet holds 4 points per manifold; fed a dozen contacts one by one, it keeps what arrival order and its
// replacement rule leave, which on a box face can be three corners on one side and nothing under the other
// half. Choosing the spread here first gives it the face's corners, which then stay from step to step.
std::vector<std::size_t> chooseSupport(const std::vector<PairContact>& contacts, const btVector3& normal) {
  std::vector<std::size_t> chosen;
  if (contacts.size() <= 4) {
    for (std::size_t i = 0; i < contacts.size(); ++i) chosen.push_back(i);
    return chosen;
  }
  const auto argmax = [&](auto score) {
    std::size_t best = 0;
    btScalar bestScore = score(contacts[0].pointOnB);
    for (std::size_t i = 1; i < contacts.size(); ++i) {
      const btScalar value = score(contacts[i].pointOnB);
      if (value > bestScore) best = i, bestScore = value;
    }
    return std::pair{best, bestScore};
  };
  std::size_t d = 0;
  for (std::size_t i = 1; i < contacts.size(); ++i) {
    if (contacts[i].distance < contacts[d].distance) d = i;
  }
  const btVector3 p0 = contacts[d].pointOnB;
  const std::size_t far = argmax([&](const btVector3& p) { return (p - p0).length2(); }).first;
  const btVector3 axis = contacts[far].pointOnB - p0;
  // Signed distance from the line p0-far, within the contact plane.
  const auto side = [&](const btVector3& p) { return axis.cross(p - p0).dot(normal); };
  const std::size_t third = argmax([&](const btVector3& p) { return btFabs(side(p)); }).first;
  const btScalar sign = side(contacts[third].pointOnB) >= 0 ? btScalar(1) : btScalar(-1);
  auto [fourth, fourthSide] = argmax([&](const btVector3& p) { return -sign * side(p); });
  if (fourthSide <= 0) {
    // Nothing on the other side: the point farthest from the three chosen.
    fourth = argmax([&](const btVector3& p) {
               return btMin(btMin((p - p0).length2(), (p - contacts[far].pointOnB).length2()),
                            (p - contacts[third].pointOnB).length2());
             }).first;
  }
  for (std::size_t i : {d, far, third, fourth}) {
    if (std::find(chosen.begin(), chosen.end(), i) == chosen.end()) chosen.push_back(i);
  }
  return chosen;
}

}  // namespace

std::vector<PairContact> swapSides(std::vector<PairContact> contacts) {
  for (PairContact& c : contacts) {
    // Body0's point is body1's point moved by the distance along body1's normal (Bullet's convention:
    // pointOnA = pointOnB + normalOnB * distance); the normal turns round.
    c.pointOnB = c.pointOnB + c.normalOnB * c.distance;
    c.normalOnB = -c.normalOnB;
    std::swap(c.partId0, c.partId1);
    std::swap(c.index0, c.index1);
  }
  return contacts;
}

ContactManifoldSet::~ContactManifoldSet() {
  for (const Group& g : m_groups) m_dispatcher->releaseManifold(g.manifold);
}

void ContactManifoldSet::write(const std::vector<PairContact>& contacts,
                               const btCollisionObjectWrapper* body0, const btCollisionObjectWrapper* body1,
                               btManifoldResult* result, btScalar speculativeDistance) {
  btPersistentManifold* const original = result->getPersistentManifold();
  const btMatrix3x3& body1Basis = body1->getWorldTransform().getBasis();
  std::vector<std::vector<PairContact>> byGroup(m_groups.size());
  // Patches are placed in the smaller body's frame, so that they turn and slide with it over the larger.
  btVector3 centre;
  btScalar radius0, radius1;
  body0->getCollisionShape()->getBoundingSphere(centre, radius0);
  body1->getCollisionShape()->getBoundingSphere(centre, radius1);
  const btTransform smallInverse = (radius0 <= radius1 ? body0 : body1)->getWorldTransform().inverse();
  const btScalar patch = kPatchOfRadius * btMin(radius0, radius1);
  // A contact's patch reaches a quarter of the smaller body's radius, or over the flat faces it lies on. A
  // shape without a size (or with a broken one) makes one patch of everything.
  const auto reach2Of = [&](const PairContact& contact) {
    const btScalar reach = btMax(patch, kFlatFaceReach * contact.flatSize);
    return reach > 0 && std::isfinite(reach) ? reach * reach : BT_INFINITY;
  };
  for (const PairContact& contact : contacts) {
    const btVector3 normalInBody1 = body1Basis.transpose() * contact.normalOnB;
    const btVector3 anchor = smallInverse * contact.pointOnB;
    const btScalar reach2 = reach2Of(contact);
    std::size_t group = 0;
    while (group < m_groups.size() &&
           (m_groups[group].normalInBody1.dot(normalInBody1) < kSameManifoldCos ||
            (m_groups[group].anchor - anchor).length2() > btMax(m_groups[group].reach2, reach2))) {
      ++group;
    }
    if (group == m_groups.size()) {
      btPersistentManifold* manifold =
          m_dispatcher->getNewManifold(body0->getCollisionObject(), body1->getCollisionObject());
      m_groups.push_back({manifold, normalInBody1, manifold->getContactBreakingThreshold(), anchor, reach2});
      byGroup.emplace_back();
    }
    byGroup[group].push_back(contact);
  }
  for (std::size_t g = 0; g < m_groups.size(); ++g) {
    // Bullet drops a point beyond the breaking threshold, both when it is added and when it is refreshed.
    m_groups[g].manifold->setContactBreakingThreshold(
        btMax(m_groups[g].breakingThreshold, speculativeDistance));
    result->setPersistentManifold(m_groups[g].manifold);
    const std::vector<std::size_t> chosen = chooseSupport(byGroup[g], body1Basis * m_groups[g].normalInBody1);
    // Bullet takes an added point for the held point nearest to it within the breaking threshold and
    // overwrites it. With a speculative pair's threshold raised to its whole reach (centimetres to
    // decimetres), chosen contacts would overwrite each other (the deepest, which bounds how far the bodies
    // may close, among them) and a rod end's corners would merge into one point, about which the rod then
    // turns into the other body. So each goes in with the threshold raised only to its own distance (Bullet's
    // own at least), and one within that distance of a contact already added is left out; the whole reach is
    // restored for the refresh below. At Bullet's own threshold (resting pairs) every chosen contact goes in.
    btPersistentManifold* const manifold = m_groups[g].manifold;
    const btScalar threshold = manifold->getContactBreakingThreshold();
    const btScalar own = m_groups[g].breakingThreshold;
    const bool raised = threshold > own;
    std::vector<btVector3> added;
    for (std::size_t i : chosen) {
      const PairContact& contact = byGroup[g][i];
      const btVector3 onA = contact.pointOnB + contact.normalOnB * contact.distance;
      const btScalar radius = btMax(own, contact.distance);
      if (raised && std::any_of(added.begin(), added.end(),
                                [&](const btVector3& p) { return (p - onA).length2() < radius * radius; })) {
        continue;
      }
      if (raised) {
        added.push_back(onA);
        manifold->setContactBreakingThreshold(radius);
      }
      // The triangles go into the point and gContactAddedCallback (Bullet swaps them with the bodies).
      result->setShapeIdentifiersA(contact.partId0, contact.index0);
      result->setShapeIdentifiersB(contact.partId1, contact.index1);
      result->addContactPoint(contact.normalOnB, contact.pointOnB, contact.distance);
    }
    manifold->setContactBreakingThreshold(threshold);
  }
  result->setShapeIdentifiersA(-1, -1);
  result->setShapeIdentifiersB(-1, -1);
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
