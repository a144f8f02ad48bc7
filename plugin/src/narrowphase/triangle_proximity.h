#pragma once

#include <Eigen/Core>

#include "narrowphase/triangle_contact.h"

namespace gpucol {

/// The most contacts proximityContacts gives for one pair: each of the six vertices over the other's face, and
/// one edge-edge pair.
inline constexpr int kMaxProximityContacts = 7;

/// Contacts of two triangles that do not cross but come within `reach` of each other (the sum of the two
/// shapes' collision margins), so that bodies with margins rest `reach` apart instead of falling through the
/// gap. Written to `out`; returns how many (0 when `reach` <= 0 or either triangle is degenerate).
///
/// Triangles are counter-clockwise seen from outside, as for generateContact. The contacts are Bullet's
/// closest points between the two surfaces, each with a distance in [0, reach) in `depth`:
/// - every vertex of one triangle whose projection falls on the other's face and that lies on that face's
///   outer side (a face resting on a face gives a contact at each corner, not one arbitrary closest point);
/// - the pair's closest points when they lie on an edge of each, if each lies on the other triangle's outer
///   side.
/// A point behind the other's face is inside that body: a crossing (generateContact) answers for it, and a
/// proximity contact there would push the bodies through each other.
///
/// Contacts from `speculativeFrom` on (the margins' sum, below `reach`) are speculative: the bodies are not
/// that close yet. There, two edges closer than 1e-3 of the triangles' size (a box sliding on a floor) have
/// no reliable direction between their closest points, and a sideways one would push the box aside: their
/// contact takes the normal of the face whose plane has the other triangle wholly on its outer side, and
/// there is none when neither does.
///
/// Computed in double from the float inputs. The caller must only pass pairs that trianglesIntersect rejects.
int proximityContacts(const Eigen::Vector3f (&a)[3], const Eigen::Vector3f (&b)[3], float reach,
                      TriangleContact (&out)[kMaxProximityContacts], float speculativeFrom);
inline int proximityContacts(const Eigen::Vector3f (&a)[3], const Eigen::Vector3f (&b)[3], float reach,
                             TriangleContact (&out)[kMaxProximityContacts]) {
  return proximityContacts(a, b, reach, out, reach);
}

}  // namespace gpucol
