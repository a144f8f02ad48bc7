#pragma once

#include <Eigen/Core>
#include <optional>

namespace gpucol {

struct EdgeWings;

/// One contact between triangle A and triangle B, in Bullet's conventions and the frame of the inputs.
struct TriangleContact {
  /// A point shared by both triangles: the midpoint of their common segment on the planes' intersection
  /// line (coplanar pairs: the mean of the corners of their overlap polygon). A contact at another corner of
  /// the overlap (clipContactToOverlap): that corner moved halfway out.
  Eigen::Vector3f point;
  /// Unit normal on B pointing towards A: moving A along it by -depth separates the pair.
  Eigen::Vector3f normalOnB;
  /// Signed distance along normalOnB: <= 0; negative when penetrating, 0 when touching.
  float depth;
  /// True when normalOnB is B's face normal (A is pushed out of B's face, so A's deepest point is |depth| from
  /// `point` against the normal); false when it is minus A's (B is pushed out of A's face, and B's deepest point
  /// is |depth| from `point` along the normal).
  bool onFaceOfB = true;
  /// True when the triangles face the same way (nA . nB > 0). Surfaces that press on each other face opposite
  /// ways, or cross at a right angle where an edge dips into a face; same-facing triangles cross in the wedge
  /// where two nearly flush faces meet (the sides of two stacked boxes when the upper one tilts a little), and
  /// there the rule above finds the wedge's small sideways depth, not the bodies'. The mesh pair query uses
  /// such contacts only for a pair that has no other (deeply overlapping bodies, where every crossing may
  /// face the same way).
  bool sameFacing = false;
  /// The deepest vertex of the triangle that moves out (A's when onFaceOfB, else B's): where that body really
  /// is deepest, and a point fixed on it (a box's corner rather than the middle of its crossing edge), so that a
  /// solver's persistent contact stays put from step to step. Coplanar pairs: `point`.
  Eigen::Vector3f deepestPoint = Eigen::Vector3f::Zero();
};

/// Contact of two intersecting triangles (thesis §5.3.4); std::nullopt when none is kept.
///
/// Triangles are counter-clockwise seen from outside: the outward normal is (v1 - v0) x (v2 - v0).
/// For each triangle, the distance to move it along the other's outward normal until all its vertices are
/// on the outer side of the other's plane is measured; the smaller one wins:
///   A moves least along nB  ->  normalOnB =  nB, depth = -(A's distance);
///   B moves least along nA  ->  normalOnB = -nA, depth = -(B's distance)  (ties go to A moving along nB).
/// The contact is dropped when the triangles separate along their intersection line (direction nA x nB,
/// the overlap of the projections of the whole triangles on it) by less than the depth's magnitude: such a
/// pair says little about the bodies' collision, and neighbouring pairs give the contact (§5.3.4).
///
/// Returns std::nullopt when the triangles do not intersect (this function repeats Möller's test, so the
/// GPU style of calling it on every candidate pair is correct, thesis §5.4.1), when either triangle is
/// degenerate (see trianglesIntersect), or when the contact is dropped as above. It agrees with
/// trianglesIntersect: a contact is returned only for pairs that function reports as intersecting.
///
/// Coplanar pairs (every vertex of one in the other's plane, within trianglesIntersect's tolerance) have
/// no intersection line: both distances are 0, so the contact is normalOnB = nB, depth = 0 (resting
/// face-on-face contact), at the mean of the corners of the overlap polygon; coplanar triangles facing the
/// same way (flush faces side by side) give no contact.
std::optional<TriangleContact> generateContact(const Eigen::Vector3f (&a)[3], const Eigen::Vector3f (&b)[3]);

/// The most corners an overlap has besides its deepest: a triangle clipped by up to six sides has at most
/// nine.
inline constexpr int kMaxOverlapCorners = 8;

/// Takes `contact` (generateContact's answer for triangles a and b) over the part of the moving triangle that
/// lies over the other one, its overlap: the moving triangle clipped to the prism the other spans along the
/// contact's normal. The overlap's corner deepest below the other's plane becomes deepestPoint, its depth the
/// contact's; each other corner below the plane gives a contact of its own in `corners` (returns how many),
/// with the same normal, its own depth, and `point` that corner moved halfway out. A long triangle crossing a
/// small one (the faces of two crossed rods) thus gives contacts where the two overlap and as deep as they
/// overlap there, not at its far vertex, which can lie beyond the other body, and a face resting on a face
/// is held at every corner of their overlap that dips in (thesis §5.3.4 keeps the deepest vertex alone).
/// Where `flatWings` gives the far vertex across an edge of the other triangle (the one the moving triangle
/// leaves: B when onFaceOfB, else A; NaN elsewhere), that edge is a diagonal of a flat face, not the face's
/// end: the two far edges of the triangle across it bound the overlap instead, where the two triangles make
/// a convex quad (not at the inner corner of a flat face shaped like an L, where those edges would cut into
/// the triangle itself). Each side is moved out by 1e-5 of the other triangle's size, so that a face lying in
/// it (the sides of two boxes stacked flush) is not cut by rounding. Where `otherWings` gives the far vertex
/// across a convex edge of the other triangle (NaN elsewhere, flat diagonals included), a corner's depth is at
/// most how far it lies behind the face across that edge and 5% of the other triangle's size: a corner nearer
/// that face belongs to the pair it makes with that face. A contact that is not below 0 is left as it is.
int clipContactToOverlap(const Eigen::Vector3f (&a)[3], const Eigen::Vector3f (&b)[3],
                         const EdgeWings& flatWings, const EdgeWings& otherWings, TriangleContact& contact,
                         TriangleContact (&corners)[kMaxOverlapCorners]);

}  // namespace gpucol
