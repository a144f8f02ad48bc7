// gpucol::MeshShape as a Bullet btConcaveShape, each part against a reference:
// - getAabb: the brute-force box of the transformed vertices (double) and the |R|-carried vertex box;
// - processAllTriangles: a brute-force box test over every triangle;
// - calculateLocalInertia: analytic solids (box, sphere), the bounding-box fallback of an open mesh;
// - setLocalScaling: its refusals;
// - ray tests through a world: analytic shapes and a double-precision ray-triangle test;
// - resting heights in worlds: convex shapes on a mesh ground with stock Bullet, a compound holding a mesh
//   with gpucol's dispatchers, a real mesh on a btStaticPlaneShape and on a btBvhTriangleMeshShape floor.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <iostream>
#include <limits>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "bullet/mesh_pair_test_util.h"
#include "bullet/test_world.h"
#include "scenes/procedural_meshes.h"
#include "support/test_paths.h"

namespace gpucol::test {
namespace {

using Vec3 = Eigen::Vector3d;
constexpr double kInf = std::numeric_limits<double>::infinity();
// One unit in the last place of a float relative to its magnitude.
constexpr double kFloatEpsilon = 1.0 / (1 << 24);

Vec3 toEigen(const btVector3& v) {
  return Vec3(double(v.x()), double(v.y()), double(v.z()));
}

Eigen::Matrix3d toEigen(const btMatrix3x3& m) {
  Eigen::Matrix3d out;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) out(r, c) = double(m[r][c]);
  }
  return out;
}

// Vertex v in the shape's scaled local frame, exactly: a float times a float fits in a double.
Vec3 scaledVertex(const MeshShape& shape, std::uint32_t v) {
  const float* p = shape.mesh().positions().data() + 3 * std::size_t(v);
  const btVector3& s = shape.getLocalScaling();
  return Vec3(double(p[0]) * double(s.x()), double(p[1]) * double(s.y()), double(p[2]) * double(s.z()));
}

std::uint32_t corner(const MeshShape& shape, std::size_t triangle, int i) {
  return shape.mesh().indices()[3 * triangle + std::size_t(i)];
}

// Per-axis scaling with magnitudes log-uniform in [1/4, 4] and, when allowed, random signs.
btVector3 randomScaling(std::mt19937& rng, bool allowNegative) {
  std::uniform_real_distribution<float> logMagnitude(std::log(0.25f), std::log(4.0f));
  std::bernoulli_distribution negative(allowNegative ? 0.5 : 0.0);
  btVector3 s;
  for (int axis = 0; axis < 3; ++axis) s[axis] = (negative(rng) ? -1.0f : 1.0f) * std::exp(logMagnitude(rng));
  return s;
}

std::shared_ptr<const TriangleMesh> shared(TriangleMesh mesh) {
  return std::make_shared<const TriangleMesh>(std::move(mesh));
}

// -----------------------------------------------------------------------------------------------------------
// getAabb

// For random poses, scalings (negative too) and margins: the box contains every transformed vertex widened by
// the margin, and equals the |R|-carried box of the scaled vertices widened by the margin (Bullet's own
// convention for the margin, btTransformAabb), within float rounding.
void expectAabbIsCarriedVertexBox(MeshShape& shape, std::mt19937& rng, int poses) {
  const float size = largestSide(shape.mesh());
  std::uniform_real_distribution<float> marginDistribution(0.0f, 0.1f * size);
  for (int pose = 0; pose < poses; ++pose) {
    shape.setLocalScaling(pose == 0 ? btVector3(1, 1, 1) : randomScaling(rng, true));
    const float margin = pose % 3 == 0 ? 0.0f : marginDistribution(rng);
    shape.setMargin(margin);
    const btTransform transform =
        pose == 0 ? btTransform::getIdentity() : randomPose(rng, btVector3(0, 0, 0), 30 * size);
    btVector3 lo, hi;
    shape.getAabb(transform, lo, hi);

    const Eigen::Matrix3d rotation = toEigen(transform.getBasis());
    const Vec3 origin = toEigen(transform.getOrigin());
    Vec3 localLo = Vec3::Constant(kInf), localHi = Vec3::Constant(-kInf);
    Vec3 worldLo = Vec3::Constant(kInf), worldHi = Vec3::Constant(-kInf);
    for (std::size_t t = 0; t < shape.mesh().triangleCount(); ++t) {
      for (int i = 0; i < 3; ++i) {
        const Vec3 local = scaledVertex(shape, corner(shape, t, i));
        const Vec3 world = rotation * local + origin;
        localLo = localLo.cwiseMin(local);
        localHi = localHi.cwiseMax(local);
        worldLo = worldLo.cwiseMin(world);
        worldHi = worldHi.cwiseMax(world);
      }
    }
    const Vec3 centre = 0.5 * (localLo + localHi);
    const Vec3 halfExtent = 0.5 * (localHi - localLo) + Vec3::Constant(margin);
    const Vec3 carriedCentre = rotation * centre + origin;
    const Vec3 carriedExtent = rotation.cwiseAbs() * halfExtent;
    // getAabb works in float: a handful of roundings of numbers no larger than these magnitudes; 16 ulps of
    // their sum bounds them.
    const double tolerance =
        16 * kFloatEpsilon *
        (origin.cwiseAbs().maxCoeff() + 3 * centre.cwiseAbs().maxCoeff() + 3 * halfExtent.maxCoeff());
    for (int axis = 0; axis < 3; ++axis) {
      EXPECT_LE(double(lo[axis]), worldLo[axis] - margin + tolerance) << "pose " << pose << " axis " << axis;
      EXPECT_GE(double(hi[axis]), worldHi[axis] + margin - tolerance) << "pose " << pose << " axis " << axis;
      EXPECT_NEAR(double(lo[axis]), carriedCentre[axis] - carriedExtent[axis], tolerance)
          << "pose " << pose << " axis " << axis << ": not the |R|-carried box";
      EXPECT_NEAR(double(hi[axis]), carriedCentre[axis] + carriedExtent[axis], tolerance)
          << "pose " << pose << " axis " << axis << ": not the |R|-carried box";
    }
  }
}

TEST(MeshShapeAabb, IsTheCarriedVertexBoxOnProceduralMeshes) {
  std::mt19937 rng(31);
  MeshShape torus(shared(scenes::makeTorus(1.0f, 0.3f, 24, 12)));
  expectAabbIsCarriedVertexBox(torus, rng, 60);
  MeshShape lShape(shared(scenes::makeLShape(2.0f, 0.5f)));
  expectAabbIsCarriedVertexBox(lShape, rng, 60);
}

