// loadMesh: real files keep the file's exact vertices and triangles; corner-split formats are welded
// on exactly equal positions only; node transforms are applied; bad files give a MeshError that
// names the file and the reason, and never crash (assimp itself does on truncated PLY files).
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
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
  // OBJ: assimp gives each face corner its own vertex; welding restores the closed tetrahedron. The
  // fifth vertex differs from vertex 1 in the last float bit, so it must stay separate.
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

TEST(LoadMesh, SeveralMeshesAreMergedWithTheirNodeTransforms) {
  // A glTF scene: one triangle mesh used by two nodes, one translated by (10, 0, 0), one mirrored in
  // x (its winding is swapped back so the triangle still faces the same way as in the file).
  test::TempDir dir;
  const float positions[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  const std::uint16_t indices[4] = {0, 1, 2, 0};  // padded to 4-byte alignment
  std::string buffer(reinterpret_cast<const char*>(positions), sizeof positions);
  buffer.append(reinterpret_cast<const char*>(indices), sizeof indices);
  std::ofstream(dir.file("tri.bin"), std::ios::binary).write(buffer.data(), std::streamsize(buffer.size()));
  const std::string gltf = dir.write("scene.gltf", R"({
  "asset": {"version": "2.0"},
  "scene": 0,
  "scenes": [{"nodes": [0, 1]}],
  "nodes": [{"mesh": 0, "translation": [10, 0, 0]}, {"mesh": 0, "scale": [-1, 1, 1]}],
  "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "mode": 4}]}],
  "buffers": [{"uri": "tri.bin", "byteLength": 44}],
  "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": 6}],
  "accessors": [
    {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
    {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}]
})");
  const TriangleMesh mesh = loadMesh(gltf);
  ASSERT_EQ(mesh.triangleCount(), 2u);
  ASSERT_EQ(mesh.vertexCount(), 6u);
  // Each triangle's normal (right-hand rule over its stored corners) must be +z for both copies.
  float minX = 1e9f, maxX = -1e9f;
  for (std::size_t t = 0; t < 2; ++t) {
    const float* a = &mesh.positions()[3 * mesh.indices()[3 * t]];
    const float* b = &mesh.positions()[3 * mesh.indices()[3 * t + 1]];
    const float* c = &mesh.positions()[3 * mesh.indices()[3 * t + 2]];
    const float nz = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
    EXPECT_GT(nz, 0.0f) << "triangle " << t;
    for (const float* p : {a, b, c}) {
      minX = std::min(minX, p[0]);
      maxX = std::max(maxX, p[0]);
    }
  }
  EXPECT_EQ(minX, -1.0f);  // mirrored copy
  EXPECT_EQ(maxX, 11.0f);  // translated copy
}

TEST(LoadMesh, PointsAndLinesAreRefused) {
  test::TempDir dir;
  const std::string line = dir.write("line.obj", "v 0 0 0\nv 1 0 0\nl 1 2\n");
  const std::string message = loadError(line);
  EXPECT_CONTAINS(message, line + ": mesh 0");
  EXPECT_CONTAINS(message, "face 0 has 2 indices (a line); gpucol needs triangles");
}

TEST(LoadMesh, MissingEmptyAndGarbageFiles) {
  test::TempDir dir;
  const std::string missing = dir.file("missing.ply");
  EXPECT_EQ(loadError(missing), missing + ": cannot open mesh file: No such file or directory");
  EXPECT_EQ(loadError(dir.file("")), dir.file("") + ": cannot read mesh file: it is a directory");
  const std::string empty = dir.write("empty.ply", "");
  EXPECT_EQ(loadError(empty), empty + ": the mesh file is empty");
  std::string noise(3000, '\0');
  for (std::size_t i = 0; i < noise.size(); ++i) noise[i] = char((i * 2654435761u) >> 13);
  const std::string garbage = dir.write("garbage.xyzw", noise);
  EXPECT_CONTAINS(loadError(garbage), garbage + ": assimp cannot read the mesh file: ");
  // assimp reads every .ply path with its PLY reader, so the pre-check sees it first.
  const std::string garbagePly = dir.write("garbage.ply", noise);
  EXPECT_CONTAINS(loadError(garbagePly),
                  garbagePly + ": malformed PLY file: it does not start with the line 'ply'");
  // An OBJ file with vertices but no faces holds no triangle mesh.
  const std::string noFaces = dir.write("nofaces.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n");
  EXPECT_CONTAINS(loadError(noFaces),
                  noFaces + ": assimp cannot read the mesh file: Validation failed: Mesh");
}

