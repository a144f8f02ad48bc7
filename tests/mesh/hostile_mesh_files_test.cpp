// A corpus of hostile and unusual mesh files, made here byte by byte, each with its exact outcome: the
// geometry it loads as, or the MeshError it gives (the whole message after the path). Every file is loaded in
// a child process limited to 64 MB of address space and 10 s (limited_load.h), so a reader that allocates by
// a declared count or loops forever fails its case instead of taking the machine. Every message must be
// printable ASCII.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <numeric>
#include <string>
#include <vector>

#include "limited_load.h"
#include "mesh_test_util.h"

namespace gpucol::test {
namespace {

constexpr std::size_t kMemoryLimit = 64u << 20;
constexpr unsigned kSeconds = 10;

/// A file and what loading it must give.
struct Case {
  std::string file;
  std::string bytes;
  std::string error;  ///< The MeshError's text after "<path>: "; empty when the file must load.
  std::size_t vertices = 0, triangles = 0;
  bool closed = false;
  std::vector<float> xyz;              ///< When not empty: the exact positions.
  std::vector<std::uint32_t> indices;  ///< When not empty: the exact triangles.
};

Case refused(std::string file, std::string bytes, std::string error) {
  Case c;
  c.file = std::move(file), c.bytes = std::move(bytes), c.error = std::move(error);
  return c;
}

Case loads(std::string file, std::string bytes, std::size_t vertices, std::size_t triangles, bool closed) {
  Case c;
  c.file = std::move(file), c.bytes = std::move(bytes);
  c.vertices = vertices, c.triangles = triangles, c.closed = closed;
  return c;
}

Case loadsExactly(std::string file, std::string bytes, std::vector<float> xyz,
                  std::vector<std::uint32_t> indices) {
  Case c = loads(std::move(file), std::move(bytes), xyz.size() / 3, indices.size() / 3, false);
  c.xyz = std::move(xyz), c.indices = std::move(indices);
  c.closed = false;
  return c;
}

bool printableAscii(const std::string& text) {
  for (const char c : text) {
    if (c < 0x20 || c > 0x7e) return false;
  }
  return true;
}

/// Writes every case, loads it within the limits and compares.
void expectOutcomes(const std::vector<Case>& cases) {
  TempDir dir;
  for (const Case& c : cases) {
    SCOPED_TRACE(c.file);
    const std::string path = dir.write(c.file, c.bytes);
    const LimitedLoad got = loadWithinLimits(path, kMemoryLimit, kSeconds);
    if (!c.error.empty()) {
      ASSERT_EQ(got.outcome, LimitedLoad::Outcome::kMeshError) << got.message;
      EXPECT_EQ(got.message, path + ": " + c.error);
      EXPECT_TRUE(printableAscii(got.message.substr(path.size()))) << got.message;
      continue;
    }
    ASSERT_EQ(got.outcome, LimitedLoad::Outcome::kLoaded) << got.message;
    EXPECT_EQ(got.xyz.size(), 3 * c.vertices);
    EXPECT_EQ(got.indices.size(), 3 * c.triangles);
    if (c.xyz.empty()) {
      EXPECT_EQ(got.closed, c.closed);
    } else {
      // Bit for bit: -0 stays -0.
      ASSERT_EQ(got.xyz.size(), c.xyz.size());
      EXPECT_EQ(std::memcmp(got.xyz.data(), c.xyz.data(), 4 * c.xyz.size()), 0);
      EXPECT_EQ(got.xyz, c.xyz);
    }
    if (!c.indices.empty()) {
      EXPECT_EQ(got.indices, c.indices);
    }
  }
}

// --- byte builders
// ---------------------------------------------------------------------------------------------

template <typename T>
std::string bytesOf(T value, bool bigEndian = false) {
  std::string out(reinterpret_cast<const char*>(&value), sizeof value);
  if (bigEndian) out = std::string(out.rbegin(), out.rend());
  return out;
}

std::string plyHead(const std::string& format, const std::string& elements) {
  return "ply\nformat " + format + " 1.0\n" + elements + "end_header\n";
}

const std::string kXyz = "property float x\nproperty float y\nproperty float z\n";
const std::string kTriangleHead = plyHead(
    "ascii", "element vertex 3\n" + kXyz + "element face 1\nproperty list uchar int vertex_indices\n");
const std::string kTriangle =
    "0 0 0\n1 0 0\n0 1 0\n";  // lines 10 to 12 below kTriangleHead; the face is line 13
const std::vector<float> kTriangleXyz = {0, 0, 0, 1, 0, 0, 0, 1, 0};

const std::string kTetraVertices = "0 0 0\n1 0 0\n0 1 0\n0 0 1\n";
const std::string kTetraFaces = "3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n";

/// A binary PLY of `xyz` and triangles, in either byte order, uchar counts and int indices.
std::string binaryPly(const std::vector<float>& xyz, const std::vector<std::uint32_t>& tris, bool big) {
  std::string out =
      plyHead(big ? "binary_big_endian" : "binary_little_endian",
              "element vertex " + std::to_string(xyz.size() / 3) + "\n" + kXyz + "element face " +
                  std::to_string(tris.size() / 3) + "\nproperty list uchar int vertex_indices\n");
  for (float v : xyz) out += bytesOf(v, big);
  for (std::size_t t = 0; t < tris.size(); t += 3) {
    out += char(3);
    for (int k = 0; k < 3; ++k) out += bytesOf(std::int32_t(tris[t + std::size_t(k)]), big);
  }
  return out;
}

/// A binary STL of triangles given by their 9 coordinates each, with the given 80-byte header start.
std::string binaryStl(const std::vector<std::vector<float>>& triangles, const std::string& header = "",
                      std::uint32_t count = UINT32_MAX) {
  std::string out = header;
  out.resize(80, ' ');
  out += bytesOf(count == UINT32_MAX ? std::uint32_t(triangles.size()) : count);
  for (const auto& t : triangles) {
    for (int k = 0; k < 3; ++k) out += bytesOf(0.0f);
    for (float v : t) out += bytesOf(v);
    out += std::string(2, '\0');
  }
  return out;
}

/// A strictly convex polygon with integer corners (exact in float), counter-clockwise: its edges are the
/// primitive vectors (a, b) with 1 <= a, b <= m, in order of angle, turned into each quadrant.
std::vector<std::array<int, 2>> convexLatticePolygon(int m) {
  std::vector<std::array<int, 2>> edges;
  for (int a = 1; a <= m; ++a) {
    for (int b = 1; b <= m; ++b) {
      if (std::gcd(a, b) == 1) edges.push_back({a, b});
    }
  }
  // Angle order in the first quadrant, from (m, 1) to (1, m).
  std::sort(edges.begin(), edges.end(),
            [](const auto& p, const auto& q) { return p[0] * q[1] - p[1] * q[0] > 0; });
  std::vector<std::array<int, 2>> corners;
  std::array<int, 2> at = {0, 0};
  for (int quadrant = 0; quadrant < 4; ++quadrant) {
    for (std::array<int, 2> e : edges) {
      for (int turn = 0; turn < quadrant; ++turn) e = {-e[1], e[0]};
      corners.push_back(at);
      at = {at[0] + e[0], at[1] + e[1]};
    }
  }
  return corners;
}

const std::vector<std::vector<float>> kTetraFacets = {{0, 0, 0, 0, 1, 0, 1, 0, 0},
                                                      {0, 0, 0, 1, 0, 0, 0, 0, 1},
                                                      {0, 0, 0, 0, 0, 1, 0, 1, 0},
                                                      {1, 0, 0, 0, 1, 0, 0, 0, 1}};

std::string asciiFacet(const std::string& normal, const std::vector<std::string>& vertices) {
  std::string out = "facet normal " + normal + "\nouter loop\n";
  for (const std::string& v : vertices) out += "vertex " + v + "\n";
  return out + "endloop\nendfacet\n";
}

const std::string kBlenderCube =
    "# Blender v2.93 OBJ File\nmtllib cube.mtl\no Cube\nv 1 1 -1\nv 1 -1 -1\nv 1 1 1\nv 1 -1 1\nv -1 1 -1\n"
    "v -1 -1 -1\nv -1 1 1\nv -1 -1 1\nvt 0.625 0.5\nvn 0 1 0\nvn 0 0 1\nvn -1 0 0\nvn 0 -1 0\nvn 1 0 0\n"
    "vn 0 0 -1\nusemtl Material\ns off\nf 1/1/1 5/1/1 7/1/1 3/1/1\nf 4/1/2 3/1/2 7/1/2 8/1/2\n"
    "f 8/1/3 7/1/3 5/1/3 6/1/3\nf 6/1/4 2/1/4 4/1/4 8/1/4\nf 2/1/5 1/1/5 3/1/5 4/1/5\nf 6/1/6 5/1/6 1/1/6 "
    "2/1/6\n";

// --- the corpus
// ------------------------------------------------------------------------------------------------

TEST(HostileMeshFiles, MemoryAndDeclaredCounts) {
  std::vector<Case> cases;
  // 22 bytes on which assimp allocated without bound: a format gpucol does not read is not read at all.
  cases.push_back(
      refused("tiny.nff", "tpp 99999999999 0 0 0\n",
              "unsupported mesh file type '.nff'; gpucol reads PLY (.ply), OBJ (.obj), STL (.stl) and "
              "OFF (.off) mesh files"));
  cases.push_back(
      refused("huge-vertices.off", "OFF\n1000000000 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
              "malformed OFF file: line 2: truncated: 1000000000 vertices and 1 faces need at least "
              "6000000001 bytes, but only 26 follow the line of counts"));
  cases.push_back(
      refused("huge-faces.off", "OFF\n3 100000000 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
              "malformed OFF file: line 2: truncated: 3 vertices and 100000000 faces need at least "
              "200000017 bytes, but only 26 follow the line of counts"));
  cases.push_back(
      refused("huge.ply",
              plyHead("binary_little_endian", "element vertex 4294967295\n" + kXyz +
                                                  "element face 1\nproperty list uchar int vertex_indices\n"),
              "malformed PLY file: truncated: element 'vertex' declares 4294967295 records of at least "
              "12 bytes, but only 0 bytes follow the header (file size 178)"));
  cases.push_back(
      refused("huge-ascii.ply",
              plyHead("ascii", "element vertex 1000000000\n" + kXyz +
                                   "element face 1\nproperty list uchar int vertex_indices\n") +
                  kTriangle + "3 0 1 2\n",
              "malformed PLY file: truncated: element 'vertex' declares 1000000000 records of at least "
              "6 bytes, but only 26 bytes follow the header (file size 189)"));
  cases.push_back(
      refused("above.ply", plyHead("binary_little_endian", "element vertex 18446744073709551615\n" + kXyz),
              "malformed PLY file: line 3: element 'vertex' count '18446744073709551615' is out of "
              "range (0 to 4294967295)"));
  // Records of no bytes: no file size would bound them.
  cases.push_back(
      refused("empty-records.ply",
              plyHead("binary_little_endian", "element vertex 1\n" + kXyz + "element face 4000000000\n"),
              "malformed PLY file: element 'face' has no list 'vertex_indices' (or 'vertex_index')"));
  cases.push_back(
      refused("no-properties.ply",
              plyHead("binary_little_endian", "element vertex 3\n" + kXyz +
                                                  "element face 1\nproperty list uchar int "
                                                  "vertex_indices\nelement junk 4000000000\n") +
                  std::string(49, '\0'),
              "malformed PLY file: element 'junk' declares 4000000000 records but no properties"));
  // A binary list of 4e9 items in a file of a few bytes.
  {
    std::string ply =
        plyHead("binary_little_endian",
                "element vertex 3\n" + kXyz + "element face 1\nproperty list uint int vertex_indices\n");
    for (float v : kTriangleXyz) ply += bytesOf(v);
    ply += bytesOf(std::uint32_t(4000000000u)) + bytesOf(std::int32_t(0)) + bytesOf(std::int32_t(1));
    cases.push_back(
        refused("long-list.ply", ply,
                "malformed PLY file: truncated: element 'face' record 0 property 'vertex_indices' of 1 "
                "needs 16000000000 bytes at offset 208, but the file ends at 216"));
  }
  cases.push_back(
      refused("long-list.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n4294967295 0 1 2\n",
              "malformed OFF file: line 6: face 0 declares 4294967295 corners but the line holds 3 "
              "values after the count (colours and other values on a face line are refused)"));
  cases.push_back(
      refused("huge-count.stl", binaryStl(kTetraFacets, "binary", 4000000000u),
              "malformed STL file: neither binary STL (84 + 50 N bytes for the N facets declared at byte "
              "80: 4000000000 facets need 200000000084 bytes, the file has 284) nor ASCII STL (starting "
              "with 'solid'); it starts with 'binary          '..."));
  cases.push_back(
      refused("far-index.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 99999999999\n",
              "malformed OBJ file: line 4: corner 3: the vertex index '99999999999' names no vertex: 3 "
              "defined before this line"));
  // A convex polygon of 4,996 corners is a fan; a non-convex one beyond 1,024 corners is refused (ear
  // clipping costs the square of the corners).
  {
    const std::vector<std::array<int, 2>> polygon = convexLatticePolygon(35);
    std::string off = "OFF\n" + std::to_string(polygon.size()) + " 1 0\n",
                face = std::to_string(polygon.size());
    for (std::size_t k = 0; k < polygon.size(); ++k) {
      off += std::to_string(polygon[k][0]) + " " + std::to_string(polygon[k][1]) + " 0\n";
      face += " " + std::to_string(k);
    }
    cases.push_back(loads("convex.off", off + face + "\n", polygon.size(), polygon.size() - 2, false));
    std::string star = "OFF\n2000 1 0\n", starFace = "2000";
    for (int k = 0; k < 2000; ++k) {
      const double a = 2 * M_PI * k / 2000, r = k % 2 ? 1000.0 : 500.0;
      star += std::to_string(std::lround(r * std::cos(a))) + " " +
              std::to_string(std::lround(r * std::sin(a))) + " 0\n";
      starFace += " " + std::to_string(k);
    }
    cases.push_back(
        refused("star.off", star + starFace + "\n",
                "malformed OFF file: line 2003: the non-convex polygon has 2000 corners; gpucol splits "
                "non-convex polygons of at most 1024 corners"));
  }
  expectOutcomes(cases);
}

TEST(HostileMeshFiles, Off) {
  const std::string tetra = "OFF\n4 4 0\n" + kTetraVertices;
  std::vector<Case> cases;
  cases.push_back(loadsExactly("tetra.off", tetra + kTetraFaces, {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1},
                               {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3}));
  // Comments, blank lines, tabs and "\r\n" are fine.
  cases.push_back(
      loads("comments.off",
            "# made by hand\r\nOFF\r\n\r\n4 4 0 # counts\r\n0\t0 0\r\n1 0 0\n0 1 0\n0 0 1\n" + kTetraFaces, 4,
            4, true));
  // 3 1 2 7 loaded as (1, 2, 3): a valid-looking closed tetrahedron made of a wrong face.
  cases.push_back(
      refused("index.off", tetra + "3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 7\n",
              "malformed OFF file: line 10: face 3 corner 3: the vertex index '7' is out of range for 4 "
              "vertices (0 to 3)"));
  cases.push_back(
      refused("negative.off", tetra + "3 0 2 1\n3 0 1 3\n3 0 3 -2\n3 1 2 3\n",
              "malformed OFF file: line 9: face 2 corner 3: the vertex index '-2' is out of range for 4 "
              "vertices (0 to 3)"));
  cases.push_back(
      refused("fraction.off", tetra + "3 0 2 1.5\n" + kTetraFaces.substr(8),
              "malformed OFF file: line 7: face 0 corner 3: the vertex index '1.5' is not an integer"));
  // Corner counts that do not match the line were dropped.
  cases.push_back(
      refused("short-face.off", tetra + "3 0 2 1\n4 0 1 3\n3 0 3 2\n3 1 2 3\n",
              "malformed OFF file: line 8: face 1 declares 4 corners but the line holds 3 values after "
              "the count (colours and other values on a face line are refused)"));
  cases.push_back(
      refused("colour.off", tetra + "3 0 2 1 255 0 0\n" + kTetraFaces.substr(8),
              "malformed OFF file: line 7: face 0 declares 3 corners but the line holds 6 values after "
              "the count (colours and other values on a face line are refused)"));
  cases.push_back(
      refused("line.off", tetra + "2 0 1\n" + kTetraFaces.substr(8),
              "malformed OFF file: line 7: face 0 has 2 corners; a face needs at least 3 (points and "
              "lines are refused)"));
  cases.push_back(
      refused("point.off", tetra + "1 0\n" + kTetraFaces.substr(8),
              "malformed OFF file: line 7: face 0 has 1 corner; a face needs at least 3 (points and "
              "lines are refused)"));
  cases.push_back(refused("repeat.off", tetra + "3 0 2 0\n" + kTetraFaces.substr(8),
                          "malformed OFF file: line 7: the face repeats vertex 0 (corners 1 and 3 of 3)"));
  // 2^32 + 4 was read as 4.
  cases.push_back(refused("wrapped.off", "OFF\n4294967300 4 0\n" + kTetraVertices + kTetraFaces,
                          "malformed OFF file: line 2: the vertex count '4294967300' is out of range (0 to "
                          "4294967295)"));
  cases.push_back(
      refused("negative-count.off", "OFF\n-4 4 0\n" + kTetraVertices + kTetraFaces,
              "malformed OFF file: line 2: the vertex count '-4' is out of range (0 to 4294967295)"));
  cases.push_back(
      refused("two-counts.off", "OFF\n4 4\n" + kTetraVertices + kTetraFaces,
              "malformed OFF file: line 2: the line of counts must hold three integers: vertices, faces "
              "and edges"));
  // 20-digit integer coordinates were read as 0; an 18-digit one is kept, rounded once to float.
  cases.push_back(
      refused("digits20.off", "OFF\n4 4 0\n12345678901234567890 0 0\n1 0 0\n0 1 0\n0 0 1\n" + kTetraFaces,
              "malformed OFF file: line 3: vertex 0 coordinate x '12345678901234567890' is beyond "
              "gpucol's limit of +-1e+18"));
  cases.push_back(loadsExactly("digits18.off", "OFF\n3 1 0\n123456789012345678 0 0\n0 1 0\n0 0 1\n3 0 1 2\n",
                               {float(123456789012345678.0), 0, 0, 0, 1, 0, 0, 0, 1}, {0, 1, 2}));
  cases.push_back(loadsExactly("exponents.off", "OFF\n3 1 0\n1e3 -2.5E-1 +.5\n-0 0 0\n0 1 0\n3 0 1 2\n",
                               {1000, -0.25f, 0.5f, -0.0f, 0, 0, 0, 1, 0}, {0, 1, 2}));
  cases.push_back(
      refused("word.off", "OFF\n3 1 0\n0 0 zero\n1 0 0\n0 1 0\n3 0 1 2\n",
              "malformed OFF file: line 3: vertex 0 coordinate z 'zero' is not a decimal number"));
  cases.push_back(refused("nan.off", "OFF\n3 1 0\n0 0 0\n1 nan 0\n0 1 0\n3 0 1 2\n",
                          "malformed OFF file: line 4: vertex 1 coordinate y 'nan' is not finite"));
  cases.push_back(
      refused("hex.off", "OFF\n3 1 0\n0x10 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
              "malformed OFF file: line 3: vertex 0 coordinate x '0x10' is not a decimal number"));
  cases.push_back(refused("overflow.off", "OFF\n3 1 0\n1e400 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
                          "malformed OFF file: line 3: vertex 0 coordinate x '1e400' is out of range"));
  cases.push_back(refused("four-values.off", "OFF\n3 1 0\n0 0 0 1\n1 0 0\n0 1 0\n3 0 1 2\n",
                          "malformed OFF file: line 3: vertex 0 has 4 values; a vertex line holds x y z"));
  cases.push_back(
      refused("coff.off", "COFF\n3 1 0\n0 0 0 1 1 1 1\n1 0 0 1 1 1 1\n0 1 0 1 1 1 1\n3 0 1 2\n",
              "malformed OFF file: line 1: the header 'COFF' announces a variant (colours, normals, "
              "texture coordinates or other dimensions); gpucol reads plain OFF"));
  cases.push_back(
      refused("binary.off", "OFF BINARY\n",
              "malformed OFF file: line 1: the header line must be 'OFF' alone (binary OFF and counts "
              "on it are refused)"));
  cases.push_back(
      refused("inline.off", "OFF 3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
              "malformed OFF file: line 1: the header line must be 'OFF' alone (binary OFF and counts "
              "on it are refused)"));
  cases.push_back(refused("headless.off", "3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
                          "malformed OFF file: line 1: it does not start with the line 'OFF' but with '3'"));
  cases.push_back(
      refused("more-faces.off", tetra + kTetraFaces + "3 0 1 2\n",
              "malformed OFF file: line 11: text after the last face; the line of counts declares 4 "
              "faces"));
  cases.push_back(refused("fewer-faces.off", tetra + kTetraFaces.substr(0, 24),
                          "malformed OFF file: truncated: the file ends before face 3 of 4"));
  cases.push_back(
      refused("control.off", "OFF\n3 1 0\n0 0 0\n1\f0 0\n0 1 0\n3 0 1 2\n",
              "malformed OFF file: line 4: control byte 0x0c at column 2; text may hold only printable "
              "characters, spaces and tabs"));
  cases.push_back(refused("comments-only.off", "# nothing\n\n",
                          "malformed OFF file: the file holds only comments "
                          "and blank lines"));
  // A quad cube written with a vertex per face corner (24) is welded into its 8 corners: closed.
  {
    std::string off = "OFF\n24 6 0\n";
    std::string faces;
    const int quads[6][4] = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4},
                             {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}};
    const char* corners[8] = {"0 0 0", "1 0 0", "1 1 0", "0 1 0", "0 0 1", "1 0 1", "1 1 1", "0 1 1"};
    for (int f = 0; f < 6; ++f) {
      faces += "4";
      for (int k = 0; k < 4; ++k) {
        off += std::string(corners[quads[f][k]]) + "\n";
        faces += " " + std::to_string(4 * f + k);
      }
      faces += "\n";
    }
    cases.push_back(loads("quad-cube.off", off + faces, 8, 12, true));
  }
  expectOutcomes(cases);
}