TEST(MeshShapeAabb, IsTheCarriedVertexBoxOnARealMesh) {
  GPUCOL_REQUIRE_MESH(path, "armadillo-2766.ply");
  std::mt19937 rng(32);
  MeshShape armadillo(shared(loadMesh(path)));
  expectAabbIsCarriedVertexBox(armadillo, rng, 60);
}

// -----------------------------------------------------------------------------------------------------------
// processAllTriangles

struct ReportedTriangle {
  int index;
  int part;
  std::array<btVector3, 3> corners;
};

class CollectTriangles : public btTriangleCallback {
 public:
  void processTriangle(btVector3* triangle, int partId, int triangleIndex) override {
    triangles.push_back({triangleIndex, partId, {triangle[0], triangle[1], triangle[2]}});
  }
  std::vector<ReportedTriangle> triangles;
};

struct QueryTally {
  std::size_t reported = 0;
  std::size_t ambiguous = 0;
  std::size_t touching = 0;  // decided exactly with a triangle box touching the query box on some axis
};

// One query box (in the scaled frame) against the brute force over every triangle. With `exact`, every
// triangle must be decided exactly (touching counts). Otherwise triangles whose box is within a
// float-rounding band of a query face may go either way: the shape maps the query into the mesh's unscaled
// frame as q / s in float, which moves each face by at most one rounding, 2^-24 |q| in the scaled frame,
// while the tree's boxes are the exact float vertex bounds. The band is 4 such roundings. With a power-of-two
// scaling q / s is exact and so is the answer, which is what `exact` tests.
void expectQueryMatchesBruteForce(const MeshShape& shape, const btVector3& queryLo, const btVector3& queryHi,
                                  bool exact, QueryTally& tally) {
  CollectTriangles callback;
  shape.processAllTriangles(&callback, queryLo, queryHi);

  const std::size_t triangleCount = shape.mesh().triangleCount();
  const btVector3& s = shape.getLocalScaling();
  std::vector<bool> reported(triangleCount, false);
  std::size_t twice = 0, badCoordinates = 0;
  for (const ReportedTriangle& r : callback.triangles) {
    ASSERT_GE(r.index, 0);
    ASSERT_LT(std::size_t(r.index), triangleCount);
    EXPECT_EQ(r.part, 0);
    if (reported[std::size_t(r.index)]) ++twice;
    reported[std::size_t(r.index)] = true;
    for (int i = 0; i < 3; ++i) {
      const float* p =
          shape.mesh().positions().data() + 3 * std::size_t(corner(shape, std::size_t(r.index), i));
      for (int axis = 0; axis < 3; ++axis) {
        // The product of two floats rounded once: what scaling ∘ vertex is in float.
        const float expected = float(double(p[axis]) * double(s[axis]));
        if (r.corners[i][axis] != expected) ++badCoordinates;
      }
    }
  }
  EXPECT_EQ(twice, 0u) << "triangles reported twice";
  EXPECT_EQ(badCoordinates, 0u) << "reported coordinates that are not scaling * vertex";

  std::size_t missing = 0, extra = 0;
  for (std::size_t t = 0; t < triangleCount; ++t) {
    Vec3 lo = Vec3::Constant(kInf), hi = Vec3::Constant(-kInf);
    for (int i = 0; i < 3; ++i) {
      lo = lo.cwiseMin(scaledVertex(shape, corner(shape, t, i)));
      hi = hi.cwiseMax(scaledVertex(shape, corner(shape, t, i)));
    }
    bool must = true, mustNot = false, touches = false;
    for (int axis = 0; axis < 3; ++axis) {
      const double band =
          exact ? 0.0
                : 4 * kFloatEpsilon *
                      std::max(std::abs(double(queryLo[axis])), std::abs(double(queryHi[axis])));
      // >= 0: the two intervals overlap or touch on this axis.
      const double overlap = std::min(double(queryHi[axis]) - lo[axis], hi[axis] - double(queryLo[axis]));
      if (overlap < band) must = false;
      if (overlap < -band) mustNot = true;
      if (overlap == 0) touches = true;
    }
    if (exact && must && touches) ++tally.touching;
    if (must && !reported[t]) ++missing;
    if (mustNot && reported[t]) ++extra;
    if (!must && !mustNot) ++tally.ambiguous;
  }
  EXPECT_EQ(missing, 0u) << "triangles whose box overlaps the query but were not reported";
  EXPECT_EQ(extra, 0u) << "triangles reported whose box misses the query";
  tally.reported += callback.triangles.size();
}

// Random query boxes of many sizes around the scaled mesh; random scalings (exact: powers of two) with
// negative components; and query faces placed exactly on vertex coordinates so that touching boxes occur.
void expectQueriesMatchBruteForce(MeshShape& shape, std::mt19937& rng, int scalings, int queriesPerScaling) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::uniform_int_distribution<int> powerOfTwo(-2, 2);
  std::uniform_int_distribution<std::uint32_t> vertexIndex(0, std::uint32_t(shape.mesh().vertexCount() - 1));
  QueryTally tally;
  for (int scaling = 0; scaling < scalings; ++scaling) {
    const bool exact = scaling % 2 == 0;
    btVector3 s = randomScaling(rng, true);
    if (exact) {
      for (int axis = 0; axis < 3; ++axis)
        s[axis] = std::copysign(std::ldexp(1.0f, powerOfTwo(rng)), s[axis]);
    }
    shape.setLocalScaling(s);
    Vec3 meshLo = Vec3::Constant(kInf), meshHi = Vec3::Constant(-kInf);
    for (std::uint32_t v = 0; v < shape.mesh().vertexCount(); ++v) {
      meshLo = meshLo.cwiseMin(scaledVertex(shape, v));
      meshHi = meshHi.cwiseMax(scaledVertex(shape, v));
    }
    const double diagonal = (meshHi - meshLo).norm();

    // Everything: every triangle once.
    {
      CollectTriangles all;
      shape.processAllTriangles(&all, btVector3(-1e30f, -1e30f, -1e30f), btVector3(1e30f, 1e30f, 1e30f));
      std::set<int> distinct;
      for (const ReportedTriangle& r : all.triangles) distinct.insert(r.index);
      EXPECT_EQ(all.triangles.size(), shape.mesh().triangleCount());
      EXPECT_EQ(distinct.size(), shape.mesh().triangleCount());
    }

    for (int query = 0; query < queriesPerScaling; ++query) {
      btVector3 lo, hi;
      if (exact && query % 2 == 1) {
        // Faces on the coordinates of random vertices: in float exactly, since s is a power of two.
        for (int axis = 0; axis < 3; ++axis) {
          const double a = scaledVertex(shape, vertexIndex(rng))[axis];
          const double b = scaledVertex(shape, vertexIndex(rng))[axis];
          lo[axis] = btScalar(std::min(a, b));
          hi[axis] = btScalar(std::max(a, b));
        }
      } else {
        for (int axis = 0; axis < 3; ++axis) {
          const double centre = meshLo[axis] + (meshHi[axis] - meshLo[axis]) * (1.2 * unit(rng) - 0.1);
          const double half = diagonal * std::exp(std::log(1e-3) + unit(rng) * std::log(300.0));
          lo[axis] = btScalar(centre - half);
          hi[axis] = btScalar(centre + half);
        }
      }
      expectQueryMatchesBruteForce(shape, lo, hi, exact, tally);
      // The same query twice gives the same triangles in the same order.
      CollectTriangles first, second;
      shape.processAllTriangles(&first, lo, hi);
      shape.processAllTriangles(&second, lo, hi);
      ASSERT_EQ(first.triangles.size(), second.triangles.size());
      for (std::size_t i = 0; i < first.triangles.size(); ++i) {
        EXPECT_EQ(first.triangles[i].index, second.triangles[i].index);
      }
    }
  }
  std::cout << shape.mesh().name() << ": " << tally.reported << " triangles reported, " << tally.touching
            << " of them touching the query exactly, " << tally.ambiguous << " within the rounding band\n";
  EXPECT_GT(tally.reported, 0u);
  EXPECT_GT(tally.touching, 0u) << "the exact queries should include touching boxes";
}

