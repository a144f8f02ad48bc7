#include "mesh/raw_mesh.h"

#include <algorithm>
#include <sstream>

#include "mesh/mesh_file.h"
#include "mesh/polygon_triangulation.h"
#include "mesh/vertex_welding.h"

namespace gpucol {

RawMesh::RawMesh(const std::string& path, const char* format, const char* place)
    : m_path(path), m_format(format), m_place(place) {}

void RawMesh::addFace(const std::uint32_t* corners, std::size_t n, std::uint64_t where) {
  m_faceStart.push_back(m_corners.size());
  m_corners.insert(m_corners.end(), corners, corners + n);
  m_where.push_back(where);
}

void RawMesh::reserveFaces(std::size_t faces, std::size_t corners) {
  m_faceStart.reserve(m_faceStart.size() + faces);
  m_where.reserve(m_where.size() + faces);
  m_corners.reserve(m_corners.size() + corners);
}

void RawMesh::failFace(std::size_t face, const std::string& what) const {
  throwMalformed(m_path, m_format, std::string(m_place) + " " + std::to_string(m_where[face]) + ": " + what);
}

TriangleMesh RawMesh::build(bool weld) && {
  std::vector<std::uint32_t> remap;
  if (weld) remap = weldEqualPositions(xyz);
  const auto vertex = [&](std::uint32_t v) { return weld ? remap[v] : v; };

  const std::size_t faces = m_where.size();
  m_faceStart.push_back(m_corners.size());
  std::vector<std::uint32_t> indices;
  indices.reserve(3 * (m_corners.size() - 2 * faces));
  std::vector<std::uint32_t> face;
  for (std::size_t f = 0; f < faces; ++f) {
    const std::uint32_t* original = &m_corners[std::size_t(m_faceStart[f])];
    const std::size_t n = std::size_t(m_faceStart[f + 1] - m_faceStart[f]);
    face.resize(n);
    for (std::size_t k = 0; k < n; ++k) face[k] = vertex(original[k]);
    // Repeated corners: pairwise for small faces, by sorting a copy for large ones.
    std::size_t first = n, second = n;
    if (n <= 16) {
      for (std::size_t a = 0; a < n && first == n; ++a) {
        for (std::size_t b = a + 1; b < n; ++b) {
          if (face[a] == face[b]) {
            first = a, second = b;
            break;
          }
        }
      }
    } else {
      std::vector<std::pair<std::uint32_t, std::uint32_t>> sorted(n);
      for (std::size_t k = 0; k < n; ++k) sorted[k] = {face[k], std::uint32_t(k)};
      std::sort(sorted.begin(), sorted.end());
      for (std::size_t k = 1; k < n && first == n; ++k) {
        if (sorted[k].first == sorted[k - 1].first) first = sorted[k - 1].second, second = sorted[k].second;
      }
    }
    if (first != n) {
      std::ostringstream out;
      if (original[first] == original[second]) {
        out << "the face repeats vertex " << original[first] << " (corners " << first + 1 << " and "
            << second + 1 << " of " << n << ")";
      } else {
        const float* p = &xyz[3 * std::size_t(face[first])];
        out << "corners " << first + 1 << " and " << second + 1 << " of the face are at the same position ("
            << p[0] << ", " << p[1] << ", " << p[2]
            << "), so it has a repeated vertex once equal positions are joined";
      }
      failFace(f, out.str());
    }
    const std::size_t at = indices.size();
    indices.resize(at + 3 * (n - 2));
    if (n == 3) {
      std::copy(face.begin(), face.end(), indices.begin() + std::ptrdiff_t(at));
      continue;
    }
    switch (triangulatePolygon(xyz, face.data(), n, &indices[at])) {
      case PolygonStatus::kOk:
        break;
      case PolygonStatus::kSelfIntersecting:
        failFace(f,
                 "the polygon of " + std::to_string(n) +
                     " corners is not simple (seen along its normal its edges cross, touch or fold back), so "
                     "it cannot be split into triangles");
      case PolygonStatus::kTooManyCorners:
        failFace(f, "the non-convex polygon has " + std::to_string(n) +
                        " corners; gpucol splits non-convex "
                        "polygons of at most " +
                        std::to_string(kMaxNonConvexCorners) + " corners");
    }
  }
  m_corners = std::vector<std::uint32_t>();
  m_faceStart = std::vector<std::uint64_t>();
  m_where = std::vector<std::uint64_t>();
  return TriangleMesh::fromArrays(std::move(xyz), std::move(indices), m_path);
}

}  // namespace gpucol