TEST(HostileMeshFiles, PlyNumbersAndIndices) {
  const std::string head = kTriangleHead;
  const std::string uintHead = plyHead(
      "ascii", "element vertex 3\n" + kXyz + "element face 1\nproperty list uchar uint vertex_indices\n");
  std::vector<Case> cases;
  cases.push_back(loadsExactly("good.ply", head + kTriangle + "3 0 1 2\n", kTriangleXyz, {0, 1, 2}));
  // Read as 2, 2 and 0 before.
  cases.push_back(
      refused("index-wraps.ply", uintHead + kTriangle + "3 0 1 4294967298\n",
              "malformed PLY file: line 13: element 'face' record 0 property 'vertex_indices': the value "
              "'4294967298' is out of range for uint (0 to 4294967295)"));
  cases.push_back(
      refused("index-fraction.ply", head + kTriangle + "3 0 1 2.5\n",
              "malformed PLY file: line 13: element 'face' record 0 property 'vertex_indices': the value "
              "'2.5' is not an integer"));
  cases.push_back(
      refused("uchar.ply",
              plyHead("ascii", "element vertex 3\n" + kXyz +
                                   "property uchar red\nelement face 1\n"
                                   "property list uchar int vertex_indices\n") +
                  "0 0 0 -253\n1 0 0 0\n0 1 0 0\n3 0 1 2\n",
              "malformed PLY file: line 11: element 'vertex' record 0 property 'red': the value '-253' is "
              "out of range for uchar (0 to 255)"));
  cases.push_back(
      refused("count-type.ply", head + kTriangle + "300 0 1 2\n",
              "malformed PLY file: line 13: element 'face' record 0 property 'vertex_indices': the value "
              "'300' is out of range for uchar (0 to 255)"));
  cases.push_back(
      refused("digits20.ply", head + "12345678901234567890 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
              "malformed PLY file: line 10: element 'vertex' record 0 property 'x': the coordinate "
              "1.23457e+19 is beyond gpucol's limit of +-1e+18"));
  cases.push_back(
      refused("float-overflow.ply",
              plyHead("ascii", "element vertex 3\n" + kXyz +
                                   "property float s\nelement face 1\n"
                                   "property list uchar int vertex_indices\n") +
                  "0 0 0 1e39\n1 0 0 0\n0 1 0 0\n3 0 1 2\n",
              "malformed PLY file: line 11: element 'vertex' record 0 property 's': the value '1e39' is "
              "out of range for float"));
  cases.push_back(
      refused("out-of-range.ply", head + kTriangle + "3 0 1 7\n",
              "malformed PLY file: line 13: element 'face' record 0 property 'vertex_indices': the vertex "
              "index 7 is out of range for 3 vertices"));
  cases.push_back(
      refused("negative.ply", head + kTriangle + "3 0 -1 2\n",
              "malformed PLY file: line 13: element 'face' record 0 property 'vertex_indices': the vertex "
              "index -1 is out of range for 3 vertices"));
  cases.push_back(
      refused("nan.ply", head + "0 0 0\n1 nan 0\n0 1 0\n3 0 1 2\n",
              "malformed PLY file: line 11: element 'vertex' record 1 property 'y': the value 'nan' is not "
              "finite"));
  cases.push_back(
      refused("hex.ply", head + "0 0 0\n0x10 0 0\n0 1 0\n3 0 1 2\n",
              "malformed PLY file: line 11: element 'vertex' record 1 property 'x': the value '0x10' is "
              "not a decimal number"));
  cases.push_back(
      refused("word.ply", head + "0 0 0\n1 0 zero\n0 1 0\n3 0 1 2\n",
              "malformed PLY file: line 11: element 'vertex' record 1 property 'z': the value 'zero' is "
              "not a decimal number"));
  cases.push_back(
      refused("short-line.ply", head + "0 0 0\n1 0\n0 1 0\n3 0 1 2\n",
              "malformed PLY file: line 11: element 'vertex' record 1 ends before property 'z' (2 values on "
              "the line)"));
  cases.push_back(
      refused("long-line.ply", head + "0 0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
              "malformed PLY file: line 10: element 'vertex' record 0 has 4 values where 3 are expected "
              "(an ASCII record is one line)"));
  cases.push_back(
      refused("short-list.ply", head + kTriangle + "3 0 1\n",
              "malformed PLY file: line 13: element 'face' record 0 has 3 values, too few for a list of 3 "
              "in property 'vertex_indices'"));
  cases.push_back(
      refused("empty-face.ply", head + kTriangle + "0\n",
              "malformed PLY file: line 13: element 'face' record 0 property 'vertex_indices': a face of 0 "
              "corners; a face needs at least 3 (points and lines are refused)"));
  cases.push_back(
      refused("line-face.ply", head + kTriangle + "2 0 1\n",
              "malformed PLY file: line 13: element 'face' record 0 property 'vertex_indices': a face of 2 "
              "corners; a face needs at least 3 (points and lines are refused)"));
  cases.push_back(refused("repeat.ply", head + kTriangle + "3 0 1 1\n",
                          "malformed PLY file: line 13: the face repeats vertex 1 (corners 2 and 3 of 3)"));
  cases.push_back(
      refused("short-body.ply", head + kTriangle,
              "malformed PLY file: truncated: element 'face' declares 1 records of at least 2 bytes "
              "(after the elements before it), but only 18 bytes follow the header (file size 172)"));
  cases.push_back(refused("trailing.ply", head + kTriangle + "3 0 1 2\n3 0 2 1\n",
                          "malformed PLY file: line 14: text after the last record of the last element"));
  // A value that is not a number in a property gpucol skips is refused all the same.
  cases.push_back(
      refused("skipped-nan.ply",
              plyHead("ascii", "element vertex 3\n" + kXyz +
                                   "property float nx\nelement face 1\n"
                                   "property list uchar int vertex_indices\n") +
                  "0 0 0 nan\n1 0 0 0\n0 1 0 0\n3 0 1 2\n",
              "malformed PLY file: line 11: element 'vertex' record 0 property 'nx': the value 'nan' is "
              "not finite"));
  expectOutcomes(cases);
}

