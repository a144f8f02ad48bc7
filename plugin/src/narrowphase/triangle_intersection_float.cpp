#include "narrowphase/triangle_intersection_float.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "shared_math/triangle_test.h"

namespace gpucol {
namespace {

bool sameStrictSign(float x, float y) { return (x > 0.0f && y > 0.0f) || (x < 0.0f && y < 0.0f); }

bool allOnOneSide(const float d[3]) { return sameStrictSign(d[0], d[1]) && sameStrictSign(d[0], d[2]); }

// Möller's interval of a triangle on the planes' intersection line, from its coordinates `p` along the line's
// dominant axis and its distances `d` to the other plane; the lone vertex is the one on its own side.
void lineInterval(const float p[3], const float d[3], float& lo, float& hi) {
  int lone = 0;
  if (sameStrictSign(d[0], d[1])) {
    lone = 2;
  } else if (sameStrictSign(d[0], d[2])) {
    lone = 1;
  } else if (!sameStrictSign(d[1], d[2]) && d[0] == 0.0f) {
    lone = d[1] != 0.0f ? 1 : 2;
  }
  const int b = lone == 2 ? 0 : lone + 1;
  const int c = b == 2 ? 0 : b + 1;
  const float t0 = p[lone] + (p[b] - p[lone]) * (d[lone] / (d[lone] - d[b]));
  const float t1 = p[lone] + (p[c] - p[lone]) * (d[lone] / (d[lone] - d[c]));
  lo = std::min(t0, t1);
  hi = std::max(t0, t1);
}

int dominantAxis(const Eigen::Vector3f& v) {
  const float x = std::fabs(v.x()), y = std::fabs(v.y()), z = std::fabs(v.z());
  return x >= y ? (x >= z ? 0 : 2) : (y >= z ? 1 : 2);
}

bool coplanarOverlap(const Eigen::Vector3f* const af[3], const Eigen::Vector3f* const bf[3], int dropAxis) {
  // The 2-D overlap test of the exact path, on the same float coordinates: the sweep measures the float
  // plane decisions, not a second copy of the 2-D test.
  double a[3][3], b[3][3];
  for (int v = 0; v < 3; ++v) {
    for (int k = 0; k < 3; ++k) {
      a[v][k] = (*af[v])[k];
      b[v][k] = (*bf[v])[k];
    }
  }
  return gpucol_coplanar_overlap(a, b, dropAxis, nullptr) != 0;
}

}  // namespace

bool trianglesIntersectFloat(const Eigen::Vector3f& a0, const Eigen::Vector3f& a1, const Eigen::Vector3f& a2,
                             const Eigen::Vector3f& b0, const Eigen::Vector3f& b1, const Eigen::Vector3f& b2) {
  const Eigen::Vector3f nA = (a1 - a0).cross(a2 - a0);
  if (!(nA.squaredNorm() > 0.0f)) return false;
  const float dB[3] = {nA.dot(b0 - a0), nA.dot(b1 - a0), nA.dot(b2 - a0)};
  if (allOnOneSide(dB)) return false;
  const Eigen::Vector3f nB = (b1 - b0).cross(b2 - b0);
  if (!(nB.squaredNorm() > 0.0f)) return false;
  const Eigen::Vector3f* const a[3] = {&a0, &a1, &a2};
  const Eigen::Vector3f* const b[3] = {&b0, &b1, &b2};
  if (dB[0] == 0.0f && dB[1] == 0.0f && dB[2] == 0.0f) return coplanarOverlap(a, b, dominantAxis(nA));
  const float dA[3] = {nB.dot(a0 - b0), nB.dot(a1 - b0), nB.dot(a2 - b0)};
  if (allOnOneSide(dA)) return false;
  if (dA[0] == 0.0f && dA[1] == 0.0f && dA[2] == 0.0f) return coplanarOverlap(a, b, dominantAxis(nB));
  const int axis = dominantAxis(nA.cross(nB));
  const float pA[3] = {a0[axis], a1[axis], a2[axis]};
  const float pB[3] = {b0[axis], b1[axis], b2[axis]};
  float loA, hiA, loB, hiB;
  lineInterval(pA, dA, loA, hiA);
  lineInterval(pB, dB, loB, hiB);
  return loA <= hiB && loB <= hiA;
}

}  // namespace gpucol
