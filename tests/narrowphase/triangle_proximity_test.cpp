// proximityContacts against a reference distance: triangle pairs that do not cross, at random poses and in
// the resting configurations that margins are for (a face over a face, edges across edges).
#include "narrowphase/triangle_proximity.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "narrowphase/triangle_intersection.h"

namespace gpucol {
namespace {

using Vec = Eigen::Vector3d;
using Tri = std::array<Eigen::Vector3f, 3>;

// Reference: the distance from a point to a triangle, as the smaller of the distance to its plane (when the
// foot falls inside, by barycentric coordinates) and to each edge (the foot clamped onto the segment).
double pointSegment(const Vec& p, const Vec& a, const Vec& b) {
  const Vec ab = b - a;
  const double t = std::clamp((p - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
  return (p - (a + t * ab)).norm();
}

double pointTriangle(const Vec& p, const Vec (&t)[3]) {
  const Vec n = (t[1] - t[0]).cross(t[2] - t[0]).normalized();
  const Vec foot = p - n * n.dot(p - t[0]);
  // Barycentric coordinates of the foot from sub-triangle areas.
  const double total = (t[1] - t[0]).cross(t[2] - t[0]).dot(n);
  const double u = (t[1] - foot).cross(t[2] - foot).dot(n) / total;
  const double v = (t[2] - foot).cross(t[0] - foot).dot(n) / total;
  if (u >= 0 && v >= 0 && u + v <= 1) return std::fabs(n.dot(p - t[0]));
  return std::min({pointSegment(p, t[0], t[1]), pointSegment(p, t[1], t[2]), pointSegment(p, t[2], t[0])});
}

// The distance from a segment to a triangle, a convex function along the segment: golden-section search.
double segmentTriangle(const Vec& a, const Vec& b, const Vec (&t)[3]) {
  double lo = 0, hi = 1;
  const double g = (std::sqrt(5.0) - 1) / 2;
  for (int i = 0; i < 200; ++i) {
    const double m1 = hi - g * (hi - lo), m2 = lo + g * (hi - lo);
    if (pointTriangle(a + m1 * (b - a), t) < pointTriangle(a + m2 * (b - a), t)) hi = m2;
    else lo = m1;
  }
  return pointTriangle(a + 0.5 * (lo + hi) * (b - a), t);
}

// Two triangles that do not cross: their closest points include a point of an edge of one of them.
double referenceDistance(const Tri& a, const Tri& b) {
  Vec da[3], db[3];
  for (int i = 0; i < 3; ++i) da[i] = a[i].cast<double>(), db[i] = b[i].cast<double>();
  double best = std::numeric_limits<double>::infinity();
  for (int i = 0; i < 3; ++i) {
    best = std::min(best, segmentTriangle(da[i], da[(i + 1) % 3], db));
    best = std::min(best, segmentTriangle(db[i], db[(i + 1) % 3], da));
  }
  return best;
}

int contactsOf(const Tri& a, const Tri& b, float reach, TriangleContact (&out)[kMaxProximityContacts]) {
  const Eigen::Vector3f pa[3] = {a[0], a[1], a[2]};
  const Eigen::Vector3f pb[3] = {b[0], b[1], b[2]};
  return proximityContacts(pa, pb, reach, out);
}

bool crosses(const Tri& a, const Tri& b) { return trianglesIntersect(a[0], a[1], a[2], b[0], b[1], b[2]); }

Vec outward(const Tri& t) { return (t[1] - t[0]).cross(t[2] - t[0]).cast<double>().normalized(); }

// Bullet's points of a contact: on B (toWorld's rule) and on A = on B + normal * distance.
Vec pointOnB(const TriangleContact& c) {
  const Vec deepest = c.deepestPoint.cast<double>();
  return c.onFaceOfB ? Vec(deepest - c.normalOnB.cast<double>() * c.depth) : deepest;
}
Vec pointOnA(const TriangleContact& c) { return pointOnB(c) + c.normalOnB.cast<double>() * c.depth; }

Tri randomTriangle(std::mt19937_64& rng, const Vec& centre) {
  std::uniform_real_distribution<double> u(-1, 1);
  Tri t;
  for (auto& v : t) v = (centre + Vec(u(rng), u(rng), u(rng))).cast<float>();
  return t;
}

// Every contact's points lie on their triangles, the distance between them is its depth (in [0, reach)), the
// normal is a unit vector along them, and no contact is closer than the triangles are.
void expectConsistent(const Tri& a, const Tri& b, float reach, const TriangleContact* contacts, int count,
                      double distance) {
  Vec da[3], db[3];
  for (int i = 0; i < 3; ++i) da[i] = a[i].cast<double>(), db[i] = b[i].cast<double>();
  for (int k = 0; k < count; ++k) {
    const TriangleContact& c = contacts[k];
    EXPECT_GE(c.depth, 0.0f);
    EXPECT_LT(c.depth, reach);
    EXPECT_NEAR(c.normalOnB.cast<double>().norm(), 1.0, 1e-6);
    EXPECT_LT(pointTriangle(pointOnA(c), da), 1e-5);
    EXPECT_LT(pointTriangle(pointOnB(c), db), 1e-5);
    EXPECT_NEAR((pointOnA(c) - pointOnB(c)).norm(), c.depth, 1e-5);
    EXPECT_GE(c.depth, distance - 1e-5);
    // Each point on the other's outer side: the contact pushes the bodies apart, never through.
    EXPECT_GE(c.normalOnB.cast<double>().dot(outward(b)), -1e-5);
    EXPECT_LE(c.normalOnB.cast<double>().dot(outward(a)), 1e-5);
  }
}

TEST(TriangleProximity, RandomPairsAreConsistentWithTheReferenceDistance) {
  std::mt19937_64 rng(11);
  int withContacts = 0;
  for (int i = 0; i < 4000; ++i) {
    const Tri a = randomTriangle(rng, Vec::Zero());
    const Tri b = randomTriangle(rng, Vec(0.8, 0.6, 0.4));
    if (crosses(a, b)) continue;
    const double distance = referenceDistance(a, b);
    TriangleContact contacts[kMaxProximityContacts];
    const int count = contactsOf(a, b, 10.0f, contacts);
    expectConsistent(a, b, 10.0f, contacts, count, distance);
    withContacts += count > 0;
    if (::testing::Test::HasFailure()) {
      ADD_FAILURE() << "pair " << i;
      return;
    }
  }
  EXPECT_GT(withContacts, 500);
}

// A facing B across a gap, each entirely on the other's outer side: the closest points always give a contact,
// at the reference distance, and nothing beyond the reach.
TEST(TriangleProximity, FacingPairsGiveTheirClosestPoints) {
  std::mt19937_64 rng(12);
  std::uniform_real_distribution<double> u(-1, 1), gap(0.001, 0.3);
  int tested = 0;
  for (int i = 0; i < 4000 && tested < 1500; ++i) {
    Tri b = randomTriangle(rng, Vec::Zero()), a = randomTriangle(rng, Vec::Zero());
    for (auto& v : b) v.z() *= 0.2f;  // B roughly facing up, A above it facing down
    for (auto& v : a) v.z() = float(0.2 * v.z() + 0.5 + gap(rng));
    if (outward(b).z() < 0) std::swap(b[1], b[2]);
    if (outward(a).z() > 0) std::swap(a[1], a[2]);
    bool facing = true;
    for (int k = 0; k < 3; ++k) {
      facing &= outward(b).dot((a[k] - b[0]).cast<double>()) > 0;
      facing &= outward(a).dot((b[k] - a[0]).cast<double>()) > 0;
    }
    if (!facing) continue;
    ++tested;
    const double distance = referenceDistance(a, b);
    TriangleContact contacts[kMaxProximityContacts];
    const int count = contactsOf(a, b, float(distance) * 1.01f + 1e-4f, contacts);
    ASSERT_GT(count, 0) << "pair " << i << " at distance " << distance;
    expectConsistent(a, b, float(distance) * 1.01f + 1e-4f, contacts, count, distance);
    double closest = std::numeric_limits<double>::infinity();
    for (int k = 0; k < count; ++k) closest = std::min(closest, double(contacts[k].depth));
    EXPECT_NEAR(closest, distance, 1e-5 + 1e-5 * distance) << "pair " << i;
    EXPECT_EQ(contactsOf(a, b, float(distance) * 0.99f, contacts) > 0, false) << "pair " << i;
  }
  EXPECT_GE(tested, 1500);
}

// A small triangle lying flat over a large one: a contact at each of its corners, straight up, at the gap.
TEST(TriangleProximity, FaceOverFaceGivesEveryCorner) {
  const Tri b = {Eigen::Vector3f(-2, -2, 0), Eigen::Vector3f(2, -2, 0), Eigen::Vector3f(0, 2, 0)};
  const Tri a = {Eigen::Vector3f(-0.3f, -0.3f, 0.01f), Eigen::Vector3f(0, 0.3f, 0.01f),
                 Eigen::Vector3f(0.3f, -0.3f, 0.01f)};  // clockwise from above: facing down
  TriangleContact contacts[kMaxProximityContacts];
  const int count = contactsOf(a, b, 0.02f, contacts);
  ASSERT_EQ(count, 3);
  for (int k = 0; k < count; ++k) {
    EXPECT_NEAR(contacts[k].depth, 0.01f, 1e-6f);
    EXPECT_NEAR(contacts[k].normalOnB.z(), 1.0f, 1e-6f);
    EXPECT_NEAR(pointOnB(contacts[k]).z(), 0.0, 1e-6);
    EXPECT_NEAR((pointOnA(contacts[k]) - a[k].cast<double>()).norm(), 0.0, 1e-6);
  }
  EXPECT_EQ(contactsOf(a, b, 0.01f, contacts), 0);  // the gap is not within the reach
  EXPECT_EQ(contactsOf(a, b, 0.0f, contacts), 0);
}

// Two edges crossing at right angles a gap apart: one contact between them, along the gap.
TEST(TriangleProximity, EdgesAcrossEdges) {
  // B's top edge along x at z = 0, its face hanging below it (facing -y, a little up); A's bottom edge
  // nearly along y at z = 0.05, its face rising above it (facing +x, a little down).
  const Tri b = {Eigen::Vector3f(-1, 0, 0), Eigen::Vector3f(0, -0.3f, -1), Eigen::Vector3f(1, 0, 0)};
  const Tri a = {Eigen::Vector3f(0.1f, -1, 0.05f), Eigen::Vector3f(-0.1f, 1, 0.05f), Eigen::Vector3f(0, 0.2f, 1)};
  TriangleContact contacts[kMaxProximityContacts];
  const int count = contactsOf(a, b, 0.1f, contacts);
  ASSERT_EQ(count, 1);
  EXPECT_NEAR(contacts[0].depth, 0.05f, 1e-6f);
  EXPECT_NEAR(contacts[0].normalOnB.z(), 1.0f, 1e-5f);
  EXPECT_NEAR(pointOnB(contacts[0]).norm(), 0.0, 1e-5);
}

// The same crossing edges with what lies across B's edge (its wing): the contact along the gap stays where
// the surface folds away from it (a ridge), and goes where B's edge is flat or concave (the surface there
// leaves an edge no direction of its own) but stays when the wing is unknown.
TEST(TriangleProximity, EdgeContactsOnlyAlongDirectionsTheirFacesLeave) {
  const Eigen::Vector3f b[3] = {Eigen::Vector3f(-1, 0, 0), Eigen::Vector3f(0, -0.3f, -1),
                                Eigen::Vector3f(1, 0, 0)};
  const Eigen::Vector3f a[3] = {Eigen::Vector3f(0.1f, -1, 0.05f), Eigen::Vector3f(-0.1f, 1, 0.05f),
                                Eigen::Vector3f(0, 0.2f, 1)};
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const Eigen::Vector3f unknown(nan, nan, nan);
  const EdgeWings noneA{{unknown, unknown, unknown}};
  // B's top edge is its edge 2, from (1, 0, 0) to (-1, 0, 0).
  const auto count = [&](const Eigen::Vector3f& wing) {
    const EdgeWings wingsB{{unknown, unknown, wing}};
    TriangleContact out[kMaxProximityContacts];
    return proximityContacts(proximityFace(a), proximityFace(b), 0.1f, out, 0.1f, &noneA, &wingsB);
  };
  EXPECT_EQ(count(Eigen::Vector3f(0, 1, -0.3f)), 1);  // a ridge
  EXPECT_EQ(count(Eigen::Vector3f(0, 0.3f, 1)), 0);   // flat: the face goes on
  EXPECT_EQ(count(Eigen::Vector3f(0, -0.5f, 1)), 0);  // a valley
  EXPECT_EQ(count(unknown), 1);
}

// A point behind the other's face is inside that body: no proximity contact pulls it through.
TEST(TriangleProximity, NothingFromBehindAFace) {
  const Tri b = {Eigen::Vector3f(-2, -2, 0), Eigen::Vector3f(2, -2, 0), Eigen::Vector3f(0, 2, 0)};  // facing up
  const Tri below = {Eigen::Vector3f(-0.3f, -0.3f, -0.01f), Eigen::Vector3f(0.3f, -0.3f, -0.01f),
                     Eigen::Vector3f(0, 0.3f, -0.01f)};  // under B, facing up like it
  TriangleContact contacts[kMaxProximityContacts];
  EXPECT_EQ(contactsOf(below, b, 0.05f, contacts), 0);
  EXPECT_EQ(contactsOf(b, below, 0.05f, contacts), 0);
}

TEST(TriangleProximity, DegenerateTrianglesHaveNoContacts) {
  const Tri b = {Eigen::Vector3f(-2, -2, 0), Eigen::Vector3f(2, -2, 0), Eigen::Vector3f(0, 2, 0)};
  const Tri line = {Eigen::Vector3f(-0.3f, 0, 0.01f), Eigen::Vector3f(0, 0, 0.01f), Eigen::Vector3f(0.3f, 0, 0.01f)};
  TriangleContact contacts[kMaxProximityContacts];
  EXPECT_EQ(contactsOf(line, b, 0.05f, contacts), 0);
  EXPECT_EQ(contactsOf(b, line, 0.05f, contacts), 0);
}

// The float pre-test of the proximity pass (proximityCertainlyEmptyBranchFree) only rejects pairs that
// proximityContacts gives nothing for: random pairs over six orders of magnitude of scale, slivers among
// them, with reaches just below and above their separation along either plane, and B just behind A's face. It
// also rejects nearly every pair clearly beyond the reach, or the pass would gain nothing from it.
TEST(TriangleProximity, FloatPreTestRejectsOnlyPairsWithoutContacts) {
  std::mt19937_64 rng(29);
  std::uniform_real_distribution<double> u(-1, 1), unit(0, 1);
  // Separation of `of` in front of the plane of `plane` (unit normal), and how far it reaches behind it.
  const auto separation = [](const Tri& plane, const Tri& of, double& front, double& back) {
    const Vec p0 = plane[0].cast<double>();
    const Vec n =
        (plane[1] - plane[0]).cast<double>().cross((plane[2] - plane[0]).cast<double>()).normalized();
    front = std::numeric_limits<double>::infinity(), back = -front;
    for (const Eigen::Vector3f& v : of) {
      const double d = n.dot(v.cast<double>() - p0);
      front = std::min(front, d);
      back = std::max(back, d);
    }
  };
  int clearlyBeyond = 0, rejectedBeyond = 0, checked = 0;
  for (int i = 0; i < 20000; ++i) {
    const double scale = std::pow(10.0, -3 + 6 * unit(rng));
    const Vec offset = Vec(u(rng), u(rng), u(rng)) * scale * std::pow(10.0, 3 * unit(rng));
    Tri a = randomTriangle(rng, Vec::Zero()), b = randomTriangle(rng, Vec::Zero());
    if (i % 5 == 0) a[2] = (0.5f * (a[0] + a[1]) + 1e-4f * (a[2] - a[0]));  // a sliver
    // B lifted off A's plane by a random gap, sometimes a hair behind it instead.
    const Vec n = outward(a);
    double front, back;
    separation(a, b, front, back);
    const double lift = i % 3 == 0 ? -back - std::pow(10.0, -8 + 5 * unit(rng)) : -front + 0.3 * unit(rng);
    for (Eigen::Vector3f& v : b) v += (n * lift).cast<float>();
    for (Tri* t : {&a, &b}) {
      for (Eigen::Vector3f& v : *t) v = (v.cast<double>() * scale + offset).cast<float>();
    }
    if (crosses(a, b)) continue;
    double frontA, backA, frontB, backB;
    separation(b, a, frontA, backA);
    separation(a, b, frontB, backB);
    const double apart = std::max(frontA, frontB);
    const float reaches[] = {
        float(apart * (1 - 1e-7)), float(apart * (1 + 1e-7)), float(apart * 0.999), float(apart * 1.001),
        float(apart * 0.5),        float(1e-3 * scale),       float(scale)};
    for (const float reach : reaches) {
      if (!(reach > 0)) continue;
      ++checked;
      const bool empty = proximityCertainlyEmptyBranchFree(a[0], a[1], a[2], b[0], b[1], b[2], reach) != 0;
      TriangleContact contacts[kMaxProximityContacts];
      if (empty) {
        ASSERT_EQ(contactsOf(a, b, reach, contacts), 0) << "pair " << i << " reach " << reach;
      }
      if (i % 5 != 0 && apart > 1.01 * reach) {
        ++clearlyBeyond;
        rejectedBeyond += empty;
      }
    }
  }
  EXPECT_GT(checked, 50000);
  EXPECT_GT(clearlyBeyond, 10000);
  EXPECT_GT(rejectedBeyond, 0.99 * clearlyBeyond);
}

}  // namespace
}  // namespace gpucol