TEST(HostileMeshFiles, PlyStructure) {
  const std::string vertex = "element vertex 3\n" + kXyz;
  const std::string face = "element face 1\nproperty list uchar int vertex_indices\n";
  const std::string body = kTriangle + "3 0 1 2\n";
  std::vector<Case> cases;
  // The second element overwrote the first, or was dropped.
  cases.push_back(refused("two-vertex.ply", plyHead("ascii", vertex + face + vertex) + body + kTriangle,
                          "malformed PLY file: line 9: a second element 'vertex' (the first is on line 3)"));
  cases.push_back(refused("two-face.ply", plyHead("ascii", vertex + face + face) + body + "3 0 1 2\n",
                          "malformed PLY file: line 9: a second element 'face' (the first is on line 7)"));
  cases.push_back(
      refused("tristrips.ply",
              plyHead("ascii", vertex + "element tristrips 1\nproperty list int int vertex_indices\n") +
                  kTriangle + "3 0 1 2\n",
              "malformed PLY file: line 7: element 'tristrips' holds geometry gpucol does not read; "
              "store the triangles in element 'face'"));
  cases.push_back(
      refused("range-grid.ply", plyHead("ascii", vertex + face + "element range_grid 1\n"),
              "malformed PLY file: line 9: element 'range_grid' holds geometry gpucol does not read; "
              "store the triangles in element 'face'"));
  // Coordinates became 0.
  cases.push_back(refused("no-z.ply",
                          plyHead("ascii", "element vertex 3\nproperty float x\nproperty float y\n" + face) +
                              "0 0\n1 0\n0 1\n3 0 1 2\n",
                          "malformed PLY file: element 'vertex' has no property 'z'"));
  cases.push_back(
      refused("list-x.ply",
              plyHead("ascii",
                      "element vertex 3\nproperty list uchar float x\nproperty float y\n"
                      "property float z\n" +
                          face) +
                  "1 0 0 0\n1 1 0 0\n1 0 1 0\n3 0 1 2\n",
              "malformed PLY file: property 'x' of element 'vertex' is a list; a coordinate is a scalar"));
  cases.push_back(refused("no-vertex.ply", plyHead("ascii", face) + "3 0 1 2\n",
                          "malformed PLY file: the header declares no element 'vertex'"));
  cases.push_back(refused("no-face.ply", plyHead("ascii", vertex) + kTriangle,
                          "malformed PLY file: the header declares no element 'face'"));
  cases.push_back(
      refused("scalar-indices.ply",
              plyHead("ascii", vertex + "element face 1\nproperty int vertex_indices\n") + kTriangle + "0\n",
              "malformed PLY file: property 'vertex_indices' of element 'face' is not a list"));
  cases.push_back(
      refused("float-indices.ply",
              plyHead("ascii", vertex + "element face 1\nproperty list uchar float vertex_indices\n") + body,
              "malformed PLY file: the list 'vertex_indices' of element 'face' holds float values; vertex "
              "indices are integers"));
  cases.push_back(refused("both-lists.ply",
                          plyHead("ascii", vertex + face + "property list uchar int vertex_index\n") +
                              kTriangle + "3 0 1 2 3 0 1 2\n",
                          "malformed PLY file: element 'face' has both 'vertex_indices' and 'vertex_index'"));
  cases.push_back(refused("same-property.ply", plyHead("ascii", vertex + "property float x\n" + face) + body,
                          "malformed PLY file: line 7: element 'vertex' has a second property 'x'"));
  cases.push_back(
      refused("float-count.ply",
              plyHead("ascii", vertex + "element face 1\nproperty list float int vertex_indices\n") + body,
              "malformed PLY file: line 8: a list property must read 'property list <integer type> "
              "<type> <name>'"));
  cases.push_back(refused("type.ply", plyHead("ascii", "element vertex 1\nproperty quad x\n") + "0\n",
                          "malformed PLY file: line 4: unknown property type 'quad'"));
  cases.push_back(refused("format.ply", "ply\nformat binary_middle_endian 1.0\nend_header\n",
                          "malformed PLY file: line 2: unknown format 'binary_middle_endian'"));
  cases.push_back(refused("version.ply", "ply\nformat ascii 2.0\nend_header\n",
                          "malformed PLY file: line 2: the format line must read 'format "
                          "<ascii|binary_little_endian|binary_big_endian> 1.0'"));
  cases.push_back(refused("two-formats.ply", "ply\nformat ascii 1.0\nformat ascii 1.0\nend_header\n",
                          "malformed PLY file: line 3: a second 'format' line"));
  cases.push_back(refused("no-format.ply", "ply\n" + vertex + face + "end_header\n" + body,
                          "malformed PLY file: the header has no 'format' line"));
  cases.push_back(refused("no-end.ply", "ply\nformat ascii 1.0\n" + vertex,
                          "malformed PLY file: the header has no 'end_header' line"));
  cases.push_back(refused("end-extra.ply",
                          "ply\nformat ascii 1.0\n" + vertex + face + "end_header now\n" + body,
                          "malformed PLY file: line 9: 'end_header' must stand alone on its line"));
  cases.push_back(refused("property-first.ply", "ply\nformat ascii 1.0\nproperty float x\n" + vertex,
                          "malformed PLY file: line 3: a property before any element"));
  cases.push_back(refused("keyword.ply", "ply\nformat ascii 1.0\nvertex 3\n",
                          "malformed PLY file: line 3: unexpected header line starting with 'vertex'"));
  // Bytes that are not text are shown escaped, never raw.
  cases.push_back(refused("binary-start.ply",
                          std::string("\x7f"
                                      "ELF\x02\x01\x01\0\0\0",
                                      10) +
                              std::string(100, '\0'),
                          "malformed PLY file: it does not start with the line 'ply' but with "
                          "'\\x7fELF\\x02\\x01\\x01\\x00\\x00\\x00\\x00\\x00\\x00\\x00\\x00\\x00'..."));
  cases.push_back(refused("utf8.ply", "ply\nformat ascii 1.0\n\xc3\xa9l\xc3\xa9ment vertex 3\n",
                          "malformed PLY file: line 3: unexpected header line starting with "
                          "'\\xc3\\xa9l\\xc3\\xa9ment'"));
  // Found by the fuzzer (tests/fuzz/findings/loader_hang_assimp_ply.bin, less its first byte): assimp looped
  // forever.
  {
    static const char kFinding[] =
        "ply\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033"
        "\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033"
        "\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033"
        "\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033\033td\"\"\"\"\"\"\""
        "\"\"\""
        "p\000\000\000\"\"\"\"\"\"\"\"\"\"\"\"\"\"\"\"\000ply\nformat ascii 1.0\nelement &ertex 3\nproperty "
        "float x\npro\"\"\"\"\"\"\"\"\"\"\"perty float y\034\000\000\000\000\007\000\000\nproperty float "
        "z\nel\003OFF\n4 4 0\n0 0\n\n0 0 0\000\000\000\000\000\000\000\000\n1 0\0000\n0 1 "
        "0\"\"\"\"\"\"\"\"\"\"\"\"\"\"\"\"\"\"\"\"\"\"\"\"\"\"\"\"\"\"\"\"\"\"\"ar 2 1 2int "
        "vertex_indices\nend "
        "3_header\n\n0 0 0\n3 0 1 2\n\n1 0\0000\n0 1 0\n3 0 1 2=\n";
    const std::string finding(kFinding, sizeof kFinding - 1);
    cases.push_back(refused("finding.ply", finding,
                            "malformed PLY file: it does not start with the line 'ply' but with "
                            "'ply\\x1b\\x1b\\x1b\\x1b\\x1b\\x1b\\x1b\\x1b\\x1b\\x1b\\x1b\\x1b\\x1b'..."));
  }
  cases.push_back(refused("leading-newline.ply", "\nply\nformat ascii 1.0\n",
                          "malformed PLY file: it does not start with the line 'ply' but with "
                          "'\\x0aply\\x0aformat asci'..."));
  cases.push_back(
      refused("zeros.ply", std::string(3000000, '\0'),
              "malformed PLY file: it does not start with the line 'ply' but with "
              "'\\x00\\x00\\x00\\x00\\x00\\x00\\x00\\x00\\x00\\x00\\x00\\x00\\x00\\x00\\x00\\x00'..."));
  cases.push_back(
      refused("vtab.ply", "ply\nformat ascii 1.0\n" + vertex + face + "end_header\v\n" + body,
              "malformed PLY file: line 9: control byte 0x0b at column 11; text may hold only printable "
              "characters, spaces and tabs"));
  cases.push_back(
      refused("feed.ply", plyHead("ascii", vertex + face) + "0 0 0\n1 0\f0\n0 1 0\n3 0 1 2\n",
              "malformed PLY file: line 11: control byte 0x0c at column 4; text may hold only printable "
              "characters, spaces and tabs"));
  // What loads: comments and obj_info anywhere in the header, "\r\n", tabs, extra elements and properties
  // (skipped), the face element before the vertex element, sized type names.
  cases.push_back(loadsExactly(
      "comments.ply",
      "ply\r\nformat ascii 1.0\r\ncomment a\r\nelement face 1\r\nproperty uint8 flags\r\n"
      "property list uint8 int32 vertex_index\r\nobj_info b\r\nelement vertex 3\r\n"
      "property float32 x\r\ncomment between\r\nproperty\tfloat32 y\r\n\r\nproperty float32 z\r\n"
      "property list uchar float uv\r\nelement edge 1\r\nproperty int a\r\nend_header\r\n"
      "7 3 2 1 0\r\n0 0 0 2 0.5 0.5\r\n1 0 0 0\r\n0 1 0 1 9\r\n0\r\n",
      kTriangleXyz, {2, 1, 0}));
  // Polygons are split, and then vertices at equal positions welded; triangles alone keep the file's
  // vertices.
  cases.push_back(loadsExactly(
      "duplicates.ply",
      plyHead("ascii",
              "element vertex 4\n" + kXyz + "element face 1\nproperty list uchar int vertex_indices\n") +
          kTriangle + "0 0 0\n3 0 1 2\n",
      {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 0}, {0, 1, 2}));
  cases.push_back(loadsExactly(
      "quad.ply",
      plyHead("ascii",
              "element vertex 5\n" + kXyz + "element face 1\nproperty list uchar int vertex_indices\n") +
          "0 0 0\n1 0 0\n1 1 0\n0 1 0\n1 0 0\n4 0 4 2 3\n",
      {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0}, {0, 1, 2, 0, 2, 3}));
  expectOutcomes(cases);
}