TEST(MeshShapeProcessAllTriangles, MatchesBruteForceOnProceduralMeshes) {
  std::mt19937 rng(41);
  MeshShape torus(shared(scenes::makeTorus(1.0f, 0.3f, 32, 16)));
  expectQueriesMatchBruteForce(torus, rng, 8, 40);
  // Leaves of several triangles go through their entries' own boxes.
  Config config;
  config.trianglesPerLeaf = 4;
  MeshShape box(shared(scenes::makeBox(1.0f, 0.5f, 2.0f, 6)), config);
  expectQueriesMatchBruteForce(box, rng, 8, 40);
}

TEST(MeshShapeProcessAllTriangles, MatchesBruteForceOnARealMesh) {
  GPUCOL_REQUIRE_MESH(path, "armadillo-2766.ply");
  std::mt19937 rng(42);
  MeshShape armadillo(shared(loadMesh(path)));
  expectQueriesMatchBruteForce(armadillo, rng, 8, 40);
}

// -----------------------------------------------------------------------------------------------------------
// calculateLocalInertia

// Box of sides a, b, c: I = m/12 (b² + c², a² + c², a² + b²). The inertia comes from double integrals stored
// as floats, hence the 1e-5 relative tolerance.
void expectBoxInertia(const btVector3& inertia, btScalar mass, double a, double b, double c) {
  const double expected[3] = {mass / 12.0 * (b * b + c * c), mass / 12.0 * (a * a + c * c),
                              mass / 12.0 * (a * a + b * b)};
  for (int axis = 0; axis < 3; ++axis) {
    EXPECT_NEAR(double(inertia[axis]), expected[axis], 1e-5 * expected[axis]) << "axis " << axis;
  }
}

TEST(MeshShapeInertia, BoxMatchesAnalyticWithScaling) {
  for (int subdivisions : {1, 3}) {
    MeshShape box(shared(scenes::makeBox(0.5f, 1.0f, 1.5f, subdivisions)));
    btVector3 inertia;
    box.calculateLocalInertia(2.0f, inertia);
    expectBoxInertia(inertia, 2.0f, 1.0, 2.0, 3.0);
    // Non-uniform scaling, one component negative (a mirror, whose winding turns inward).
    box.setLocalScaling(btVector3(2.0f, 0.5f, -3.0f));
    box.calculateLocalInertia(5.0f, inertia);
    expectBoxInertia(inertia, 5.0f, 2.0, 1.0, 9.0);
    box.setLocalScaling(btVector3(-0.25f, -2.0f, 1.5f));
    box.calculateLocalInertia(0.5f, inertia);
    expectBoxInertia(inertia, 0.5f, 0.25, 4.0, 4.5);
  }
}

// flatFaceSize: the diagonal of a triangle's flat face, scaled with the shape; a sphere's triangle is its
// own.
TEST(MeshShapeFlatFaces, ABoxTriangleSpansItsScaledSide) {
  MeshShape box(shared(scenes::makeBox(0.5f, 1.0f, 1.5f, 3)));
  box.setLocalScaling(btVector3(2.0f, -0.5f, 1.0f));  // sides 2 x 1 x 3 after scaling
  const btScalar sides[3] = {2, 1, 3};
  const float* soup = box.triangleSoup();
  for (std::uint32_t t = 0; t < box.mesh().triangleCount(); ++t) {
    // The side's normal axis: the one on which the triangle's three vertices agree.
    int normalAxis = 0;
    for (int c = 0; c < 3; ++c) {
      if (soup[9 * t + c] == soup[9 * t + 3 + c] && soup[9 * t + c] == soup[9 * t + 6 + c]) normalAxis = c;
    }
    const btScalar a = sides[(normalAxis + 1) % 3], b = sides[(normalAxis + 2) % 3];
    EXPECT_NEAR(box.flatFaceSize(t), btSqrt(a * a + b * b), 1e-5f) << t;
  }
  MeshShape sphere(shared(scenes::makeIcosphere(1.0f, 2)));
  for (std::uint32_t t = 0; t < sphere.mesh().triangleCount(); ++t)
    EXPECT_LT(sphere.flatFaceSize(t), 0.5f) << t;
}

