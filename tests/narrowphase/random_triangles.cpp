#include "random_triangles.h"

#include <cmath>

namespace gpucol::test {
namespace {

Eigen::Vector3d uniformInCube(std::mt19937_64& rng, double half) {
  std::uniform_real_distribution<double> u(-half, half);
  return {u(rng), u(rng), u(rng)};
}

std::array<Eigen::Vector3d, 3> randomTriangleD(std::mt19937_64& rng) {
  while (true) {
    std::array<Eigen::Vector3d, 3> t = {uniformInCube(rng, 1.0), uniformInCube(rng, 1.0),
                                        uniformInCube(rng, 1.0)};
    TriangleF f = {t[0].cast<float>(), t[1].cast<float>(), t[2].cast<float>()};
    if (wellShaped(f)) return t;
  }
}

Eigen::Vector3d barycentric(std::mt19937_64& rng, const std::array<Eigen::Vector3d, 3>& t) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  double s = u(rng), r = u(rng);
  if (s + r > 1.0) {
    s = 1.0 - s;
    r = 1.0 - r;
  }
  return t[0] + s * (t[1] - t[0]) + r * (t[2] - t[0]);
}

double logUniform(std::mt19937_64& rng, double lo, double hi) {
  std::uniform_real_distribution<double> u(std::log(lo), std::log(hi));
  return std::exp(u(rng));
}

/// A triangle with `apex` as a vertex, its other two vertices random around it.
std::array<Eigen::Vector3d, 3> triangleAt(std::mt19937_64& rng, const Eigen::Vector3d& apex) {
  while (true) {
    std::array<Eigen::Vector3d, 3> t = {apex, apex + uniformInCube(rng, 1.0), apex + uniformInCube(rng, 1.0)};
    TriangleF f = {t[0].cast<float>(), t[1].cast<float>(), t[2].cast<float>()};
    if (wellShaped(f)) return t;
  }
}

}  // namespace

std::string familyName(PairFamily family) {
  switch (family) {
    case PairFamily::General:
      return "general";
    case PairFamily::NearCoplanar:
      return "near-coplanar";
    case PairFamily::ExactCoplanar:
      return "exactly coplanar";
    case PairFamily::SharedVertex:
      return "shared vertex";
    case PairFamily::VertexOnFace:
      return "vertex on face";
    case PairFamily::EdgeOnEdge:
      return "edge on edge";
    case PairFamily::NearTouching:
      return "slightly separated / penetrating";
    case PairFamily::Count:
      break;
  }
  return "?";
}

Eigen::Matrix3d randomRotation(std::mt19937_64& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  Eigen::Quaterniond q(n(rng), n(rng), n(rng), n(rng));
  return q.normalized().toRotationMatrix();
}

bool wellShaped(const TriangleF& t) {
  for (int i = 0; i < 3; ++i) {
    const Eigen::Vector3d e1 = (t[(i + 1) % 3] - t[i]).cast<double>();
    const Eigen::Vector3d e2 = (t[(i + 2) % 3] - t[i]).cast<double>();
    const double d = e1.squaredNorm() * e2.squaredNorm();
    if (!(e1.cross(e2).squaredNorm() > 1e-4 * d)) return false;
  }
  return true;
}