TEST(HostileMeshFiles, PlyBinary) {
  const std::vector<float> tetraXyz = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
  const std::vector<std::uint32_t> tetraTris = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3};
  const std::string little = binaryPly(tetraXyz, tetraTris, false),
                    big = binaryPly(tetraXyz, tetraTris, true);
  const std::size_t body = little.find("end_header\n") + 11;
  std::vector<Case> cases;
  cases.push_back(loadsExactly("little.ply", little, tetraXyz, tetraTris));
  cases.push_back(loadsExactly("big.ply", big, tetraXyz, tetraTris));
  // Double coordinates, short indices, a char count: rounded once to float, read exactly.
  {
    std::string ply = plyHead("binary_big_endian",
                              "element vertex 3\nproperty double x\nproperty double y\n"
                              "property double z\nelement face 1\nproperty list char ushort "
                              "vertex_indices\n");
    for (double v : {0.1, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, -0.0}) ply += bytesOf(v, true);
    ply += char(3) + bytesOf(std::uint16_t(0), true) + bytesOf(std::uint16_t(1), true) +
           bytesOf(std::uint16_t(2), true);
    cases.push_back(loadsExactly("double.ply", ply, {0.1f, 0, 0, 1, 0, 0, 0, 1, -0.0f}, {0, 1, 2}));
  }
  cases.push_back(
      refused("cut-faces.ply", little.substr(0, little.size() - 5),
              "malformed PLY file: truncated: element 'face' record 3 property 'vertex_indices' of 4 needs "
              "12 bytes at offset 257, but the file ends at 264"));
  cases.push_back(
      refused("cut-vertices.ply", little.substr(0, body + 20),
              "malformed PLY file: truncated: element 'vertex' declares 4 records of at least 12 bytes, but "
              "only 20 bytes follow the header (file size 189)"));
  cases.push_back(refused("cut-header.ply", little.substr(0, little.find("property float y")),
                          "malformed PLY file: the header has no 'end_header' line"));
  cases.push_back(refused("cut-header-line.ply", little.substr(0, little.find("property float y") + 7),
                          "malformed PLY file: line 5: unexpected header line starting with 'propert'"));
  cases.push_back(
      refused("extra-bytes.ply", little + "\n",
              "malformed PLY file: 1 bytes follow the last record of the last element (at offset 269); "
              "the header declares fewer records than the file holds"));
  {
    std::string nan = little;
    const float value = std::nanf("");
    std::memcpy(&nan[body + 4 * 8], &value, 4);
    cases.push_back(
        refused("nan-binary.ply", nan,
                "malformed PLY file: element 'vertex' record 2 property 'z': the value nan is not finite"));
    std::string far = little;
    const float huge = 3e38f;
    std::memcpy(&far[body + 4], &huge, 4);
    cases.push_back(
        refused("far-binary.ply", far,
                "malformed PLY file: element 'vertex' record 0 property 'y': the coordinate 3e+38 is "
                "beyond gpucol's limit of +-1e+18"));
    std::string zero = little;
    zero[body + 48 + 13] = 0;  // the second face's count
    cases.push_back(
        refused("empty-binary-face.ply", zero,
                "malformed PLY file: element 'face' record 1 property 'vertex_indices': a face of 0 "
                "corners; a face needs at least 3 (points and lines are refused)"));
    std::string range = little;
    range[body + 48 + 1] = 9;  // the first face's first index
    cases.push_back(
        refused("range-binary.ply", range,
                "malformed PLY file: element 'face' record 0 property 'vertex_indices': the vertex index 9 "
                "is out of range for 4 vertices"));
    std::string repeated = little;
    repeated[body + 48 + 5] = 0;  // the first face's second index: 0 0 1
    cases.push_back(
        refused("repeat-binary.ply", repeated,
                "malformed PLY file: element 'face' record 0: the face repeats vertex 0 (corners 1 and 2 of "
                "3)"));
  }
  {
    std::string ply =
        plyHead("binary_little_endian",
                "element vertex 3\n" + kXyz + "element face 1\nproperty list char int vertex_indices\n");
    for (float v : kTriangleXyz) ply += bytesOf(v);
    ply += char(-3) + bytesOf(std::int32_t(0)) + bytesOf(std::int32_t(1)) + bytesOf(std::int32_t(2));
    cases.push_back(
        refused("negative-length.ply", ply,
                "malformed PLY file: element 'face' record 0 property 'vertex_indices': the list length -3 "
                "is negative"));
  }
  expectOutcomes(cases);
}

