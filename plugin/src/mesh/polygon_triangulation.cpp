#include "mesh/polygon_triangulation.h"

#include <algorithm>
#include <cmath>

namespace gpucol {

namespace {

struct Point {
  double u, v;
};

/// Twice the signed area of (a, b, c): positive when they turn counter-clockwise.
double turn(const Point& a, const Point& b, const Point& c) {
  return (b.u - a.u) * (c.v - a.v) - (b.v - a.v) * (c.u - a.u);
}

/// True when p lies inside the counter-clockwise triangle (a, b, c) or on its boundary.
bool inTriangle(const Point& p, const Point& a, const Point& b, const Point& c) {
  return turn(a, b, p) >= 0 && turn(b, c, p) >= 0 && turn(c, a, p) >= 0;
}

/// True when p lies on the closed segment (a, b), given that the three are collinear.
bool onSegment(const Point& p, const Point& a, const Point& b) {
  return std::min(a.u, b.u) <= p.u && p.u <= std::max(a.u, b.u) && std::min(a.v, b.v) <= p.v &&
         p.v <= std::max(a.v, b.v);
}

/// True when the closed segments (a, b) and (c, d) share a point.
bool segmentsMeet(const Point& a, const Point& b, const Point& c, const Point& d) {
  const double o1 = turn(a, b, c), o2 = turn(a, b, d), o3 = turn(c, d, a), o4 = turn(c, d, b);
  if (((o1 > 0 && o2 < 0) || (o1 < 0 && o2 > 0)) && ((o3 > 0 && o4 < 0) || (o3 < 0 && o4 > 0))) return true;
  return (o1 == 0 && onSegment(c, a, b)) || (o2 == 0 && onSegment(d, a, b)) ||
         (o3 == 0 && onSegment(a, c, d)) || (o4 == 0 && onSegment(b, c, d));
}

/// True when the closed polygon is simple: no two edges meet but neighbours at their shared corner, and no
/// edge folds back over its neighbour. Ear clipping splits a simple polygon, and only a simple one, right.
bool isSimple(const std::vector<Point>& p) {
  const std::size_t n = p.size();
  for (std::size_t i = 0; i < n; ++i) {
    const Point &a = p[i], &b = p[(i + 1) % n], &c = p[(i + 2) % n];
    const double dot = (b.u - a.u) * (c.u - b.u) + (b.v - a.v) * (c.v - b.v);
    if (turn(a, b, c) == 0 && dot < 0) return false;  // the edge after b runs back along the one before
    for (std::size_t j = i + 2; j < n; ++j) {
      if (i == 0 && j == n - 1) continue;  // the last edge ends where the first begins
      if (segmentsMeet(a, b, p[j], p[(j + 1) % n])) return false;
    }
  }
  return true;
}

void fan(const std::uint32_t* corners, std::size_t n, std::uint32_t* out) {
  for (std::size_t k = 1; k + 1 < n; ++k) {
    *out++ = corners[0];
    *out++ = corners[k];
    *out++ = corners[k + 1];
  }
}

}  // namespace

PolygonStatus triangulatePolygon(const std::vector<float>& xyz, const std::uint32_t* corners, std::size_t n,
                                 std::uint32_t* out) {
  const auto at = [&](std::size_t k, int axis) {
    return double(xyz[3 * std::size_t(corners[k]) + std::size_t(axis)]) -
           double(xyz[3 * std::size_t(corners[0]) + std::size_t(axis)]);
  };
  // Newell's normal, relative to the first corner so that far meshes keep their precision.
  double normal[3] = {0, 0, 0};
  for (std::size_t k = 0; k < n; ++k) {
    const std::size_t j = (k + 1) % n;
    for (int axis = 0; axis < 3; ++axis) {
      const int a = (axis + 1) % 3, b = (axis + 2) % 3;
      normal[axis] += (at(k, a) - at(j, a)) * (at(k, b) + at(j, b));
    }
  }
  int drop = 0;
  for (int axis = 1; axis < 3; ++axis) {
    if (std::abs(normal[axis]) > std::abs(normal[drop])) drop = axis;
  }
  if (normal[drop] == 0) {
    // No area: a fan of degenerate triangles is the polygon only when every corner lies on one line; lobes
    // of opposite winding that cancel (a bow tie) are not a surface.
    std::size_t far = 1;
    double farthest = 0;
    for (std::size_t k = 1; k < n; ++k) {
      const double d = at(k, 0) * at(k, 0) + at(k, 1) * at(k, 1) + at(k, 2) * at(k, 2);
      if (d > farthest) farthest = d, far = k;
    }
    for (std::size_t k = 1; k < n; ++k) {
      for (int axis = 0; axis < 3; ++axis) {
        const int a = (axis + 1) % 3, b = (axis + 2) % 3;
        const double cross = at(far, a) * at(k, b) - at(far, b) * at(k, a);
        if (std::abs(cross) > 1e-12 * farthest) return PolygonStatus::kSelfIntersecting;
      }
    }
    fan(corners, n, out);
    return PolygonStatus::kOk;
  }
  // Projected onto the plane across the normal's largest axis, turned so the polygon runs counter-clockwise.
  const int first = (drop + 1) % 3, second = (drop + 2) % 3;
  const bool flip = normal[drop] < 0;
  std::vector<Point> p(n);
  for (std::size_t k = 0; k < n; ++k) {
    p[k] = flip ? Point{at(k, second), at(k, first)} : Point{at(k, first), at(k, second)};
  }

  // Convex: every corner turns left or goes straight, and the turns add up to one full turn (a star
  // polygon turns left everywhere too, but winds twice).
  bool convex = true;
  double winding = 0;
  for (std::size_t k = 0; k < n && convex; ++k) {
    const Point& a = p[(k + n - 1) % n];
    const Point& b = p[k];
    const Point& c = p[(k + 1) % n];
    const double cross = turn(a, b, c);
    convex = cross >= 0;
    const double dot = (b.u - a.u) * (c.u - b.u) + (b.v - a.v) * (c.v - b.v);
    winding += std::atan2(cross, dot);
  }
  if (convex && std::abs(winding - 2 * M_PI) < 1) {
    fan(corners, n, out);
    return PolygonStatus::kOk;
  }
  if (n > kMaxNonConvexCorners) return PolygonStatus::kTooManyCorners;
  if (!isSimple(p)) return PolygonStatus::kSelfIntersecting;

  // Ear clipping over a ring of the corners left. An ear is a corner turning strictly left whose triangle
  // holds no other corner left (inside or on its edges); ear flags are kept and redone only for the two
  // neighbours of a clipped ear, so the whole costs O(n^2).
  std::vector<std::size_t> prev(n), next(n);
  for (std::size_t k = 0; k < n; ++k) {
    prev[k] = (k + n - 1) % n;
    next[k] = (k + 1) % n;
  }
  std::vector<char> removed(n, 0);
  std::size_t left = n;
  const auto isEar = [&](std::size_t k) {
    const Point &a = p[prev[k]], &b = p[k], &c = p[next[k]];
    if (turn(a, b, c) <= 0) return false;
    for (std::size_t j = next[next[k]]; j != prev[k]; j = next[j]) {
      if (inTriangle(p[j], a, b, c)) return false;
    }
    return true;
  };
  std::vector<char> ear(n, 0);
  std::vector<std::size_t> ears;
  for (std::size_t k = 0; k < n; ++k) {
    ear[k] = isEar(k);
    if (ear[k]) ears.push_back(k);
  }
  const auto clip = [&](std::size_t k) {
    *out++ = corners[prev[k]];
    *out++ = corners[k];
    *out++ = corners[next[k]];
    removed[k] = 1;
    next[prev[k]] = next[k];
    prev[next[k]] = prev[k];
    --left;
    for (const std::size_t neighbour : {prev[k], next[k]}) {
      ear[neighbour] = left > 3 ? isEar(neighbour) : 1;
      if (ear[neighbour]) ears.push_back(neighbour);
    }
  };
  std::size_t any = 0;  // a corner still in the ring
  while (left > 3) {
    while (!ears.empty() && (removed[ears.back()] || !ear[ears.back()])) ears.pop_back();
    if (!ears.empty()) {
      const std::size_t k = ears.back();
      ears.pop_back();
      any = next[k];
      clip(k);
      continue;
    }
    // No ear: a corner lying straight between its neighbours can still go (a zero-area triangle on the
    // polygon's edge); a corner where the boundary turns back on itself or crosses cannot.
    while (removed[any]) any = next[any];
    std::size_t k = any;
    bool found = false;
    do {
      const Point &a = p[prev[k]], &b = p[k], &c = p[next[k]];
      const double dot = (b.u - a.u) * (c.u - b.u) + (b.v - a.v) * (c.v - b.v);
      if (turn(a, b, c) == 0 && dot > 0) {
        found = true;
        break;
      }
      k = next[k];
    } while (k != any);
    if (!found) return PolygonStatus::kSelfIntersecting;
    any = next[k];
    clip(k);
  }
  const std::size_t k = any;
  const Point &a = p[prev[k]], &b = p[k], &c = p[next[k]];
  // The last three corners must still turn left (or be straight): otherwise the polygon winds the wrong way.
  if (turn(a, b, c) < 0) return PolygonStatus::kSelfIntersecting;
  *out++ = corners[prev[k]];
  *out++ = corners[k];
  *out++ = corners[next[k]];
  return PolygonStatus::kOk;
}

}  // namespace gpucol