void randomPair(PairFamily family, std::mt19937_64& rng, TriangleF& a, TriangleF& b) {
  std::array<Eigen::Vector3d, 3> ta, tb;
  std::uniform_int_distribution<int> pick(0, 2);
  bool exact = false;  // exactly constructed pairs keep their coordinates (no rotation, dyadic scale)
  switch (family) {
    case PairFamily::General: {
      ta = randomTriangleD(rng);
      tb = randomTriangleD(rng);
      const Eigen::Vector3d shift = uniformInCube(rng, 1.0);
      for (auto& v : tb) v += shift;
      break;
    }
    case PairFamily::NearCoplanar: {
      ta = randomTriangleD(rng);
      // B inside A's plane around a point of A, then tilted about a random in-plane point and lifted.
      const Eigen::Vector3d n = (ta[1] - ta[0]).cross(ta[2] - ta[0]).normalized();
      const Eigen::Vector3d u = n.unitOrthogonal(), w = n.cross(u);
      const Eigen::Vector3d shift = uniformInCube(rng, 0.5);
      const Eigen::Vector3d centre = barycentric(rng, ta) + shift.x() * u + shift.y() * w;
      for (auto& v : tb) {
        const Eigen::Vector3d r = uniformInCube(rng, 1.0);
        v = centre + r.x() * u + r.y() * w;
      }
      const double tilt = logUniform(rng, 1e-7, 1e-2) * (pick(rng) == 0 ? 0.0 : 1.0);
      const double lift = logUniform(rng, 1e-7, 1e-2) * (pick(rng) == 0 ? -1.0 : 1.0);
      const Eigen::Matrix3d rot =
          Eigen::AngleAxisd(tilt, uniformInCube(rng, 1.0).normalized()).toRotationMatrix();
      for (auto& v : tb) v = centre + rot * (v - centre) + lift * n;
      if (pick(rng) == 0) std::swap(tb[1], tb[2]);  // either facing
      break;
    }
    case PairFamily::ExactCoplanar: {
      // Multiples of 1/64 in [-2, 2]; z = x/2 - y/4 + 1/8 (or z = c) is exact in float.
      std::uniform_int_distribution<int> grid(-128, 128);
      const int plane = pick(rng);
      auto point = [&]() {
        const double x = grid(rng) / 64.0, y = grid(rng) / 64.0;
        const double z = plane == 0 ? 0.125 : x / 2 - y / 4 + 0.125;
        return Eigen::Vector3d(x, y, z);
      };
      do {
        ta = {point(), point(), point()};
        tb = {point(), point(), point()};
      } while (!wellShaped({ta[0].cast<float>(), ta[1].cast<float>(), ta[2].cast<float>()}) ||
               !wellShaped({tb[0].cast<float>(), tb[1].cast<float>(), tb[2].cast<float>()}));
      // Swap axes so the plane is not always the same one.
      const int axis = pick(rng);
      for (auto* t : {&ta, &tb}) {
        for (auto& v : *t) std::swap(v[2], v[axis]);
      }
      exact = true;
      break;
    }
    case PairFamily::SharedVertex: {
      ta = randomTriangleD(rng);
      tb = triangleAt(rng, ta[pick(rng)]);
      break;
    }
    case PairFamily::VertexOnFace: {
      ta = randomTriangleD(rng);
      tb = triangleAt(rng, barycentric(rng, ta));
      break;
    }
    case PairFamily::EdgeOnEdge: {
      ta = randomTriangleD(rng);
      const int i = pick(rng);
      std::uniform_real_distribution<double> u(0.0, 1.0);
      const Eigen::Vector3d onA = ta[i] + u(rng) * (ta[(i + 1) % 3] - ta[i]);
      // B's edge passes through that point, B on a random side.
      const Eigen::Vector3d direction = uniformInCube(rng, 1.0);
      const double s = u(rng);
      tb = {onA - s * direction, onA + (1.0 - s) * direction, onA + uniformInCube(rng, 1.0)};
      if (!wellShaped({tb[0].cast<float>(), tb[1].cast<float>(), tb[2].cast<float>()}))
        tb = triangleAt(rng, onA);
      break;
    }
    case PairFamily::NearTouching: {
      const PairFamily touching[] = {PairFamily::SharedVertex, PairFamily::VertexOnFace,
                                     PairFamily::EdgeOnEdge};
      TriangleF fa, fb;
      randomPair(touching[pick(rng)], rng, fa, fb);
      const Eigen::Vector3d shift = uniformInCube(rng, 1.0).normalized() * logUniform(rng, 1e-7, 1e-2) *
                                    pairScale(toDouble(fa), toDouble(fb));
      for (auto& v : fb) v = (v.cast<double>() + shift).cast<float>();
      a = fa;
      b = fb;
      return;
    }
    case PairFamily::Count:
      break;
  }
  if (pick(rng) == 0) std::swap(ta, tb);
  if (!exact) {
    const Eigen::Matrix3d rotation = randomRotation(rng);
    const double scale = std::pow(10.0, std::uniform_int_distribution<int>(-3, 3)(rng));
    const Eigen::Vector3d offset = uniformInCube(rng, 10.0) * scale;
    for (auto* t : {&ta, &tb}) {
      for (auto& v : *t) v = scale * (rotation * v) + offset;
    }
  }
  for (int i = 0; i < 3; ++i) {
    a[i] = ta[i].cast<float>();
    b[i] = tb[i].cast<float>();
  }
}

}  // namespace gpucol::test
