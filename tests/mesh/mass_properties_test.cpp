// Mass properties against closed forms (box, right tetrahedron, sphere) and their invariance under
// rigid motion; open, non-manifold, inside-out and flat meshes are refused with a reason.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <random>
#include <string>
#include <tuple>

#include "gpucol/mesh_error.h"
#include "gpucol/triangle_mesh.h"
#include "mesh_test_util.h"
#include "support/test_paths.h"

namespace gpucol {
namespace {

using Matrix = Eigen::Matrix<double, 3, 3, Eigen::RowMajor>;

Matrix asMatrix(const std::array<double, 9>& a) {
  return Matrix(a.data());
}

std::string massError(const TriangleMesh& mesh, double density = 1.0) {
  try {
    mesh.massProperties(density);
  } catch (const MeshError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no MeshError";
  return {};
}

TEST(MassProperties, BoxMatchesClosedForm) {
  // Box 2a x 2b x 2c: V = 8abc, I = m/3 diag(b^2 + c^2, a^2 + c^2, a^2 + b^2). The corners are exact in
  // float, so the only error is double rounding: relative 1e-12.
  const double a = 0.5, b = 1.25, c = 2.0, density = 3.0;
  for (int n : {1, 4}) {
    const auto box = test::boxArrays({a, b, c}, {1.5, -2.0, 0.25}, n);
    const MassProperties mp = TriangleMesh::fromArrays(box.xyz, box.indices, "box").massProperties(density);
    const double volume = 8 * a * b * c, mass = density * volume;
    EXPECT_NEAR(mp.volume, volume, 1e-12 * volume);
    EXPECT_NEAR(mp.mass, mass, 1e-12 * mass);
    EXPECT_NEAR(mp.centerOfMass[0], 1.5, 1e-12);
    EXPECT_NEAR(mp.centerOfMass[1], -2.0, 1e-12);
    EXPECT_NEAR(mp.centerOfMass[2], 0.25, 1e-12);
    const double expected[9] = {mass / 3 * (b * b + c * c), 0, 0, 0, mass / 3 * (a * a + c * c), 0, 0, 0,
                                mass / 3 * (a * a + b * b)};
    for (int k = 0; k < 9; ++k)
      EXPECT_NEAR(mp.inertia[k], expected[k], 1e-12 * mass * c * c) << "entry " << k;
    EXPECT_NEAR(mp.principalMoments[0], expected[8], 1e-12 * mass * c * c);  // ascending: z, y, x
    EXPECT_NEAR(mp.principalMoments[1], expected[4], 1e-12 * mass * c * c);
    EXPECT_NEAR(mp.principalMoments[2], expected[0], 1e-12 * mass * c * c);
    EXPECT_NEAR(asMatrix(mp.principalAxes).determinant(), 1.0, 1e-12);
  }
}

TEST(MassProperties, RightTetrahedronMatchesClosedForm) {
  // Corners 0, e_x, e_y, e_z: V = 1/6, centre (1/4, 1/4, 1/4); about the centre the diagonal is
  // 3m/40... = 1/80 and the off-diagonal entries are +m/80 = 1/480 (the integral of xy is 1/120).
  const TriangleMesh tet = TriangleMesh::fromArrays({0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1},
                                                    {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3}, "tetrahedron");
  const MassProperties mp = tet.massProperties();
  EXPECT_NEAR(mp.volume, 1.0 / 6, 1e-15);
  for (double x : mp.centerOfMass) EXPECT_NEAR(x, 0.25, 1e-15);
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) EXPECT_NEAR(mp.inertia[3 * i + j], i == j ? 1.0 / 80 : 1.0 / 480, 1e-15);
  }
  // Eigenvalues of 1/80 I + 1/480 (J - I): 1/80 - 1/480 twice and 1/80 + 2/480 once (along (1,1,1)).
  EXPECT_NEAR(mp.principalMoments[0], 1.0 / 80 - 1.0 / 480, 1e-15);
  EXPECT_NEAR(mp.principalMoments[1], 1.0 / 80 - 1.0 / 480, 1e-15);
  EXPECT_NEAR(mp.principalMoments[2], 1.0 / 80 + 2.0 / 480, 1e-15);
  const Matrix axes = asMatrix(mp.principalAxes);
  EXPECT_NEAR(std::abs(axes.col(2).dot(Eigen::Vector3d(1, 1, 1).normalized())), 1.0, 1e-12);
  EXPECT_NEAR(axes.determinant(), 1.0, 1e-12);
}

TEST(MassProperties, SphereApproachesClosedForm) {
  // An inscribed icosphere falls short of the ball by O(h^2): at 5 levels (20,480 triangles) the
  // measured relative shortfall is below 1e-3 in volume and 2e-3 in moment; the tensor is isotropic
  // to 1e-3 by the icosahedral symmetry.
  const double r = 2.0;
  const auto sphere = test::icosphereArrays(r, 5);
  const MassProperties mp =
      TriangleMesh::fromArrays(sphere.xyz, sphere.indices, "sphere").massProperties(1.0);
  const double volume = 4.0 / 3.0 * M_PI * r * r * r, moment = 0.4 * volume * r * r;
  EXPECT_LT(mp.volume, volume);
  EXPECT_NEAR(mp.volume / volume, 1.0, 1e-3);
  for (double x : mp.centerOfMass) EXPECT_NEAR(x, 0.0, 1e-6);
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) EXPECT_NEAR(mp.inertia[3 * i + j] / moment, i == j ? 1.0 : 0.0, 2e-3);
  }
}

