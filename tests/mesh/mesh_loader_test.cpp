// loadMesh on good files: real files keep the file's exact vertices and triangles; OBJ, STL and files with
// polygons are welded on exactly equal positions only; polygons are split along their shape. Special, missing
// and cut files give a MeshError at once. The hostile corpus is in hostile_mesh_files_test.cpp.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <string>
#include <vector>

#include "gpucol/mesh_error.h"
#include "gpucol/triangle_mesh.h"
#include "limited_load.h"
#include "mesh_test_util.h"
#include "support/test_paths.h"

namespace gpucol {
namespace {

std::string loadError(const std::string& path) {
  try {
    loadMesh(path);
  } catch (const MeshError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no MeshError for " << path;
  return {};
}

#define EXPECT_CONTAINS(text, part)                          \
  EXPECT_NE(std::string(text).find(part), std::string::npos) \
      << "\"" << (text) << "\" lacks \"" << (part) << "\""

TEST(LoadMesh, RealMeshesKeepTheFilesVerticesAndTriangles) {
  // Compared element by element with an independent reader of the documented layout: no welding,
  // no reordering, unreferenced vertices kept (bunny-69451 has 1,113), duplicate positions kept
  // (the teapot has 403).
  std::size_t found = 0;
  for (const char* file : {"torus-1152.ply", "bunny-69451.ply", "teapot-6320.ply", "bunny-948.ply",
                           "armadillo-5000.ply", "fandisk-12946.ply"}) {
    const std::string path = test::meshPath(file);
    if (path.empty()) continue;
    ++found;
    const TriangleMesh mesh = loadMesh(path);
    const test::MeshArrays reference = test::readReferencePly(path);
    EXPECT_EQ(mesh.positions(), reference.xyz) << file;
    // Bit for bit, -0 included (teapot-6320 has 86 of them).
    EXPECT_TRUE(mesh.positions().size() == reference.xyz.size() &&
                std::memcmp(mesh.positions().data(), reference.xyz.data(), 4 * reference.xyz.size()) == 0)
        << file;
    EXPECT_EQ(mesh.indices(), reference.indices) << file;
    EXPECT_EQ(mesh.name(), path);
  }
  if (found == 0) GTEST_SKIP() << "no real meshes in " << test::meshDirectory();
}

TEST(LoadMesh, TorusCountsAndClosed) {
  GPUCOL_REQUIRE_MESH(path, "torus-1152.ply");
  const TriangleMesh mesh = loadMesh(path);
  EXPECT_EQ(mesh.vertexCount(), 576u);
  EXPECT_EQ(mesh.triangleCount(), 1152u);
  EXPECT_TRUE(mesh.report().closed);
}

TEST(LoadMesh, AsciiPlyAndOffKeepSharedVertices) {
  test::TempDir dir;
  const std::string ply =
      dir.write("tet.ply",
                "ply\nformat ascii 1.0\ncomment a tetrahedron and one unused vertex\n"
                "element vertex 5\nproperty float x\nproperty float y\nproperty float z\n"
                "element face 4\nproperty list uchar int vertex_indices\nend_header\n"
                "0 0 0\n1 0 0\n0 1 0\n0 0 1\n5 5 5\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n");
  const TriangleMesh mesh = loadMesh(ply);
  EXPECT_EQ(mesh.vertexCount(), 5u);
  EXPECT_EQ(mesh.indices(), (std::vector<std::uint32_t>{0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3}));
  EXPECT_EQ(mesh.report().unreferencedVertices, 1u);
  EXPECT_NEAR(mesh.massProperties().volume, 1.0 / 6, 1e-12);

  const std::string off = dir.write("quad.off", "OFF\n4 1 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n");
  const TriangleMesh quad = loadMesh(off);  // the quad is triangulated over the same 4 vertices
  EXPECT_EQ(quad.vertexCount(), 4u);
  EXPECT_EQ(quad.triangleCount(), 2u);
  EXPECT_EQ(quad.report().edgeCount, 5u);
}

TEST(LoadMesh, ObjAndStlAreWeldedOnExactlyEqualPositions) {
  test::TempDir dir;
  // OBJ: exactly equal positions are one vertex. The fifth vertex differs from vertex 1 in the last float
  // bit, so it must stay separate.
  const std::string obj = dir.write("tet.obj",
                                    "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nv 1.0000001 0 0\n"
                                    "f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\nf 5 4 2\n");
  const TriangleMesh mesh = loadMesh(obj);
  EXPECT_EQ(mesh.vertexCount(), 5u);
  EXPECT_EQ(mesh.triangleCount(), 5u);
  EXPECT_EQ(mesh.report().boundaryEdges, 2u);     // the sliver face 5 has two edges of its own
  EXPECT_EQ(mesh.report().nonManifoldEdges, 1u);  // and shares edge (2, 4) with two faces

  // Binary STL of the same tetrahedron, with -0 in one corner: -0 and +0 are the same position.
  std::string stl(80, '\0');
  const float tris[4][9] = {{0, 0, 0, 0, 1, 0, 1, 0, 0},
                            {0, 0, 0, 1, 0, 0, 0, 0, 1},
                            {-0.0f, 0, 0, 0, 0, 1, 0, 1, 0},
                            {1, 0, 0, 0, 1, 0, 0, 0, 1}};
  const std::uint32_t count = 4;
  stl.append(reinterpret_cast<const char*>(&count), 4);
  for (const auto& t : tris) {
    const float normal[3] = {0, 0, 0};
    stl.append(reinterpret_cast<const char*>(normal), 12);
    stl.append(reinterpret_cast<const char*>(t), 36);
    stl.append(2, '\0');
  }
  const TriangleMesh fromStl = loadMesh(dir.write("tet.stl", stl));
  EXPECT_EQ(fromStl.vertexCount(), 4u);
  EXPECT_TRUE(fromStl.report().closed);
  EXPECT_NEAR(fromStl.massProperties().volume, 1.0 / 6, 1e-12);
}

/// Twice the signed area of the triangles' projection on z: positive for counter-clockwise seen from +z.
std::vector<double> signedAreas(const TriangleMesh& mesh) {
  std::vector<double> areas;
  for (std::size_t t = 0; t < mesh.triangleCount(); ++t) {
    const float* a = &mesh.positions()[3 * mesh.indices()[3 * t]];
    const float* b = &mesh.positions()[3 * mesh.indices()[3 * t + 1]];
    const float* c = &mesh.positions()[3 * mesh.indices()[3 * t + 2]];
    areas.push_back((double(b[0]) - a[0]) * (double(c[1]) - a[1]) -
                    (double(b[1]) - a[1]) * (double(c[0]) - a[0]));
  }
  return areas;
}

TEST(LoadMesh, PolygonsAreSplitAlongTheirShapeWithTheirWinding) {
  // A split is right when every triangle keeps the polygon's winding and their areas add up to the polygon's:
  // a triangle outside the polygon, or two overlapping, would break one or the other.
  const auto expectSplit = [](const TriangleMesh& mesh, double area, std::size_t triangles) {
    const std::vector<double> areas = signedAreas(mesh);
    ASSERT_EQ(areas.size(), triangles);
    double sum = 0;
    for (double a : areas) {
      EXPECT_GE(a, 0.0);
      sum += a;
    }
    EXPECT_NEAR(sum / 2, area, 1e-9 * area);
  };
  test::TempDir dir;
  // An L whose first corner is reflex, so a fan from it would be wrong, and a star of 1,000 corners
  // (non-convex, ear-clipped), starting at an inner corner.
  expectSplit(
      loadMesh(dir.write("l.obj", "v 1 1 0\nv 1 2 0\nv 0 2 0\nv 0 0 0\nv 2 0 0\nv 2 1 0\nf 1 2 3 4 5 6\n")),
      3, 4);
  std::string star;
  std::string face = "f";
  double shoelace = 0;
  std::vector<std::array<double, 2>> corners;
  for (int k = 0; k < 1000; ++k) {
    const double angle = 2 * M_PI * k / 1000, r = k % 2 ? 1000 : 400;
    corners.push_back({double(std::lround(r * std::cos(angle))), double(std::lround(r * std::sin(angle)))});
    star += "v " + std::to_string(std::lround(corners.back()[0])) + " " +
            std::to_string(std::lround(corners.back()[1])) + " 0\n";
    face += " " + std::to_string(k + 1);
  }
  for (std::size_t k = 0; k < corners.size(); ++k) {
    const auto& a = corners[k];
    const auto& b = corners[(k + 1) % corners.size()];
    shoelace += a[0] * b[1] - a[1] * b[0];
  }
  expectSplit(loadMesh(dir.write("star.obj", star + face + "\n")), shoelace / 2, 998);
  // A convex hexagon written clockwise seen from +z keeps its winding: every triangle faces -z.
  const TriangleMesh clockwise =
      loadMesh(dir.write("cw.off", "OFF\n6 1 0\n0 0 0\n0 1 0\n1 2 0\n2 1 0\n2 0 0\n1 -1 0\n6 0 1 2 3 4 5\n"));
  for (double a : signedAreas(clockwise)) EXPECT_LT(a, 0.0);
  // A polygon out of the xy plane (a square in x = 1, tilted) is split in its own plane.
  const TriangleMesh tilted =
      loadMesh(dir.write("tilted.obj", "v 1 0 0\nv 1 1 1\nv 1 0 2\nv 1 -1 1\nf 1 2 3 4\n"));
  EXPECT_EQ(tilted.triangleCount(), 2u);
  EXPECT_TRUE(tilted.report().degenerateTriangles.empty());
}

TEST(LoadMesh, QuadCubesAreClosedInEveryFormat) {
  // The same closed cube as quads, written the way modelling tools do: OBJ with shared corners (Blender), PLY
  // and OFF with a vertex per face corner. Welded on exactly equal positions, each is the closed cube of 8
  // vertices, 12 triangles and volume 8.
  const char* corners[8] = {"-1 -1 -1", "1 -1 -1", "1 1 -1", "-1 1 -1",
                            "-1 -1 1",  "1 -1 1",  "1 1 1",  "-1 1 1"};
  const int quads[6][4] = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4},
                           {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}};
  std::string obj, plyVertices, plyFaces, offVertices, offFaces;
  for (const char* c : corners) obj += std::string("v ") + c + "\n";
  for (int f = 0; f < 6; ++f) {
    obj += "f";
    plyFaces += "4";
    for (int k = 0; k < 4; ++k) {
      obj += " " + std::to_string(quads[f][k] + 1);
      plyVertices += std::string(corners[quads[f][k]]) + "\n";
      plyFaces += " " + std::to_string(4 * f + k);
    }
    obj += "\n";
    plyFaces += "\n";
  }
  test::TempDir dir;
  const std::string ply =
      "ply\nformat ascii 1.0\nelement vertex 24\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 6\nproperty list uchar int vertex_indices\nend_header\n" +
      plyVertices + plyFaces;
  for (const std::string& path : {dir.write("cube.obj", obj), dir.write("cube.ply", ply),
                                  dir.write("cube.off", "OFF\n24 6 0\n" + plyVertices + plyFaces)}) {
    const TriangleMesh cube = loadMesh(path);
    EXPECT_EQ(cube.vertexCount(), 8u) << path;
    EXPECT_EQ(cube.triangleCount(), 12u) << path;
    EXPECT_TRUE(cube.report().closed) << path;
    EXPECT_NEAR(cube.massProperties().volume, 8.0, 1e-12) << path;
  }
}

TEST(LoadMesh, SpecialAndMissingFilesAreRefusedAtOnce) {
  test::TempDir dir;
  const std::string missing = dir.file("missing.ply");
  EXPECT_EQ(loadError(missing), missing + ": cannot open mesh file: No such file or directory");
  const std::string missingOther = dir.file("missing.gltf");
  EXPECT_EQ(loadError(missingOther), missingOther + ": cannot open mesh file: No such file or directory");
  EXPECT_EQ(loadError(dir.file("")), dir.file("") + ": cannot read mesh file: it is a directory");
  const std::string empty = dir.write("empty.ply", "");
  EXPECT_EQ(loadError(empty), empty + ": the mesh file is empty");
  EXPECT_EQ(loadError("/dev/null"), "/dev/null: cannot read mesh file: it is a character device");
  // /dev/zero never ends (it threw std::bad_alloc after 10 s); a FIFO without a writer blocked forever. Both
  // are refused from their stat, in a child that a hang or a memory blow-up would fail.
  const std::string fifo = dir.file("fifo.ply");
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  for (const auto& [path, message] :
       {std::pair<std::string, std::string>{"/dev/zero", "it is a character device"},
        {fifo, "it is a FIFO (named pipe)"}}) {
    const test::LimitedLoad got = test::loadWithinLimits(path, 64u << 20, 10);
    EXPECT_EQ(got.outcome, test::LimitedLoad::Outcome::kMeshError) << got.message;
    EXPECT_EQ(got.message, path + ": cannot read mesh file: " + message);
  }
  // A link to a FIFO is the FIFO; a link to a mesh is the mesh.
  const std::string fifoLink = dir.file("fifo-link.off");
  ASSERT_EQ(symlink(fifo.c_str(), fifoLink.c_str()), 0);
  EXPECT_EQ(loadError(fifoLink), fifoLink + ": cannot read mesh file: it is a FIFO (named pipe)");
  const std::string off = dir.write("tri.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  const std::string link = dir.file("link.off");
  ASSERT_EQ(symlink(off.c_str(), link.c_str()), 0);
  EXPECT_EQ(loadMesh(link).triangleCount(), 1u);
}

TEST(LoadMesh, EveryCutOfARealFileIsRefusedCleanly) {
  // assimp, which read PLY before, crashed or hung on truncated binary PLY files; each cut of the torus, at
  // every 37th byte and around the header's end, must give a MeshError.
  GPUCOL_REQUIRE_MESH(source, "torus-1152.ply");
  const std::string bytes = test::readBytes(source);
  test::TempDir dir;
  const std::size_t body = bytes.find("end_header\n") + 11;
  std::vector<std::size_t> cuts = {1, body - 1, body, body + 1, bytes.size() - 1};
  for (std::size_t cut = 2; cut < bytes.size(); cut += 37) cuts.push_back(cut);
  for (const std::size_t cut : cuts) {
    const std::string path = dir.write("cut.ply", bytes.substr(0, cut));
    EXPECT_NE(loadError(path).find(path + ": malformed PLY file: "), std::string::npos) << "cut at " << cut;
  }
  const std::string lastByte = dir.write("last.ply", bytes.substr(0, bytes.size() - 1));
  EXPECT_EQ(loadError(lastByte), lastByte +
                                     ": malformed PLY file: truncated: element 'face' record 1151 property "
                                     "'vertex_indices' of 1152 needs 12 bytes at offset " +
                                     std::to_string(bytes.size() - 12) + ", but the file ends at " +
                                     std::to_string(bytes.size() - 1));
}

}  // namespace
}  // namespace gpucol
