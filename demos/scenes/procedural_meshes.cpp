#include "procedural_meshes.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <tuple>
#include <utility>
#include <vector>

namespace gpucol::scenes {
namespace {

constexpr float kPi = 3.14159265358979323846f;

struct MeshArrays {
  std::vector<float> xyz;
  std::vector<std::uint32_t> indices;

  std::uint32_t addVertex(float x, float y, float z) {
    xyz.insert(xyz.end(), {x, y, z});
    return static_cast<std::uint32_t>(xyz.size() / 3 - 1);
  }
  void addTriangle(std::uint32_t a, std::uint32_t b, std::uint32_t c) { indices.insert(indices.end(), {a, b, c}); }
  // Quad a-b-c-d counter-clockwise seen from outside.
  void addQuad(std::uint32_t a, std::uint32_t b, std::uint32_t c, std::uint32_t d) {
    addTriangle(a, b, c);
    addTriangle(a, c, d);
  }
};

}  // namespace

TriangleMesh makeBox(float hx, float hy, float hz, int subdivisions) {
  const int n = subdivisions < 1 ? 1 : subdivisions;
  // Vertices on a (n+1)^3 lattice, only those on the surface, shared between faces so the box is closed.
  std::map<std::tuple<int, int, int>, std::uint32_t> lattice;
  MeshArrays arrays;
  auto vertex = [&](int i, int j, int k) {
    auto [it, inserted] = lattice.try_emplace({i, j, k}, 0u);
    if (inserted) {
      it->second = arrays.addVertex(hx * (2.0f * i / n - 1.0f), hy * (2.0f * j / n - 1.0f), hz * (2.0f * k / n - 1.0f));
    }
    return it->second;
  };
  for (int a = 0; a < n; ++a) {
    for (int b = 0; b < n; ++b) {
      // Each face: (fixed axis, side); quads ordered so that the winding is counter-clockwise from outside.
      arrays.addQuad(vertex(a, b, n), vertex(a + 1, b, n), vertex(a + 1, b + 1, n), vertex(a, b + 1, n));  // +z
      arrays.addQuad(vertex(a, b, 0), vertex(a, b + 1, 0), vertex(a + 1, b + 1, 0), vertex(a + 1, b, 0));  // -z
      arrays.addQuad(vertex(n, a, b), vertex(n, a + 1, b), vertex(n, a + 1, b + 1), vertex(n, a, b + 1));  // +x
      arrays.addQuad(vertex(0, a, b), vertex(0, a, b + 1), vertex(0, a + 1, b + 1), vertex(0, a + 1, b));  // -x
      arrays.addQuad(vertex(b, n, a), vertex(b, n, a + 1), vertex(b + 1, n, a + 1), vertex(b + 1, n, a));  // +y
      arrays.addQuad(vertex(b, 0, a), vertex(b + 1, 0, a), vertex(b + 1, 0, a + 1), vertex(b, 0, a + 1));  // -y
    }
  }
  return TriangleMesh::fromArrays(std::move(arrays.xyz), std::move(arrays.indices), "box");
}

TriangleMesh makeIcosphere(float radius, int levels) {
  MeshArrays arrays;
  const float t = (1.0f + std::sqrt(5.0f)) / 2.0f;
  const float base[12][3] = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                             {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  auto addOnSphere = [&](float x, float y, float z) {
    const float len = std::sqrt(x * x + y * y + z * z);
    return arrays.addVertex(radius * x / len, radius * y / len, radius * z / len);
  };
  for (const auto& v : base) addOnSphere(v[0], v[1], v[2]);
  std::vector<std::uint32_t> faces = {0, 11, 5, 0, 5,  1, 0, 1, 7, 0, 7,  10, 0, 10, 11, 1, 5, 9, 5, 11,
                                      4, 11, 10, 2, 10, 7, 6, 7, 1, 8, 3, 9,  4, 3,  4,  2, 3, 2, 6, 3,
                                      6, 8,  3, 8, 9, 4, 9, 5, 2, 4, 11, 6, 2, 10, 8,  6, 7, 9, 8, 1};
  for (int level = 0; level < levels; ++level) {
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> midpoints;
    auto midpoint = [&](std::uint32_t a, std::uint32_t b) {
      const auto key = std::minmax(a, b);
      auto [it, inserted] = midpoints.try_emplace({key.first, key.second}, 0u);
      if (inserted) {
        const float* pa = &arrays.xyz[3 * a];
        const float* pb = &arrays.xyz[3 * b];
        it->second = addOnSphere(pa[0] + pb[0], pa[1] + pb[1], pa[2] + pb[2]);
      }
      return it->second;
    };
    std::vector<std::uint32_t> finer;
    finer.reserve(faces.size() * 4);
    for (std::size_t f = 0; f < faces.size(); f += 3) {
      const std::uint32_t a = faces[f], b = faces[f + 1], c = faces[f + 2];
      const std::uint32_t ab = midpoint(a, b), bc = midpoint(b, c), ca = midpoint(c, a);
      finer.insert(finer.end(), {a, ab, ca, b, bc, ab, c, ca, bc, ab, bc, ca});
    }
    faces.swap(finer);
  }
  arrays.indices = std::move(faces);
  return TriangleMesh::fromArrays(std::move(arrays.xyz), std::move(arrays.indices), "icosphere");
}

TriangleMesh makeTorus(float major, float minor, int ringSegments, int tubeSegments) {
  MeshArrays arrays;
  for (int i = 0; i < ringSegments; ++i) {
    const float u = 2.0f * kPi * i / ringSegments;
    for (int j = 0; j < tubeSegments; ++j) {
      const float v = 2.0f * kPi * j / tubeSegments;
      const float ring = major + minor * std::cos(v);
      arrays.addVertex(ring * std::cos(u), ring * std::sin(u), minor * std::sin(v));
    }
  }
  auto index = [&](int i, int j) {
    return static_cast<std::uint32_t>((i % ringSegments) * tubeSegments + (j % tubeSegments));
  };
  for (int i = 0; i < ringSegments; ++i) {
    for (int j = 0; j < tubeSegments; ++j) {
      arrays.addQuad(index(i, j), index(i + 1, j), index(i + 1, j + 1), index(i, j + 1));
    }
  }
  return TriangleMesh::fromArrays(std::move(arrays.xyz), std::move(arrays.indices), "torus");
}

TriangleMesh makeBin(float outerHalf, float innerHalf, float floorThickness, float height) {
  MeshArrays arrays;
  const float corners[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
  std::uint32_t outerBottom[4], outerTop[4], innerTop[4], innerBottom[4];
  for (int i = 0; i < 4; ++i) {
    const float x = corners[i][0], z = corners[i][1];
    outerBottom[i] = arrays.addVertex(x * outerHalf, -floorThickness, z * outerHalf);
    outerTop[i] = arrays.addVertex(x * outerHalf, height, z * outerHalf);
    innerTop[i] = arrays.addVertex(x * innerHalf, height, z * innerHalf);
    innerBottom[i] = arrays.addVertex(x * innerHalf, 0, z * innerHalf);
  }
  // Each quad wound so that its normal points along `outward`.
  auto quad = [&](std::uint32_t a, std::uint32_t b, std::uint32_t c, std::uint32_t d, float ox, float oy,
                  float oz) {
    auto at = [&](std::uint32_t v, int k) { return arrays.xyz[3 * v + std::size_t(k)]; };
    const float e1[3] = {at(b, 0) - at(a, 0), at(b, 1) - at(a, 1), at(b, 2) - at(a, 2)};
    const float e2[3] = {at(c, 0) - at(a, 0), at(c, 1) - at(a, 1), at(c, 2) - at(a, 2)};
    const float n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
    if (n[0] * ox + n[1] * oy + n[2] * oz >= 0)
      arrays.addQuad(a, b, c, d);
    else
      arrays.addQuad(d, c, b, a);
  };
  quad(outerBottom[0], outerBottom[1], outerBottom[2], outerBottom[3], 0, -1, 0);
  quad(innerBottom[0], innerBottom[1], innerBottom[2], innerBottom[3], 0, 1, 0);
  for (int i = 0; i < 4; ++i) {
    const int j = (i + 1) % 4;
    const float mx = corners[i][0] + corners[j][0], mz = corners[i][1] + corners[j][1];  // the side's direction
    quad(outerBottom[i], outerBottom[j], outerTop[j], outerTop[i], mx, 0, mz);
    quad(outerTop[i], outerTop[j], innerTop[j], innerTop[i], 0, 1, 0);
    quad(innerTop[i], innerTop[j], innerBottom[j], innerBottom[i], -mx, 0, -mz);
  }
  return TriangleMesh::fromArrays(std::move(arrays.xyz), std::move(arrays.indices), "bin");
}

TriangleMesh makeLShape(float size, float depth) {
  // The L's outline in the xy plane, counter-clockwise, extruded along z from -depth/2 to +depth/2.
  const float s = size, w = size / 3.0f;
  const float outline[6][2] = {{0, 0}, {s, 0}, {s, w}, {w, w}, {w, s}, {0, s}};
  MeshArrays arrays;
  const float z0 = -depth / 2, z1 = depth / 2;
  for (const auto& p : outline) arrays.addVertex(p[0] - s / 2, p[1] - s / 2, z0);
  for (const auto& p : outline) arrays.addVertex(p[0] - s / 2, p[1] - s / 2, z1);
  // Caps: the L splits into two convex quads, (0,1,2,3) and (0,3,4,5).
  arrays.addQuad(6, 7, 8, 9);
  arrays.addQuad(6, 9, 10, 11);
  arrays.addQuad(0, 3, 2, 1);
  arrays.addQuad(0, 5, 4, 3);
  for (std::uint32_t i = 0; i < 6; ++i) {
    const std::uint32_t j = (i + 1) % 6;
    arrays.addQuad(i, j, j + 6, i + 6);
  }
  return TriangleMesh::fromArrays(std::move(arrays.xyz), std::move(arrays.indices), "l-shape");
}

TriangleMesh makeCross(float arm, float width, float depth) {
  // The outline counter-clockwise; it is star-shaped about the centre, so each cap is a fan from a centre
  // vertex.
  const float a = arm, w = width / 2;
  const float outline[12][2] = {{a, -w}, {a, w},   {w, w},   {w, a},   {-w, a}, {-w, w},
                                {-a, w}, {-a, -w}, {-w, -w}, {-w, -a}, {w, -a}, {w, -w}};
  MeshArrays arrays;
  const float z0 = -depth / 2, z1 = depth / 2;
  for (const auto& p : outline) arrays.addVertex(p[0], p[1], z0);
  for (const auto& p : outline) arrays.addVertex(p[0], p[1], z1);
  const std::uint32_t bottom = arrays.addVertex(0, 0, z0), top = arrays.addVertex(0, 0, z1);
  for (std::uint32_t i = 0; i < 12; ++i) {
    const std::uint32_t j = (i + 1) % 12;
    arrays.addTriangle(top, i + 12, j + 12);
    arrays.addTriangle(bottom, j, i);
    arrays.addQuad(i, j, j + 12, i + 12);
  }
  return TriangleMesh::fromArrays(std::move(arrays.xyz), std::move(arrays.indices), "cross");
}

}  // namespace gpucol::scenes