TEST(MassProperties, FarFromOriginKeepsPrecision) {
  // A unit cube at 1e5 (exact in float): computing about the bounding box centre keeps the volume to
  // double precision; about the origin the tetrahedra would be 1e15 in size and cancel to ~1e-1.
  const auto box = test::boxArrays({0.5, 0.5, 0.5}, {1e5, -1e5, 1e5}, 2);
  const MassProperties mp = TriangleMesh::fromArrays(box.xyz, box.indices, "far").massProperties(1.0);
  EXPECT_NEAR(mp.volume, 1.0, 1e-12);
  EXPECT_NEAR(mp.inertia[0], 1.0 / 6, 1e-12);
  EXPECT_NEAR(mp.inertia[1], 0.0, 1e-12);
  EXPECT_NEAR(mp.centerOfMass[1], -1e5, 1e-9);
}

/// Rotating and moving a mesh rotates its tensor: I' = R I R^T, com' = R com + t, same moments.
void expectCovariant(const TriangleMesh& mesh, std::mt19937& rng, double tolerance) {
  const MassProperties before = mesh.massProperties(2.0);
  std::uniform_real_distribution<double> u(-1, 1);
  const auto r = test::axisAngle({u(rng), u(rng), u(rng)}, 3 * u(rng));
  const std::array<double, 3> t = {5 * u(rng), 5 * u(rng), 5 * u(rng)};
  const MassProperties after = mesh.transformed(r, t).massProperties(2.0);
  const Matrix rm = asMatrix(r);
  const Matrix expected = rm * asMatrix(before.inertia) * rm.transpose();
  const double scale = before.principalMoments[2];
  EXPECT_NEAR(after.volume, before.volume, tolerance * before.volume) << mesh.name();
  EXPECT_LT((asMatrix(after.inertia) - expected).cwiseAbs().maxCoeff(), tolerance * scale) << mesh.name();
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(after.principalMoments[i], before.principalMoments[i], tolerance * scale) << mesh.name();
    double com = t[i];
    for (int j = 0; j < 3; ++j) com += r[3 * i + j] * before.centerOfMass[j];
    EXPECT_NEAR(after.centerOfMass[i], com, tolerance * std::sqrt(scale / before.mass) + 1e-5) << mesh.name();
  }
}