TEST(MeshShapeInertia, IcosphereIsASolidSphereWithinItsTessellation) {
  // The icosphere lies between the sphere of its vertices (radius r) and the sphere touching its nearest face
  // plane (radius a). For a solid B with ball(a) ⊂ B ⊂ ball(r) and a² >= 3/5 r², the mean of |x|² over B lies
  // in [3/5 a², 3/5 r²] (points added to ball(a) have |x|² >= a², points removed from ball(r) have
  // |x|² >= a² >= 3/5 r²), and the icosahedral symmetry makes the tensor isotropic, so each moment lies in
  // [2/5 m a², 2/5 m r²]: that is the tessellation's error.
  const float radius = 1.0f;
  const auto mesh = shared(scenes::makeIcosphere(radius, 3));
  for (float scale : {1.0f, 0.7f, -2.0f}) {
    MeshShape sphere(mesh);
    sphere.setLocalScaling(btVector3(scale, scale, scale));
    double r = 0, a = kInf;
    for (std::uint32_t v = 0; v < mesh->vertexCount(); ++v) r = std::max(r, scaledVertex(sphere, v).norm());
    for (std::size_t t = 0; t < mesh->triangleCount(); ++t) {
      const Vec3 p0 = scaledVertex(sphere, corner(sphere, t, 0)),
                 p1 = scaledVertex(sphere, corner(sphere, t, 1)),
                 p2 = scaledVertex(sphere, corner(sphere, t, 2));
      a = std::min(a, std::abs((p1 - p0).cross(p2 - p0).normalized().dot(p0)));
    }
    ASSERT_GE(a * a, 0.6 * r * r);
    const btScalar mass = 3.0f;
    btVector3 inertia;
    sphere.calculateLocalInertia(mass, inertia);
    const double lowest = 0.4 * mass * a * a, highest = 0.4 * mass * r * r;
    std::cout << "icosphere scale " << scale << ": inertia " << inertia[0] << " " << inertia[1] << " "
              << inertia[2] << " within [" << lowest << ", " << highest << "] (2/5 m r^2 = " << highest
              << ")\n";
    for (int axis = 0; axis < 3; ++axis) {
      EXPECT_GE(double(inertia[axis]), lowest * (1 - 1e-5)) << "axis " << axis;
      EXPECT_LE(double(inertia[axis]), highest * (1 + 1e-5)) << "axis " << axis;
      EXPECT_NEAR(double(inertia[axis]), double(inertia[0]), 1e-5 * highest)
          << "not isotropic, axis " << axis;
    }
  }
}

TEST(MeshShapeInertia, OpenMeshGetsItsBoundingBoxInertiaAndAWarningOnce) {
  // A unique name per run: the warning is said once per process and name.
  static int run = 0;
  const TriangleMesh box = scenes::makeBox(0.5f, 1.0f, 1.5f);
  std::vector<std::uint32_t> indices(box.indices().begin() + 3, box.indices().end());  // one triangle removed
  MeshShape open(shared(
      TriangleMesh::fromArrays(box.positions(), std::move(indices), "open box " + std::to_string(run++))));
  ASSERT_GT(open.mesh().report().boundaryEdges, 0u);
  open.setLocalScaling(btVector3(1.0f, -2.0f, 0.5f));
  btVector3 first, second;
  testing::internal::CaptureStderr();
  EXPECT_NO_THROW(open.calculateLocalInertia(4.0f, first));
  EXPECT_NO_THROW(open.calculateLocalInertia(4.0f, second));
  const std::string warnings = testing::internal::GetCapturedStderr();
  // The bounding box of the scaled mesh: the removed triangle's vertices are shared with others, so the box
  // keeps its sides 1 × 4 × 1.5.
  expectBoxInertia(first, 4.0f, 1.0, 4.0, 1.5);
  EXPECT_EQ(first, second);
  std::size_t said = 0;
  for (std::size_t at = warnings.find("bounding box"); at != std::string::npos;
       at = warnings.find("bounding box", at + 1)) {
    ++said;
  }
  EXPECT_EQ(said, 1u) << "stderr was: " << warnings;
}

TEST(MeshShapeInertia, InertiaOutsideFloatsNormalRangeIsRefused) {
  MeshShape box(shared(scenes::makeBox(0.5f, 0.5f, 0.5f)));
  const auto refusal = [&](btScalar mass) {
    btVector3 inertia(7, 7, 7);
    try {
      box.calculateLocalInertia(mass, inertia);
    } catch (const MeshError& e) {
      EXPECT_EQ(inertia, btVector3(7, 7, 7)) << "left untouched";
      return std::string(e.what());
    }
    ADD_FAILURE() << "no MeshError for mass " << mass << ", inertia " << inertia[0];
    return std::string();
  };
  // At scale 1e-20 the inertia of a unit mass was 1.7e-41, a denormal: the body turned NaN after one step.
  box.setLocalScaling(btVector3(1e-20f, 1e-20f, 1e-20f));
  const std::string tiny = refusal(1);
  EXPECT_NE(tiny.find("the inertia about x for mass 1 at local scaling (1e-20, 1e-20, 1e-20) is 1.66667e-41, "
                      "outside float's normal range (1.17549e-38 to 3.40282e+38)"),
            std::string::npos)
      << tiny;
  // Large scales are refused by setLocalScaling beyond 1e18; within it a large mass still overflows.
  box.setLocalScaling(btVector3(1e17f, 1e17f, 1e17f));
  EXPECT_NE(refusal(1e10f).find("outside float's normal range"), std::string::npos);
  btVector3 inertia;
  box.calculateLocalInertia(1, inertia);
  expectBoxInertia(inertia, 1, 1e17, 1e17, 1e17);
  box.setLocalScaling(btVector3(1e-15f, 2e-15f, 3e-15f));
  box.calculateLocalInertia(1, inertia);
  expectBoxInertia(inertia, 1, 1e-15, 2e-15, 3e-15);
  // A static body's mass 0 gives 0; a mass that is negative or not finite is refused.
  box.calculateLocalInertia(0, inertia);
  EXPECT_EQ(inertia, btVector3(0, 0, 0));
  EXPECT_NE(refusal(-1).find("calculateLocalInertia needs a finite mass >= 0, got -1"), std::string::npos);
  EXPECT_NE(refusal(std::numeric_limits<btScalar>::infinity()).find("needs a finite mass"),
            std::string::npos);
  // The bounding-box inertia of an open mesh is checked the same way.
  static int run = 0;
  const TriangleMesh closed = scenes::makeBox(0.5f, 0.5f, 0.5f);
  std::vector<std::uint32_t> indices(closed.indices().begin() + 3, closed.indices().end());
  MeshShape open(shared(TriangleMesh::fromArrays(closed.positions(), std::move(indices),
                                                 "open tiny box " + std::to_string(run++))));
  open.setLocalScaling(btVector3(1e-20f, 1e-20f, 1e-20f));
  testing::internal::CaptureStderr();
  EXPECT_THROW(open.calculateLocalInertia(1, inertia), MeshError);
  testing::internal::GetCapturedStderr();
}

// -----------------------------------------------------------------------------------------------------------
// setLocalScaling

