#include <algorithm>
#include <cmath>
#include <sstream>
#include <tuple>

#include "mesh/mesh_analysis.h"

namespace gpucol {

namespace {

/// One directed use of an undirected edge: the key packs (min, max) vertex ids, `forward` says
/// whether the triangle walks it from min to max.
struct EdgeUse {
  std::uint64_t key;
  bool forward;
};

/// A triangle's vertex set in sorted order plus its id, to find repeated triangles by sorting.
struct SortedTriangle {
  std::uint32_t v[3];
  std::uint32_t id;
};

/// Twice the triangle's area divided by its squared longest edge: the height over the longest edge
/// divided by that edge, a scale-free measure of how far the triangle is from a segment.
double flatness(const float* a, const float* b, const float* c) {
  const double e0[3] = {double(b[0]) - a[0], double(b[1]) - a[1], double(b[2]) - a[2]};
  const double e1[3] = {double(c[0]) - a[0], double(c[1]) - a[1], double(c[2]) - a[2]};
  const double e2[3] = {double(c[0]) - b[0], double(c[1]) - b[1], double(c[2]) - b[2]};
  const double n[3] = {e0[1] * e1[2] - e0[2] * e1[1], e0[2] * e1[0] - e0[0] * e1[2],
                       e0[0] * e1[1] - e0[1] * e1[0]};
  const double twiceArea = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  const auto sq = [](const double* e) { return e[0] * e[0] + e[1] * e[1] + e[2] * e[2]; };
  const double longest = std::max({sq(e0), sq(e1), sq(e2)});
  if (longest == 0) return 0;  // all three corners coincide
  return twiceArea / longest;
}

}  // namespace

MeshReport analyzeMesh(const std::vector<float>& positions, const std::vector<std::uint32_t>& indices) {
  MeshReport report;
  report.vertexCount = positions.size() / 3;
  report.triangleCount = indices.size() / 3;
  const std::size_t triangles = report.triangleCount;

  // Edges: every triangle contributes three directed uses; sorting by the undirected key groups the
  // uses of one edge together (thesis §5.3.1: each edge of a closed manifold is shared by exactly two).
  std::vector<EdgeUse> uses;
  uses.reserve(3 * triangles);
  for (std::size_t t = 0; t < triangles; ++t) {
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t from = indices[3 * t + k];
      const std::uint32_t to = indices[3 * t + (k + 1) % 3];
      const std::uint32_t lo = std::min(from, to), hi = std::max(from, to);
      uses.push_back({(std::uint64_t(lo) << 32) | hi, from < to});
    }
  }
  std::sort(uses.begin(), uses.end(), [](const EdgeUse& x, const EdgeUse& y) { return x.key < y.key; });
  for (std::size_t i = 0; i < uses.size();) {
    std::size_t j = i;
    std::size_t forward = 0;
    while (j < uses.size() && uses[j].key == uses[i].key) forward += uses[j++].forward ? 1 : 0;
    const std::size_t count = j - i;
    ++report.edgeCount;
    if (count == 1) ++report.boundaryEdges;
    if (count > 2) ++report.nonManifoldEdges;
    // Two triangles that agree on orientation walk their shared edge in opposite directions.
    if (count == 2 && forward != 1) ++report.inconsistentEdges;
    i = j;
  }
  report.edgeCountMatchesClosedManifold = 2 * report.edgeCount == 3 * triangles;
  report.closed = report.boundaryEdges == 0 && report.nonManifoldEdges == 0;

  // Degenerate triangles stay in the mesh (nothing is dropped silently); the report lists them.
  for (std::size_t t = 0; t < triangles; ++t) {
    const float* a = &positions[3 * std::size_t(indices[3 * t])];
    const float* b = &positions[3 * std::size_t(indices[3 * t + 1])];
    const float* c = &positions[3 * std::size_t(indices[3 * t + 2])];
    if (flatness(a, b, c) <= kDegenerateTriangleRatio) report.degenerateTriangles.push_back(std::uint32_t(t));
  }

  // Duplicates: sort the sorted vertex triples, ties broken by triangle id so that the first of each
  // group is the earliest triangle, and every later one is reported.
  std::vector<SortedTriangle> sorted(triangles);
  for (std::size_t t = 0; t < triangles; ++t) {
    SortedTriangle& s = sorted[t];
    std::copy(&indices[3 * t], &indices[3 * t] + 3, s.v);
    std::sort(s.v, s.v + 3);
    s.id = std::uint32_t(t);
  }
  std::sort(sorted.begin(), sorted.end(), [](const SortedTriangle& x, const SortedTriangle& y) {
    return std::tie(x.v[0], x.v[1], x.v[2], x.id) < std::tie(y.v[0], y.v[1], y.v[2], y.id);
  });
  for (std::size_t i = 1; i < sorted.size(); ++i) {
    if (std::equal(sorted[i].v, sorted[i].v + 3, sorted[i - 1].v))
      report.duplicateTriangles.push_back(sorted[i].id);
  }
  std::sort(report.duplicateTriangles.begin(), report.duplicateTriangles.end());

  std::vector<bool> used(report.vertexCount, false);
  for (std::uint32_t v : indices) used[v] = true;
  report.unreferencedVertices = std::size_t(std::count(used.begin(), used.end(), false));
  return report;
}

std::string MeshReport::summary() const {
  std::ostringstream out;
  out << triangleCount << " triangles, " << vertexCount << " vertices, " << edgeCount << " edges, ";
  if (closed && inconsistentEdges == 0) {
    out << "closed 2-manifold";
  } else {
    // "open" only when there is a hole; edges shared by three or more triangles alone are not one.
    out << (boundaryEdges > 0 ? "open" : closed ? "closed" : "not closed");
    if (boundaryEdges > 0) out << " (" << boundaryEdges << " boundary edges)";
    if (nonManifoldEdges > 0) out << ", " << nonManifoldEdges << " non-manifold edges";
    if (inconsistentEdges > 0) out << ", " << inconsistentEdges << " inconsistently wound edges";
  }
  out << ", " << degenerateTriangles.size() << " degenerate, " << duplicateTriangles.size()
      << " duplicate triangles";
  if (unreferencedVertices > 0) out << ", " << unreferencedVertices << " unreferenced vertices";
  return out.str();
}

}  // namespace gpucol