TEST(MassProperties, CovariantUnderRigidMotion) {
  // The moved vertices are rounded to float (relative 6e-8), so 1e-5 of the largest moment.
  std::mt19937 rng(7);
  const auto box = test::boxArrays({0.3, 1.1, 0.7}, {2, 0, 1}, 3);
  const TriangleMesh boxMesh = TriangleMesh::fromArrays(box.xyz, box.indices, "box");
  for (int trial = 0; trial < 5; ++trial) expectCovariant(boxMesh, rng, 1e-5);
  for (const char* file : {"torus-1152.ply", "armadillo-5000.ply", "fandisk-12946.ply"}) {
    const std::string path = test::meshPath(file);
    if (path.empty()) continue;
    const TriangleMesh mesh = loadMesh(path);
    for (int trial = 0; trial < 3; ++trial) expectCovariant(mesh, rng, 1e-5);
  }
}

TEST(MassProperties, PrincipalFrameIsDiagonal) {
  for (const char* file : {"torus-1152.ply", "armadillo-5000.ply", "rocker-arm-20088.ply"}) {
    GPUCOL_REQUIRE_MESH(path, file);
    const TriangleMesh mesh = loadMesh(path);
    const MassProperties original = mesh.massProperties(1.5);
    std::array<double, 9> backRotation{};
    std::array<double, 3> backTranslation{};
    const TriangleMesh principal = mesh.inPrincipalFrame(1.5, &backRotation, &backTranslation);
    const MassProperties mp = principal.massProperties(1.5);
    const double scale = original.principalMoments[2];
    const double length = std::sqrt(scale / original.mass);  // radius of gyration
    for (int i = 0; i < 3; ++i) {
      EXPECT_NEAR(mp.centerOfMass[i], 0.0, 1e-5 * length) << file;
      EXPECT_NEAR(mp.principalMoments[i], original.principalMoments[i], 1e-5 * scale) << file;
      EXPECT_NEAR(mp.inertia[4 * i], original.principalMoments[i], 1e-5 * scale) << file;
      for (int j = 0; j < 3; ++j) {
        if (i != j) {
          EXPECT_NEAR(mp.inertia[3 * i + j], 0.0, 1e-5 * scale) << file;
        }
      }
    }
    EXPECT_NEAR(asMatrix(backRotation).determinant(), 1.0, 1e-12);
    // The returned transform maps the principal mesh back onto the original vertices.
    const TriangleMesh back = principal.transformed(backRotation, backTranslation);
    for (std::size_t k = 0; k < mesh.positions().size(); ++k)
      ASSERT_NEAR(back.positions()[k], mesh.positions()[k],
                  2e-6 * length + 1e-6 * std::abs(mesh.positions()[k]));
  }
}

TEST(MassProperties, RealMeshVolumesMatchExactReference) {
  // Reference: the signed volume summed in exact rational arithmetic (Python fractions) over the
  // float32 coordinates of the files; relative 1e-13. manifest.json's signed volumes differ from
  // these by up to 1.3e-8 relative because they came from the sources' longer decimal coordinates,
  // the same size as float32 rounding, so they only confirm the sign and the first 7 digits.
  const std::tuple<const char*, double, double> cases[] = {
      {"torus-1152.ply", 1.1747361744503182, 1.1747361789482011},
      {"armadillo-25000.ply", 0.23237750459618448, 0.23237750460019257},
      {"fandisk-12946.ply", 20.24337461846027, 20.24337488283945},
      {"dragon-20000.ply", 19.263384154960576, 19.263384126805352}};
  for (const auto& [file, exact, manifest] : cases) {
    GPUCOL_REQUIRE_MESH(path, file);
    const double volume = loadMesh(path).massProperties().volume;
    EXPECT_NEAR(volume, exact, 1e-13 * exact) << file;
    EXPECT_NEAR(volume, manifest, 2e-8 * manifest) << file;
  }
}