TEST(MeshShapeScaling, RefusesRatiosAboveTheLimitDenormalsAndMeshesBeyondTheCoordinateLimit) {
  MeshShape shape(shared(scenes::makeBox(1, 1, 1)));
  const auto refusal = [&](const btVector3& scaling) {
    const btVector3 before = shape.getLocalScaling();
    try {
      shape.setLocalScaling(scaling);
    } catch (const MeshError& e) {
      EXPECT_EQ(shape.getLocalScaling(), before);
      return std::string(e.what());
    }
    ADD_FAILURE() << "no MeshError";
    return std::string();
  };
  // Ratios between axes up to 1e5 are answered (checked against the brute force in tests/stress); beyond, the
  // float transforms of the pair query gave wrong pairs, so they are refused.
  shape.setLocalScaling(btVector3(1e5f, 1, -1));
  shape.setLocalScaling(btVector3(-4, 4.0f / 65536, 1));
  EXPECT_EQ(
      refusal(btVector3(1e6f, 1, 1)),
      "MeshShape 'box': local scaling (1e+06, 1, 1) refused: its components differ in magnitude by 1e+06, "
      "more than the limit of 100000");
  EXPECT_NE(refusal(btVector3(1, 1, -9.99e-6f)).find("differ in magnitude by 100100"), std::string::npos);
  EXPECT_NE(
      refusal(btVector3(1e-40f, 1e-40f, 1e-40f)).find("it must be finite and non-zero (a normal float)"),
      std::string::npos);
  // The scaled mesh must stay within TriangleMesh::kMaxCoordinate, as a mesh must.
  shape.setLocalScaling(btVector3(1e18f, 1e18f, 1e18f));
  EXPECT_EQ(refusal(btVector3(1e20f, 1e20f, 1e20f)),
            "MeshShape 'box': local scaling (1e+20, 1e+20, 1e+20) refused: the scaled mesh reaches 1e+20 on "
            "axis 0, "
            "beyond gpucol's limit of +-1e+18");
  btVector3 lo, hi;
  shape.getAabb(btTransform::getIdentity(), lo, hi);
  EXPECT_EQ(hi, btVector3(1e18f, 1e18f, 1e18f));
  EXPECT_EQ(lo, -hi);
}

TEST(MeshShapeScaling, RefusesZeroNanAndInfinityAndKeepsThePreviousScaling) {
  MeshShape shape(shared(scenes::makeBox(1, 1, 1)));
  const btVector3 previous(2.0f, -0.5f, 3.0f);
  shape.setLocalScaling(previous);
  const float bad[] = {0.0f, -0.0f, std::numeric_limits<float>::quiet_NaN(),
                       std::numeric_limits<float>::infinity(), -std::numeric_limits<float>::infinity()};
  for (float value : bad) {
    for (int axis = 0; axis < 3; ++axis) {
      btVector3 scaling(1, 1, 1);
      scaling[axis] = value;
      EXPECT_THROW(shape.setLocalScaling(scaling), MeshError) << "value " << value << " on axis " << axis;
      EXPECT_EQ(shape.getLocalScaling(), previous);
    }
  }
  // The shape still answers with the previous scaling.
  btVector3 lo, hi;
  shape.getAabb(btTransform::getIdentity(), lo, hi);
  EXPECT_EQ(hi, btVector3(2.0f, 0.5f, 3.0f));
  EXPECT_EQ(lo, btVector3(-2.0f, -0.5f, -3.0f));
}

// -----------------------------------------------------------------------------------------------------------
// Ray tests

struct RayTriangle {
  bool parallel = true;
  double t = 0;        // fraction along the segment
  double minBary = 0;  // smallest barycentric coordinate of the plane crossing
};

// Möller–Trumbore in double.
RayTriangle rayTriangle(const Vec3& from, const Vec3& to, const TriangleD& triangle) {
  RayTriangle out;
  const Vec3 d = to - from, e1 = triangle[1] - triangle[0], e2 = triangle[2] - triangle[0];
  const Vec3 p = d.cross(e2);
  const double det = e1.dot(p);
  if (std::abs(det) <= 1e-12 * d.norm() * e1.norm() * e2.norm()) return out;
  const Vec3 s = from - triangle[0], q = s.cross(e1);
  const double u = s.dot(p) / det, v = d.dot(q) / det;
  out.parallel = false;
  out.t = e2.dot(q) / det;
  out.minBary = std::min({u, v, 1 - u - v});
  return out;
}