/// Loads `path` in a child process that SIGALRM ends after 10 s, so a loader that hangs fails the test
/// instead of stalling it, and expects a MeshError containing `part` (the child prints the message it got).
void expectPromptError(const std::string& path, const std::string& part) {
  EXPECT_EXIT(
      {
        alarm(10);
        int code = 3;  // no MeshError
        try {
          loadMesh(path);
        } catch (const MeshError& e) {
          std::fprintf(stderr, "%s\n", e.what());
          code = std::string(e.what()).find(part) == std::string::npos ? 2 : 0;
        }
        std::_Exit(code);
      },
      ::testing::ExitedWithCode(0), "")
      << path << " should fail with \"" << part << "\"";
}

TEST(LoadMesh, EveryFileAssimpReadsAsPlyIsPrechecked) {
  // Found by tests/fuzz/mesh_loader_fuzzer (tests/fuzz/findings/loader_hang_assimp_ply.bin, less its first
  // byte, which chose .ply): "ply" followed by escape bytes, a '\0', then a PLY header with no "end_header"
  // line. Its first line is not exactly "ply", so the pre-check used to let it through to assimp, whose magic
  // test only compares three bytes; assimp's header loop then never ends (a failed read per turn: 17 s user,
  // 55 s system in 120 s).
  static const char kFinding[] =
      "ply\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033"
      "\033"
      "\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033"
      "\033"
      "\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033"
      "\033"
      "\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033td\"\"\"\"\"\"\"\"\"\""
      "p"
      "\000\000\000\"\"\"\"\"\"\"\"\"\"\"\"\"\"\"\"\000ply\nformat ascii 1.0\nelement &ertex 3\nproperty "
      "float "
      "x\npro\"\"\"\"\"\"\"\"\"\"\"perty float y\034\000\000\000\000\007\000\000\nproperty float "
      "z\nel\003OFF\n"
      "4 4 0\n0 0\n\n0 0 0\000\000\000\000\000\000\000\000\n1 0\0000\n0 1 "
      "0\"\"\"\"\"\"\"\"\"\"\"\"\"\"\"\"\"\""
      "\"\"\"\"\"\"\"\"\"\"\"\"\"\"\"\"\"ar 2 1 2int vertex_indices\nend 3_header\n\n0 0 0\n3 0 1 2\n\n1 "
      "0\0000"
      "\n0 1 0\n3 0 1 2=\n";
  test::TempDir dir;
  const std::string finding = dir.write("finding.ply", std::string(kFinding, sizeof kFinding - 1));
  ASSERT_EQ(test::readBytes(finding).size(), 396u);
  expectPromptError(finding, finding +
                                 ": malformed PLY file: it does not start with the line 'ply' but with "
                                 "\"ply\\x1b\\x1b");
  // The same bytes under another name: assimp picks its PLY reader by content when no reader claims the
  // extension.
  const std::string unknown = dir.write("finding.mesh", std::string(kFinding, sizeof kFinding - 1));
  expectPromptError(unknown, unknown + ": malformed PLY file: it does not start with the line 'ply'");
  // assimp skips one leading line end before its magic test: this one reaches its header loop too.
  const std::string head = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n";
  const std::string leading = dir.write("leading.ply", "\n" + head);
  expectPromptError(leading, "it does not start with the line 'ply' but with \"\\x0aply\\x0aformat");
  // 3 MB of zero bytes named .ply: assimp's line reader runs past its 1 MiB buffer looking for a '\n'.
  const std::string zeros = dir.write("zeros.ply", std::string(3000000, '\0'));
  expectPromptError(zeros, "it does not start with the line 'ply' but with \"\\x00");
}

TEST(LoadMesh, PlyTextWithControlBytesAndEmptyElementsIsRefused) {
  // Each of these hangs (more than 20 s) or aborts Debian's assimp 5.2.5 after the pre-check used to pass it.
  const std::string header =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 1\nproperty list uchar int vertex_indices\n";
  const std::string body = "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
  test::TempDir dir;
  // assimp ends the header only at "end_header" followed by a space, tab or line end; '\v' is none of them.
  const std::string vtab = dir.write("vtab.ply", header + "end_header\v\n" + body);
  expectPromptError(vtab,
                    vtab + ": malformed PLY file: header line 9 holds the control byte 0x0b at column 11");
  // assimp ends a line at '\f' and drops the rest, so the record is one value short (an assert aborts).
  const std::string feed = dir.write("feed.ply", header + "end_header\n0 0 0\n1 0\f0\n0 1 0\n3 0 1 2\n");
  expectPromptError(feed, feed + ": malformed PLY file: body line 2 holds the control byte 0x0c at column 4");
  // A binary element without properties takes no bytes, so no file size bounds its count; assimp loops over
  // it.
  const std::string binary = "ply\nformat binary_little_endian 1.0\n";
  const std::string emptyVertex =
      dir.write("empty-vertex.ply", binary + "element vertex 4000000000\nend_header\n");
  expectPromptError(
      emptyVertex,
      emptyVertex + ": malformed PLY file: element 'vertex' declares 4000000000 records but no properties");
  const std::string emptyFace =
      dir.write("empty-face.ply",
                binary + "element vertex 1\nproperty float x\nelement face 4000000000\nend_header\n0000");
  expectPromptError(emptyFace, "element 'face' declares 4000000000 records but no properties");
  // The same header with a tab and "\r\n" line ends, which both readers take, still loads.
  std::string crlf = header + "end_header\n" + body;
  for (std::size_t at = crlf.find('\n'); at != std::string::npos; at = crlf.find('\n', at + 2))
    crlf.insert(at, "\r");
  crlf.replace(crlf.find("property float y"), 16, "property\tfloat y");
  EXPECT_EQ(loadMesh(dir.write("crlf.ply", crlf)).triangleCount(), 1u);
}