TEST(HostileMeshFiles, Obj) {
  const std::string tetra = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n";
  std::vector<Case> cases;
  // Blender's quad cube: 8 vertices and a closed surface, not 24 vertices and an open one.
  cases.push_back(loads("blender-cube.obj", kBlenderCube, 8, 12, true));
  cases.push_back(loadsExactly("relative.obj", tetra + "f -4 -2 -3\nf 1 2 4\nf -4 -1 -2\nf -3 -2 -1\n",
                               {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1}, {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3}));
  cases.push_back(
      refused("texture-later.obj", tetra + "f 1/1 2/1 3/1\nvt 0 0\n",
              "malformed OBJ file: line 5: corner 1: the texture coordinate index '1' names no texture "
              "coordinate: 0 defined before this line"));
  cases.push_back(loadsExactly(
      "forms.obj", "vt 0 0\nvn 0 0 1\n" + tetra + "f 1/1/1 3//1 2/1\nf 1 2 4\nf -4/-1/-1 4 3\nf 2 3 4\n",
      {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1}, {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3}));
  cases.push_back(loads("colours.obj",
                        "v 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 0 1 0 1 1 1\nv 0 0 1 0.5 0.5 0.5\n"
                        "f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\ng part\ns 1\no name\n",
                        4, 4, true));
  cases.push_back(loads("weight.obj", "v 0 0 0 1\nv 1 0 0 1.0\nv 0 1 0 1\nf 1 2 3\n", 3, 1, false));
  cases.push_back(
      refused("weight2.obj", "v 0 0 0 2\n",
              "malformed OBJ file: line 1: the weight '2' is not 1; rational vertices are not read by "
              "gpucol"));
  cases.push_back(
      refused("two-values.obj", "v 0 0\n",
              "malformed OBJ file: line 1: a vertex holds x y z (optionally w = 1, or r g b colours), not 2 "
              "values"));
  cases.push_back(
      refused("zero.obj", tetra + "f 0 1 2\n",
              "malformed OBJ file: line 5: corner 1: the vertex index '0' is 0; OBJ indices count from 1 "
              "(or back from -1)"));
  cases.push_back(
      refused("forward.obj", "v 0 0 0\nv 1 0 0\nf 1 2 3\nv 0 1 0\n",
              "malformed OBJ file: line 3: corner 3: the vertex index '3' names no vertex: 2 defined before "
              "this line"));
  cases.push_back(
      refused("back-too-far.obj", tetra + "f -5 -1 -2\n",
              "malformed OBJ file: line 5: corner 1: the vertex index '-5' names no vertex: 4 defined "
              "before this line"));
  cases.push_back(refused("fraction.obj", tetra + "f 1 2.0 3\n",
                          "malformed OBJ file: line 5: corner 2: the vertex index '2.0' is not an integer"));
  cases.push_back(
      refused("normal-index.obj", tetra + "vn 0 0 1\nf 1//2 2//1 3//1\n",
              "malformed OBJ file: line 6: corner 1: the normal index '2' names no normal: 1 defined "
              "before this line"));
  cases.push_back(
      refused("bad-corner.obj", tetra + "f 1/1/1/1 2 3\n",
              "malformed OBJ file: line 5: corner 1: the texture coordinate index '1' names no texture "
              "coordinate: 0 defined before this line"));
  cases.push_back(
      refused("slash.obj", tetra + "f 1/ 2 3\n", "malformed OBJ file: line 5: corner 1 '1/' ends in '/'"));
  cases.push_back(
      refused("line.obj", "v 0 0 0\nv 1 0 0\nl 1 2\n",
              "malformed OBJ file: line 3: a line ('l'); gpucol needs faces of at least 3 corners (points "
              "and lines are refused)"));
  cases.push_back(
      refused("two-corners.obj", tetra + "f 1 2\n",
              "malformed OBJ file: line 5: a face of 2 corners; a face needs at least 3 (points and lines "
              "are refused)"));
  cases.push_back(
      refused("curve.obj", "cstype bspline\n",
              "malformed OBJ file: line 1: free-form geometry ('cstype': curves and surfaces) is not read "
              "by gpucol"));
  cases.push_back(refused("unknown.obj", "vx 0 0 0\n", "malformed OBJ file: line 1: unknown statement 'vx'"));
  cases.push_back(
      refused("continued.obj", "v 0 0 \\\n0\n",
              "malformed OBJ file: line 1: line continuations ('\\' at the end of a line) are not read by "
              "gpucol"));
  cases.push_back(refused("no-faces.obj", tetra, "malformed OBJ file: the file has no faces ('f' lines)"));
  cases.push_back(
      refused("nan.obj", "v 0 nan 0\n", "malformed OBJ file: line 1: the coordinate 'nan' is not finite"));
  cases.push_back(
      refused("far.obj", "v 0 3e38 0\n",
              "malformed OBJ file: line 1: the coordinate '3e38' is beyond gpucol's limit of +-1e+18"));
  // Two corners at one position become one vertex: the face is no triangle.
  cases.push_back(
      refused("coincident.obj", "v 0 0 0\nv 1 0 0\nv 0 0 0\nf 1 2 3\n",
              "malformed OBJ file: line 4: corners 1 and 3 of the face are at the same position (0, 0, 0), "
              "so it has a repeated vertex once equal positions are joined"));
  cases.push_back(refused("binary.obj", std::string("v 0 0 0\n\x89PNG\r\n\x1a\n", 15),
                          "malformed OBJ file: line 2: unknown statement '\\x89PNG'"));
  cases.push_back(
      refused("nul.obj", std::string("v 0 0 0\nv 1\0 0 0\n", 17),
              "malformed OBJ file: line 2: control byte 0x00 at column 4; text may hold only printable "
              "characters, spaces and tabs"));
  // An L-shaped hexagon (non-convex) is ear-clipped: 4 triangles covering exactly its area (3).
  cases.push_back(loadsExactly("l-shape.obj",
                               "v 0 0 0\nv 2 0 0\nv 2 1 0\nv 1 1 0\nv 1 2 0\nv 0 2 0\nf 1 2 3 4 5 6\n",
                               {0, 0, 0, 2, 0, 0, 2, 1, 0, 1, 1, 0, 1, 2, 0, 0, 2, 0}, {}));
  cases.back().triangles = 4;
  cases.push_back(
      refused("bow-tie.obj", "v 0 0 0\nv 2 2 0\nv 2 0 0\nv 0 2 0\nf 1 2 3 4\n",
              "malformed OBJ file: line 5: the polygon of 4 corners is not simple (seen along its normal "
              "its edges cross, touch or fold back), so it cannot be split into triangles"));
  cases.push_back(
      loads("pentagon.obj", "v 0 0 0\nv 2 0 0\nv 2 2 0\nv 3 0 0\nv 3 -1 0\nf 1 2 3 4 5\n", 5, 3, false));
  cases.push_back(
      refused("folded.obj", "v 0 0 0\nv 2 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3 4\n",
              "malformed OBJ file: line 5: the polygon of 4 corners is not simple (seen along its normal "
              "its edges cross, touch or fold back), so it cannot be split into triangles"));
  expectOutcomes(cases);
}