// Every hit of the segment on the shape's triangles (fractions, ascending) by brute force in double, or false
// when some triangle is too close to call: Bullet's float ray test accepts crossings up to 1e-4 outside a
// triangle (btTriangleRaycastCallback's edge tolerance), so rays within 1e-3 of an edge or an end are
// redrawn.
bool bruteForceHits(const MeshShape& shape, const btTransform& transform, const Vec3& from, const Vec3& to,
                    std::vector<double>& fractions, std::vector<Vec3>& normals) {
  fractions.clear();
  normals.clear();
  std::vector<std::pair<double, Vec3>> hits;
  for (std::uint32_t t = 0; t < shape.mesh().triangleCount(); ++t) {
    const TriangleD triangle = worldTriangle(shape, transform, t);
    const RayTriangle r = rayTriangle(from, to, triangle);
    if (r.parallel || r.t < -1e-3 || r.t > 1 + 1e-3 || r.minBary < -1e-3) continue;
    if (r.t < 1e-3 || r.t > 1 - 1e-3 || r.minBary < 1e-3) return false;
    hits.push_back({r.t, (triangle[1] - triangle[0]).cross(triangle[2] - triangle[0]).normalized()});
  }
  std::sort(hits.begin(), hits.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  for (const auto& h : hits) {
    fractions.push_back(h.first);
    normals.push_back(h.second);
  }
  return true;
}

btVector3 toBullet(const Vec3& v) {
  return btVector3(btScalar(v.x()), btScalar(v.y()), btScalar(v.z()));
}

// Bullet's float ray test against the brute force: same hits (AllHits) and the nearest one (Closest), whose
// normal faces the ray. Returns the closest callback for the caller's analytic checks.
btCollisionWorld::ClosestRayResultCallback expectRayMatchesBruteForce(TestWorld& w, const btRigidBody* body,
                                                                      const Vec3& from, const Vec3& to,
                                                                      const std::vector<double>& fractions) {
  btCollisionWorld::ClosestRayResultCallback closest(toBullet(from), toBullet(to));
  w.world().rayTest(toBullet(from), toBullet(to), closest);
  btCollisionWorld::AllHitsRayResultCallback all(toBullet(from), toBullet(to));
  w.world().rayTest(toBullet(from), toBullet(to), all);

  // Float coordinates of size ~10 along a segment of length ~20: fractions good to a few 1e-7.
  constexpr double kFractionTolerance = 1e-5;
  EXPECT_EQ(closest.hasHit(), !fractions.empty());
  if (!fractions.empty()) {
    EXPECT_EQ(closest.m_collisionObject, body);
    EXPECT_NEAR(double(closest.m_closestHitFraction), fractions.front(), kFractionTolerance);
  }
  std::vector<double> allFractions;
  for (int i = 0; i < all.m_hitFractions.size(); ++i) {
    allFractions.push_back(double(all.m_hitFractions[i]));
    EXPECT_EQ(all.m_collisionObjects[i], body);
    // The normal faces the ray's start (Bullet flips back-face normals).
    EXPECT_LT(toEigen(all.m_hitNormalWorld[i]).dot(to - from), 0.0);
  }
  std::sort(allFractions.begin(), allFractions.end());
  EXPECT_EQ(allFractions.size(), fractions.size());
  for (std::size_t i = 0; i < std::min(allFractions.size(), fractions.size()); ++i) {
    EXPECT_NEAR(allFractions[i], fractions[i], kFractionTolerance) << "hit " << i;
  }
  return closest;
}

Vec3 randomUnit(std::mt19937& rng) {
  std::normal_distribution<double> gauss;
  return Vec3(gauss(rng), gauss(rng), gauss(rng)).normalized();
}

TEST(MeshShapeRayTest, HitsARotatedScaledBoxAtTheAnalyticPoint) {
  TestWorld w(DispatchKind::Stock);
  const Vec3 half(0.5, 1.0, 0.75);
  auto shape = meshShape(scenes::makeBox(float(half.x()), float(half.y()), float(half.z())));
  const btVector3 scaling(1.5f, -0.5f, 2.0f);
  shape->setLocalScaling(scaling);
  std::mt19937 rng(51);
  const btTransform transform = randomPose(rng, btVector3(2, 1, -3), 1.0f);
  const btRigidBody* body = w.add(shape, 0, transform);
  const Eigen::Matrix3d rotation = toEigen(transform.getBasis());
  const Vec3 origin = toEigen(transform.getOrigin());
  const Vec3 scaledHalf = half.cwiseProduct(toEigen(scaling).cwiseAbs());
  std::uniform_real_distribution<double> inside(-0.8, 0.8);
  std::vector<double> fractions;
  std::vector<Vec3> normals;

  int hits = 0;
  for (int ray = 0; ray < 40; ++ray) {
    // Through a random point inside the box: enters through one face and leaves through another.
    const Vec3 localTarget(inside(rng) * scaledHalf.x(), inside(rng) * scaledHalf.y(),
                           inside(rng) * scaledHalf.z());
    const Vec3 localDirection = randomUnit(rng);
    const Vec3 localFrom = localTarget - 10 * localDirection, localTo = localTarget + 10 * localDirection;
    const Vec3 from = rotation * localFrom + origin, to = rotation * localTo + origin;
    if (!bruteForceHits(*shape, transform, from, to, fractions, normals)) continue;
    ++hits;
    // The analytic entry: slabs in the box's frame; the entry face is the slab entered last.
    double entry = -kInf;
    int entryAxis = 0;
    for (int axis = 0; axis < 3; ++axis) {
      const double d = localTo[axis] - localFrom[axis];
      const double t0 = (-scaledHalf[axis] - localFrom[axis]) / d,
                   t1 = (scaledHalf[axis] - localFrom[axis]) / d;
      if (std::min(t0, t1) > entry) {
        entry = std::min(t0, t1);
        entryAxis = axis;
      }
    }
    Vec3 localNormal = Vec3::Zero();
    localNormal[entryAxis] = localTo[entryAxis] > localFrom[entryAxis] ? -1 : 1;
    const Vec3 normal = rotation * localNormal;
    const Vec3 point = from + entry * (to - from);

    ASSERT_EQ(fractions.size(), 2u) << "a ray through a box's inside crosses two faces";
    EXPECT_NEAR(fractions.front(), entry, 1e-9);
    const auto closest = expectRayMatchesBruteForce(w, body, from, to, fractions);
    ASSERT_TRUE(closest.hasHit());
    EXPECT_NEAR(double(closest.m_closestHitFraction), entry, 1e-5);
    EXPECT_GT(toEigen(closest.m_hitNormalWorld).normalized().dot(normal), 1 - 1e-5);
    EXPECT_LT((toEigen(closest.m_hitPointWorld) - point).norm(), 1e-4);
  }
  EXPECT_GE(hits, 30);

  // Beside the box: lines in a plane 5% outside a face, in any direction within that plane.
  for (int ray = 0; ray < 40; ++ray) {
    const int axis = ray % 3;
    const Vec3 u = randomUnit(rng);
    Vec3 localDirection = u;
    localDirection[axis] = 0;
    localDirection.normalize();
    Vec3 localPoint(inside(rng) * scaledHalf.x(), inside(rng) * scaledHalf.y(), inside(rng) * scaledHalf.z());
    localPoint[axis] = (ray % 2 == 0 ? 1.05 : -1.05) * scaledHalf[axis];
    const Vec3 from = rotation * (localPoint - 10 * localDirection) + origin;
    const Vec3 to = rotation * (localPoint + 10 * localDirection) + origin;
    ASSERT_TRUE(bruteForceHits(*shape, transform, from, to, fractions, normals));
    EXPECT_TRUE(fractions.empty());
    const auto closest = expectRayMatchesBruteForce(w, body, from, to, fractions);
    EXPECT_FALSE(closest.hasHit());
  }
}

TEST(MeshShapeRayTest, HitsAnIcosphereBetweenItsInnerAndOuterSpheres) {
  TestWorld w(DispatchKind::Stock);
  const auto mesh = shared(scenes::makeIcosphere(1.0f, 3));
  auto shape = std::make_shared<MeshShape>(mesh);
  shape->setLocalScaling(btVector3(1.5f, 1.5f, 1.5f));
  std::mt19937 rng(52);
  const btTransform transform = randomPose(rng, btVector3(-1, 2, 4), 1.0f);
  const btRigidBody* body = w.add(shape, 0, transform);
  const Vec3 centre = toEigen(transform.getOrigin());
  // Radii of the vertices' sphere (r) and of the nearest face plane's sphere (a), in double from the mesh.
  double r = 0, a = kInf;
  for (std::uint32_t t = 0; t < mesh->triangleCount(); ++t) {
    const TriangleD triangle = worldTriangle(*shape, transform, t);
    for (const Vec3& p : triangle) r = std::max(r, (p - centre).norm());
    const Vec3 n = (triangle[1] - triangle[0]).cross(triangle[2] - triangle[0]).normalized();
    a = std::min(a, n.dot(triangle[0] - centre));
  }
  std::cout << "icosphere ray test: vertex radius " << r << ", face radius " << a << "\n";
  // Entry parameter of a segment into a sphere of radius rho about the centre.
  const auto sphereEntry = [&](const Vec3& from, const Vec3& to, double rho) {
    const Vec3 d = to - from, f = from - centre;
    const double qa = d.dot(d), qb = 2 * f.dot(d), qc = f.dot(f) - rho * rho;
    return (-qb - std::sqrt(qb * qb - 4 * qa * qc)) / (2 * qa);
  };
  std::uniform_real_distribution<double> within(0.0, 0.5 * a);
  std::vector<double> fractions;
  std::vector<Vec3> normals;

  int hits = 0;
  for (int ray = 0; ray < 40; ++ray) {
    const Vec3 target = centre + within(rng) * randomUnit(rng);
    const Vec3 direction = randomUnit(rng);
    const Vec3 from = target - 10 * direction, to = target + 10 * direction;
    if (!bruteForceHits(*shape, transform, from, to, fractions, normals)) continue;
    ++hits;
    ASSERT_EQ(fractions.size(), 2u) << "a ray through a convex solid's inside crosses its surface twice";
    const auto closest = expectRayMatchesBruteForce(w, body, from, to, fractions);
    ASSERT_TRUE(closest.hasHit());
    // The convex polyhedron holds the ball of radius a and lies in the ball of radius r, so its entry lies
    // between the two spheres' entries.
    const double fraction = double(closest.m_closestHitFraction);
    EXPECT_GE(fraction, sphereEntry(from, to, r) - 1e-5);
    EXPECT_LE(fraction, sphereEntry(from, to, a) + 1e-5);
    // The hit face's normal: the brute force's, and within the tessellation's angle of the sphere's normal
    // (on a face at distance a, a point p has n·p̂ = a / |p| >= a / r).
    const Vec3 normal = toEigen(closest.m_hitNormalWorld).normalized();
    EXPECT_GT(normal.dot(normals.front()), 1 - 1e-5);
    const Vec3 radial = (toEigen(closest.m_hitPointWorld) - centre).normalized();
    EXPECT_GE(normal.dot(radial), a / r - 1e-5);
  }
  EXPECT_GE(hits, 30);

  // Beside it: lines 2% outside the vertices' sphere.
  for (int ray = 0; ray < 20; ++ray) {
    const Vec3 direction = randomUnit(rng);
    const Vec3 offset = direction.cross(randomUnit(rng)).normalized() * 1.02 * r;
    const Vec3 from = centre + offset - 10 * direction, to = centre + offset + 10 * direction;
    ASSERT_TRUE(bruteForceHits(*shape, transform, from, to, fractions, normals));
    EXPECT_TRUE(fractions.empty());
    const auto closest = expectRayMatchesBruteForce(w, body, from, to, fractions);
    EXPECT_FALSE(closest.hasHit());
  }
}

// -----------------------------------------------------------------------------------------------------------
// Bodies at rest

// Resting height tolerance. Bullet's solver removes the approach velocity of a resting contact every step and
// pushes penetration back (split impulse), so a body at rest sits within ~1e-4 of its analytic height
// (measured here). A contact lost for one step lets the body sink by g dt² = 10 / 60² = 2.8 mm; 3 mm allows
// that once and still catches a margin counted wrong (the hull's is 40 mm) or missing triangles (the body
// falls through).
constexpr double kRestTolerance = 0.003;

double kineticEnergy(const btRigidBody& body) {
  const btVector3 v = body.getLinearVelocity();
  const btVector3 w = body.getWorldTransform().getBasis().transpose() * body.getAngularVelocity();
  const btVector3 inverseInertia = body.getInvInertiaDiagLocal();
  double rotational = 0;
  for (int axis = 0; axis < 3; ++axis) {
    if (inverseInertia[axis] > 0)
      rotational += double(w[axis]) * double(w[axis]) / double(inverseInertia[axis]);
  }
  return 0.5 * double(v.length2()) / double(body.getInvMass()) + 0.5 * rotational;
}

btTransform yawAt(std::mt19937& rng, const btVector3& position) {
  std::uniform_real_distribution<float> angle(0.0f, 6.2831853f);
  return btTransform(btQuaternion(btVector3(0, 1, 0), angle(rng)), position);
}

// A MeshShape that counts the calls of processAllTriangles, to tell "Bullet never asked for triangles" from
// "the triangles were wrong" when a body falls through.
ATTRIBUTE_ALIGNED16(class) CountingMeshShape : public MeshShape {
 public:
  BT_DECLARE_ALIGNED_ALLOCATOR();
  using MeshShape::MeshShape;
  void processAllTriangles(btTriangleCallback * callback, const btVector3& aabbMin, const btVector3& aabbMax)
      const override {
    ++calls;
    MeshShape::processAllTriangles(callback, aabbMin, aabbMax);
  }
  mutable int calls = 0;
};

// Boxes, spheres and hulls on a MeshShape ground go through Bullet's convex-concave algorithm. This test caught
// MeshShape first taking CUSTOM_CONCAVE_SHAPE_TYPE, which Bullet 3.24 also names SDF_SHAPE_PROXYTYPE: that
// algorithm then read the mesh as a signed distance field and every body fell through.
TEST(MeshShapeWorld, ConvexShapesRestOnAMeshGroundWithStockBullet) {
  std::mt19937 rng(61);
  std::uniform_real_distribution<float> place(-0.3f, 0.3f);
  // Ground top at y = 0 in both: a box of 12 triangles and one whose faces are split 6 × 6.
  for (int subdivisions : {1, 6}) {
    TestWorld w(DispatchKind::Stock);
    auto ground = std::make_shared<CountingMeshShape>(shared(scenes::makeBox(6, 0.5f, 6, subdivisions)));
    w.add(ground, 0, at(0, -0.5f, 0));
    // Rest heights: a btBoxShape's margin lies inside its half extents; a btSphereShape is all margin; a
    // btConvexHullShape's margin (0.04 by default) lies outside its points.
    std::vector<btVector3> prism;
    for (int k = 0; k < 6; ++k) {
      const float phi = 6.2831853f * float(k) / 6;
      prism.emplace_back(0.5f * std::cos(phi), -0.25f, 0.5f * std::sin(phi));
      prism.emplace_back(0.5f * std::cos(phi), 0.25f, 0.5f * std::sin(phi));
    }
    auto hull = std::make_shared<btConvexHullShape>(&prism[0].x(), int(prism.size()), int(sizeof(btVector3)));
    const double hullRest = 0.25 + double(hull->getMargin());
    struct Dropped {
      btRigidBody* body;
      double rest;
      const char* what;
    };
    std::vector<Dropped> bodies;
    for (int copy = 0; copy < 2; ++copy) {
      const float z = copy == 0 ? -2.0f : 2.0f;
      bodies.push_back({w.add(std::make_shared<btBoxShape>(btVector3(0.4f, 0.3f, 0.5f)), 1,
                              yawAt(rng, btVector3(-3 + place(rng), 0.8f, z + place(rng)))),
                        0.3, "box"});
      bodies.push_back({w.add(std::make_shared<btSphereShape>(0.4f), 1,
                              yawAt(rng, btVector3(place(rng), 0.9f, z + place(rng)))),
                        0.4, "sphere"});
      bodies.push_back({w.add(hull, 1, yawAt(rng, btVector3(3 + place(rng), 0.7f, z + place(rng)))), hullRest,
                        "convex hull"});
    }
    w.step(180);
    EXPECT_GT(ground->calls, 0)
        << "Bullet's convex-concave algorithm never asked the MeshShape for triangles";
    for (const Dropped& d : bodies) {
      const double y = double(d.body->getWorldTransform().getOrigin().y());
      std::cout << "ground " << subdivisions << "x" << subdivisions << ": " << d.what << " rests at " << y
                << " (analytic " << d.rest << ")\n";
      EXPECT_TRUE(isFinite(*d.body)) << d.what;
      EXPECT_NEAR(y, d.rest, kRestTolerance)
          << d.what << " on the " << subdivisions << "x" << subdivisions << " ground";
      EXPECT_LT(d.body->getLinearVelocity().length(), 0.05f) << d.what;
    }
  }
}

TEST(MeshShapeWorld, CompoundHoldingAMeshRestsOnAMeshGround) {
  for (DispatchKind kind : {DispatchKind::Gpucol, DispatchKind::StockRegistered}) {
    // A 1 × 0.6 × 0.8 mesh box as the child, offset and turned about y (which keeps its height): the
    // compound's origin rests 0.3 - 0.2 = 0.1 above the ground. The compound only points to its child, which
    // must outlive the world.
    auto child = meshShape(scenes::makeBox(0.5f, 0.3f, 0.4f));
    TestWorld w(kind);
    w.add(meshShape(scenes::makeBox(5, 0.5f, 5)), 0, at(0, -0.5f, 0));
    auto compound = std::make_shared<btCompoundShape>();
    compound->addChildShape(btTransform(btQuaternion(btVector3(0, 1, 0), 0.6f), btVector3(0.2f, 0.2f, -0.1f)),
                            child.get());
    btRigidBody* body = w.add(compound, 1, at(0.3f, 0.5f, 0.2f));
    w.step(180);
    const double y = double(body->getWorldTransform().getOrigin().y());
    std::cout << (kind == DispatchKind::Gpucol ? "Gpucol" : "StockRegistered") << ": compound rests at " << y
              << " (analytic 0.1), penetration " << w.deepestPenetration() << "\n";
    EXPECT_TRUE(isFinite(*body));
    EXPECT_NEAR(y, 0.1, kRestTolerance);
    EXPECT_LT(body->getLinearVelocity().length(), 0.05f);
  }
}

// Lowest point of the body's mesh in world space, in double.
double lowestVertex(const MeshShape& shape, const btTransform& transform) {
  double lowest = kInf;
  for (std::uint32_t t = 0; t < shape.mesh().triangleCount(); ++t) {
    for (const Vec3& p : worldTriangle(shape, transform, t)) lowest = std::min(lowest, p.y());
  }
  return lowest;
}

enum class Floor { Plane, TriangleMesh };

// A real mesh in its principal frame (so that the body's diagonal inertia is its full tensor), about 1 m
// across, dropped at random orientations from 0.3 m onto a floor at y = 0 with gpucol's dispatcher: it comes
// to rest on the floor, still. armadillo-5000 is the smallest closed 2-manifold real mesh of the data folder:
// bunny-948 is open and non-manifold, so it has no principal frame (inPrincipalFrame throws MeshError), and
// the closed bunny (59,664 triangles) takes about 8 s on the triangle mesh floor here.
void expectRealMeshRests(Floor floor, std::uint32_t seed) {
  GPUCOL_REQUIRE_MESH(path, "armadillo-5000.ply");
  const auto mesh = shared(loadMesh(path).inPrincipalFrame(1.0));
  const float scale = 1.0f / largestSide(*mesh);
  std::mt19937 rng(seed);
  for (int drop = 0; drop < 2; ++drop) {
    // The floor's triangles must outlive the world that holds the shape over them.
    btTriangleMesh floorTriangles;
    floorTriangles.addTriangle(btVector3(-50, 0, -50), btVector3(50, 0, 50), btVector3(50, 0, -50));
    floorTriangles.addTriangle(btVector3(-50, 0, -50), btVector3(-50, 0, 50), btVector3(50, 0, 50));
    TestWorld w(DispatchKind::Gpucol);
    if (floor == Floor::Plane) {
      w.add(std::make_shared<btStaticPlaneShape>(btVector3(0, 1, 0), 0), 0, btTransform::getIdentity());
    } else {
      w.add(std::make_shared<btBvhTriangleMeshShape>(&floorTriangles, true), 0, btTransform::getIdentity());
    }
    auto shape = std::make_shared<MeshShape>(mesh);
    shape->setLocalScaling(btVector3(scale, scale, scale));
    btTransform pose = randomPose(rng, btVector3(0, 0, 0), 0);
    pose.getOrigin().setY(btScalar(0.3 - lowestVertex(*shape, pose)));
    btRigidBody* body = w.add(shape, 2, pose);
    // Sleeping would zero the velocities and make the energy check empty.
    body->setActivationState(DISABLE_DEACTIVATION);
    w.step(480);
    const double lowest = lowestVertex(*shape, body->getWorldTransform());
    const double energy = kineticEnergy(*body);
    std::cout << (floor == Floor::Plane ? "plane" : "triangle mesh floor") << ", drop " << drop
              << ": lowest vertex " << lowest << ", kinetic energy " << energy << " J, deepest contact "
              << w.deepestPenetration() << "\n";
    EXPECT_TRUE(isFinite(*body));
    EXPECT_NEAR(lowest, 0.0, kRestTolerance) << "drop " << drop;
    // Still: less than the 2 kg body moving at 1 cm/s (1e-4 J).
    EXPECT_LT(energy, 1e-4) << "drop " << drop;
  }
}

TEST(MeshShapeWorld, RealMeshRestsOnATriangleMeshFloor) {
  expectRealMeshRests(Floor::TriangleMesh, 81);
}

// A real mesh on a btStaticPlaneShape rests like on the triangle mesh floor. This test caught the plane path
// first making contacts of every vertex within the breaking threshold (1 to 2 cm here): points above the plane
// crowded the supports out of the manifold, and the body never came to rest (kinetic energy 9.2e-3 J after 8 s).
TEST(MeshShapeWorld, RealMeshRestsOnAStaticPlane) {
  expectRealMeshRests(Floor::Plane, 81);
}

}  // namespace
}  // namespace gpucol::test