TEST(LoadMesh, PlyFaceWithoutCornersIsRefused) {
  // Found by tests/fuzz/mesh_loader_fuzzer (bunny-948.ply with 19 face counts set to 0): assimp 5.2.5 marks a
  // face of no corners as a polygon, and Triangulate aborts on an assert when no face has more than three.
  const std::string header =
      "element vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 2\n"
      "property list uchar int vertex_indices\nend_header\n";
  test::TempDir dir;
  const std::string ascii =
      dir.write("ascii.ply", "ply\nformat ascii 1.0\n" + header + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n0\n");
  expectPromptError(ascii, ascii +
                               ": malformed PLY file: element 'face' record 1 has an empty list "
                               "'vertex_indices' (a face without corners)");
  const float xyz[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  const std::int32_t face[3] = {0, 1, 2};
  std::string binary = "ply\nformat binary_little_endian 1.0\n" + header;
  binary.append(reinterpret_cast<const char*>(xyz), sizeof xyz);
  binary.push_back(0);
  binary.push_back(3);
  binary.append(reinterpret_cast<const char*>(face), sizeof face);
  const std::string first = dir.write("binary.ply", binary);
  expectPromptError(first, first + ": malformed PLY file: element 'face' record 0 has an empty list");
}

TEST(LoadMesh, PlyHeaderCommentsAndBlankLinesBetweenPropertiesLoad) {
  // assimp ends an element's property list at the first other line, so it read the first three binary files
  // with a 4-byte vertex record and aborted on an assert; the header it now gets holds only format, element
  // and property lines. The fourth ("\r\n" line ends) always loaded and must still.
  const float xyz[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  const std::int32_t face[3] = {0, 1, 2};
  std::string body(reinterpret_cast<const char*>(xyz), sizeof xyz);
  body.push_back(3);
  body.append(reinterpret_cast<const char*>(face), sizeof face);
  const auto header = [](const std::string& between, const std::string& end) {
    return "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n" + between +
           "property float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\n" +
           end;
  };
  test::TempDir dir;
  for (const std::string& file : {header("comment between x and y\n", "end_header\n"),
                                  header("obj_info made by hand\n", "end_header\n"),
                                  header("\n\n", "end_header\n"), header("", "end_header\r\n")}) {
    const TriangleMesh mesh = loadMesh(dir.write("between.ply", file + body));
    EXPECT_EQ(mesh.positions(), std::vector<float>(std::begin(xyz), std::end(xyz))) << file;
    EXPECT_EQ(mesh.indices(), (std::vector<std::uint32_t>{0, 1, 2})) << file;
  }
}

TEST(LoadMesh, TruncatedBinaryPly) {
  // Each of these crashes or hangs assimp 5.2.5 when given to it directly.
  GPUCOL_REQUIRE_MESH(source, "torus-1152.ply");
  const std::string bytes = test::readBytes(source);
  test::TempDir dir;
  const std::string inFaces = dir.write("faces.ply", bytes.substr(0, 15000));
  EXPECT_CONTAINS(loadError(inFaces), inFaces + ": malformed PLY file: truncated: element 'face' record ");
  EXPECT_CONTAINS(loadError(inFaces), "of 1152 (property 'vertex_indices')");
  const std::string inVertices = dir.write("vertices.ply", bytes.substr(0, 5000));
  EXPECT_CONTAINS(
      loadError(inVertices),
      inVertices + ": malformed PLY file: truncated: element 'vertex' declares 576 records of 12 bytes");
  const std::string inHeader = dir.write("header.ply", bytes.substr(0, 200));
  EXPECT_EQ(loadError(inHeader), inHeader + ": malformed PLY file: the header has no 'end_header' line");
  const std::string lastByte = dir.write("last.ply", bytes.substr(0, bytes.size() - 1));
  EXPECT_CONTAINS(loadError(lastByte), "record 1151 of 1152");
}

TEST(LoadMesh, MalformedPlyHeadersAndAsciiBodies) {
  test::TempDir dir;
  const std::string head =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
  const std::string good = dir.write("good.ply", head + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  EXPECT_EQ(loadMesh(good).triangleCount(), 1u);
  const std::string shortBody = dir.write("short.ply", head + "0 0 0\n1 0 0\n0 1 0\n");
  EXPECT_EQ(loadError(shortBody),
            shortBody + ": malformed PLY file: truncated: the file ends before element 'face' record 0 of 1");
  const std::string shortLine = dir.write("line.ply", head + "0 0 0\n1 0\n0 1 0\n3 0 1 2\n");
  EXPECT_EQ(loadError(shortLine), shortLine +
                                      ": malformed PLY file: element 'vertex' record 1 (line 2 of the body) "
                                      "has 2 values where 3 are expected");
  const std::string word = dir.write("word.ply", head + "0 0 0\n1 0 zero\n0 1 0\n3 0 1 2\n");
  EXPECT_CONTAINS(loadError(word),
                  "element 'vertex' record 1 (line 2 of the body): property 'z' has the value 'zero'");
  const std::string badList = dir.write("list.ply", head + "0 0 0\n1 0 0\n0 1 0\n3 0 1\n");
  EXPECT_CONTAINS(loadError(badList),
                  "element 'face' record 0 (line 4 of the body) has 3 values where 4 are expected");
  const std::string hugeList = dir.write("hugelist.ply", head + "0 0 0\n1 0 0\n0 1 0\n999999999999 0 1 2\n");
  EXPECT_CONTAINS(loadError(hugeList), "element 'face' record 0 (line 4 of the body) has 4 values where");
  const std::string badType =
      dir.write("type.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty quad x\nend_header\n0\n");
  EXPECT_CONTAINS(loadError(badType), "unknown property type in 'property quad x'");
  const std::string badFormat = dir.write("format.ply", "ply\nformat binary_middle_endian 1.0\nend_header\n");
  EXPECT_CONTAINS(loadError(badFormat), "unknown format 'binary_middle_endian'");
  // A huge declared count with a tiny body is caught without overflow or allocation.
  const std::string huge = dir.write("huge.ply",
                                     "ply\nformat binary_little_endian 1.0\nelement vertex 4294967295\n"
                                     "property float x\nproperty float y\nproperty float z\nend_header\n");
  EXPECT_CONTAINS(loadError(huge), "truncated: element 'vertex' declares 4294967295 records");
  // assimp keeps counts in 32 bits; a larger one is refused before it could wrap.
  const std::string above =
      dir.write("above.ply",
                "ply\nformat binary_little_endian 1.0\nelement vertex 18446744073709551615\n"
                "property float x\nproperty float y\nproperty float z\nend_header\n");
  EXPECT_CONTAINS(loadError(above), "element 'vertex' count 18446744073709551615 is above 4294967295");
  // Out-of-range and negative indices are caught by assimp's structure validation, which names the
  // face and the corner.
  const std::string outOfRange = dir.write("range.ply", head + "0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n");
  EXPECT_EQ(loadError(outOfRange), outOfRange +
                                       ": assimp cannot read the mesh file: Validation failed: "
                                       "aiMesh::mFaces[0]::mIndices[2] is out of range");
  const std::string negative = dir.write("negative.ply", head + "0 0 0\n1 0 0\n0 1 0\n3 0 -1 2\n");
  EXPECT_CONTAINS(loadError(negative), "aiMesh::mFaces[0]::mIndices[1] is out of range");
  const std::string nan = dir.write("nan.ply", head + "0 0 0\n1 nan 0\n0 1 0\n3 0 1 2\n");
  EXPECT_CONTAINS(loadError(nan), nan +
                                      ": malformed PLY file: element 'vertex' record 1 (line 2 of the body): "
                                      "property 'y' has the value 'nan', not a finite decimal number");
  // strtod reads hexadecimal, assimp does not.
  const std::string hex = dir.write("hex.ply", head + "0 0 0\n0x10 0 0\n0 1 0\n3 0 1 2\n");
  EXPECT_CONTAINS(loadError(hex), "property 'x' has the value '0x10', not a finite decimal number");
  // In a binary file a NaN is a well-formed float; validation names the vertex and the coordinate.
  std::string binary =
      "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
  const float xyz[9] = {0, 0, 0, 1, 0, 0, 0, 1, std::numeric_limits<float>::quiet_NaN()};
  const std::int32_t face[3] = {0, 1, 2};
  binary.append(reinterpret_cast<const char*>(xyz), sizeof xyz);
  binary.push_back(3);
  binary.append(reinterpret_cast<const char*>(face), sizeof face);
  const std::string binaryNan = dir.write("nan-binary.ply", binary);
  EXPECT_EQ(loadError(binaryNan), binaryNan + ": vertex 2 has a non-finite coordinate z = nan");
}

}  // namespace
}  // namespace gpucol