TEST(HostileMeshFiles, Stl) {
  std::string ascii = "solid tetra\n";
  for (const auto& t : kTetraFacets) {
    std::vector<std::string> corners;
    for (int k = 0; k < 3; ++k)
      corners.push_back(std::to_string(int(t[std::size_t(3 * k)])) + " " +
                        std::to_string(int(t[std::size_t(3 * k + 1)])) + " " +
                        std::to_string(int(t[std::size_t(3 * k + 2)])));
    ascii += asciiFacet("0 0 0", corners);
  }
  const std::string facet = asciiFacet("0 0 1", {"0 0 0", "1 0 0", "0 1 0"});
  std::vector<Case> cases;
  cases.push_back(loads("ascii.stl", ascii + "endsolid tetra\n", 4, 4, true));
  cases.push_back(loads("binary.stl", binaryStl(kTetraFacets), 4, 4, true));
  // A binary header may start with "solid": the size decides.
  cases.push_back(loads("solid-header.stl", binaryStl(kTetraFacets, "solid made by a CAD tool"), 4, 4, true));
  cases.push_back(loads("upper.stl",
                        "SOLID\r\nFACET NORMAL 0 0 1\r\nOUTER LOOP\r\nVERTEX 0 0 0\r\nVERTEX 1 0 0\r\n"
                        "VERTEX 0 1 0\r\nENDLOOP\r\nENDFACET\r\nENDSOLID\r\n",
                        3, 1, false));
  cases.push_back(loads("two-solids.stl",
                        "solid a\n" + facet + "endsolid a\nsolid b\n" +
                            asciiFacet("0 0 1", {"0 0 1", "1 0 1", "0 1 1"}) + "endsolid b\n",
                        6, 2, false));
  // A fourth vertex was cut silently.
  cases.push_back(
      refused("four.stl",
              "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n"
              "vertex 0 1 0\nvertex 1 1 0\nendloop\nendfacet\nendsolid t\n",
              "malformed STL file: line 7: facet 0 has a fourth vertex; an STL facet is a triangle"));
  cases.push_back(
      refused("two.stl",
              "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n"
              "endloop\nendfacet\nendsolid t\n",
              "malformed STL file: line 6: expected 'vertex and 3 numbers' in facet 0, found a line "
              "starting with 'endloop'"));
  cases.push_back(refused("no-end.stl", "solid t\n" + facet,
                          "malformed STL file: truncated: the file ends before 'endsolid'"));
  cases.push_back(
      refused("after-end.stl", "solid t\n" + facet + "endsolid t\n" + facet,
              "malformed STL file: line 10: only another 'solid' may follow 'endsolid', not 'facet'"));
  cases.push_back(
      refused("empty-solid.stl", "solid t\nendsolid t\n", "malformed STL file: the file has no facets"));
  cases.push_back(refused("nan-normal.stl", "solid t\n" + asciiFacet("nan 0 0", {"0 0 0", "1 0 0", "0 1 0"}),
                          "malformed STL file: line 2: facet 0: the normal component 'nan' is not finite"));
  cases.push_back(
      refused("word.stl", "solid t\n" + asciiFacet("0 0 1", {"0 0 0", "1 zero 0", "0 1 0"}),
              "malformed STL file: line 5: facet 0 vertex 2 coordinate y 'zero' is not a decimal number"));
  cases.push_back(
      refused("far.stl", "solid t\n" + asciiFacet("0 0 1", {"0 0 0", "1 0 0", "0 1 1e20"}),
              "malformed STL file: line 6: facet 0 vertex 3 coordinate z '1e20' is beyond gpucol's limit "
              "of +-1e+18"));
  cases.push_back(
      refused("degenerate.stl", "solid t\n" + asciiFacet("0 0 1", {"0 0 0", "1 0 0", "1 0 0"}) + "endsolid\n",
              "malformed STL file: line 2: corners 2 and 3 of the face are at the same position (1, 0, 0), "
              "so it has a repeated vertex once equal positions are joined"));
  cases.push_back(
      refused("count.stl", binaryStl(kTetraFacets, "binary", 5),
              "malformed STL file: neither binary STL (84 + 50 N bytes for the N facets declared at byte "
              "80: 5 facets need 334 bytes, the file has 284) nor ASCII STL (starting with 'solid'); it "
              "starts with 'binary          '..."));
  cases.push_back(refused("short.stl", "abc",
                          "malformed STL file: neither binary STL (84 + 50 N bytes for the N facets "
                          "declared at byte 80; the file has only 3 bytes) nor ASCII STL (starting "
                          "with 'solid'); it starts with 'abc'"));
  {
    auto facets = kTetraFacets;
    facets[1][4] = std::nanf("");
    cases.push_back(
        refused("nan.stl", binaryStl(facets), "malformed STL file: facet 1 corner 2 coordinate y is nan"));
    facets = kTetraFacets;
    facets[2][8] = -3e38f;
    cases.push_back(
        refused("huge.stl", binaryStl(facets),
                "malformed STL file: facet 2 corner 3 coordinate z is -3e+38, beyond gpucol's limit of "
                "+-1e+18"));
    cases.push_back(
        refused("zero-facets.stl", binaryStl({}), "malformed STL file: the binary file declares 0 facets"));
  }
  expectOutcomes(cases);
}

TEST(HostileMeshFiles, FormatsByExtension) {
  const std::string tail = "; gpucol reads PLY (.ply), OBJ (.obj), STL (.stl) and OFF (.off) mesh files";
  std::vector<Case> cases;
  for (const char* file : {"scene.gltf", "scene.glb", "model.3ds", "model.dae", "model.fbx", "model.x"}) {
    const std::string name = file;
    cases.push_back(
        refused(name, "anything", "unsupported mesh file type '" + name.substr(name.find('.')) + "'" + tail));
  }
  cases.push_back(refused("noextension", "OFF\n", "the file name has no extension" + tail));
  cases.push_back(refused("tet.ply.bak", "OFF\n", "unsupported mesh file type '.bak'" + tail));
  cases.push_back(loads("TETRA.OFF", "OFF\n4 4 0\n" + kTetraVertices + kTetraFaces, 4, 4, true));
  cases.push_back(loads("tetra.Ply",
                        plyHead("ascii", "element vertex 4\n" + kXyz +
                                             "element face 4\nproperty list "
                                             "uchar int vertex_indices\n") +
                            kTetraVertices + kTetraFaces,
                        4, 4, true));
  expectOutcomes(cases);
}

}  // namespace
}  // namespace gpucol::test