TEST(MassProperties, ResultsOutsideFloatsNormalRangeAreRefused) {
  // Bullet takes them in float: an overflow would reach a body as inf, an underflow as NaN after a step.
  const auto cube = [](double half) {
    const test::MeshArrays box = test::boxArrays({half, half, half});
    return TriangleMesh::fromArrays(box.xyz, box.indices, "cube " + std::to_string(half));
  };
  EXPECT_EQ(
      massError(cube(1e17)),
      "cube 100000000000000000.000000: cannot compute mass properties: the volume is 8e+51, outside float's "
      "normal range (1.17549e-38 to 3.40282e+38), which Bullet computes in; scale the mesh or change the "
      "density");
  EXPECT_NE(massError(cube(1e-15)).find("the volume is 8e-45, outside float's normal range"),
            std::string::npos);
  // Volume 8e-30 fits, its inertia (about 5e-60) does not.
  EXPECT_NE(massError(cube(1e-10)).find("the inertia about x is 5.33333e-50, outside"), std::string::npos);
  EXPECT_NE(massError(cube(1), 1e39).find("the mass is 8e+39, outside"), std::string::npos);
  // Within range, the double results are as before.
  EXPECT_NEAR(cube(1e4).massProperties().volume, 8e12, 1e-3);
  EXPECT_NEAR(cube(1e-3).massProperties().inertia[0], 8e-9 * 2e-6 / 3, 1e-20);
}

TEST(MassProperties, RefusesOpenNonManifoldInsideOutAndFlat) {
  auto box = test::boxArrays({1, 1, 1});
  // Open: drop the last triangle.
  auto open = box;
  open.indices.resize(open.indices.size() - 3);
  EXPECT_EQ(
      massError(TriangleMesh::fromArrays(open.xyz, open.indices, "open")),
      "open: cannot compute mass properties: the mesh is not a closed manifold (3 boundary edges, 0 edges "
      "shared by more than two triangles), so it encloses no well-defined volume");
  // Non-manifold: a fin triangle on an existing edge (and its other two edges are boundary).
  auto fin = box;
  fin.xyz.insert(fin.xyz.end(), {5, 5, 5});
  fin.indices.insert(fin.indices.end(),
                     {fin.indices[0], fin.indices[1], std::uint32_t(fin.xyz.size() / 3 - 1)});
  EXPECT_NE(massError(TriangleMesh::fromArrays(fin.xyz, fin.indices, "fin"))
                .find("1 edges shared by more than two"),
            std::string::npos);
  // Inside out: every triangle reversed.
  auto inverted = box;
  for (std::size_t t = 0; t < inverted.indices.size(); t += 3)
    std::swap(inverted.indices[t + 1], inverted.indices[t + 2]);
  const std::string inside = massError(TriangleMesh::fromArrays(inverted.xyz, inverted.indices, "inverted"));
  EXPECT_NE(inside.find("inverted: cannot compute mass properties: the signed volume is negative (-8)"),
            std::string::npos)
      << inside;
  EXPECT_NE(inside.find("inward normals"), std::string::npos);
  // One triangle flipped: closed, but its three edges are walked twice the same way.
  auto flipped = box;
  std::swap(flipped.indices[1], flipped.indices[2]);
  EXPECT_NE(
      massError(TriangleMesh::fromArrays(flipped.xyz, flipped.indices, "flipped")).find("3 edges are walked"),
      std::string::npos);
  // Flat: a triangle and its reverse close each other's edges but enclose nothing.
  const TriangleMesh sheet =
      TriangleMesh::fromArrays({0, 0, 0, 1, 0, 0, 0, 1, 0}, {0, 1, 2, 0, 2, 1}, "sheet");
  EXPECT_NE(massError(sheet).find("sheet: cannot compute mass properties: the mesh encloses no volume"),
            std::string::npos);
  // Bad density.
  const TriangleMesh cube = TriangleMesh::fromArrays(box.xyz, box.indices, "cube");
  EXPECT_NE(massError(cube, 0.0).find("density must be finite and positive, got 0"), std::string::npos);
  EXPECT_THROW(cube.massProperties(NAN), MeshError);
  // A real open mesh.
  const std::string path = test::meshPath("bunny-69451.ply");
  if (!path.empty()) {
    EXPECT_NE(massError(loadMesh(path)).find("223 boundary edges"), std::string::npos);
  }
}

}  // namespace
}  // namespace gpucol
