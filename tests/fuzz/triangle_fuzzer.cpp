// libFuzzer target: the exact triangle test and contact generation on 18 arbitrary floats (two triangles).
// Always: no crash, no sanitizer report, a contact only for a pair the test calls intersecting, and a contact is
// finite with a unit normal and depth <= 0. Where the input is well-conditioned (finite coordinates of moderate
// size, triangles with no angle under about 0.6 degrees, the pair more than 1e-5 of its size from touching), the
// answer must equal the double-precision separating-axis reference of the tests (tests/narrowphase).
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "narrowphase/reference_triangles.h"
#include "narrowphase/triangle_contact.h"
#include "narrowphase/triangle_intersection.h"

namespace {

void check(bool condition, const char* what) {
  if (!condition) {
    std::fprintf(stderr, "triangle_fuzzer: %s\n", what);
    std::abort();
  }
}

// No angle with sin^2 under 1e-4 (about 0.57 degrees): the plane is well defined by the float input.
bool wellShaped(const gpucol::test::TriangleD& t) {
  for (int i = 0; i < 3; ++i) {
    const Eigen::Vector3d e1 = t[(i + 1) % 3] - t[i], e2 = t[(i + 2) % 3] - t[i];
    const double denominator = e1.squaredNorm() * e2.squaredNorm();
    if (!(denominator > 0) || !(e1.cross(e2).squaredNorm() > 1e-4 * denominator)) return false;
  }
  return true;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 18 * sizeof(float)) return 0;
  float v[18];
  std::memcpy(v, data, sizeof v);
  gpucol::test::TriangleF a, b;
  for (int i = 0; i < 3; ++i) {
    a[i] = Eigen::Vector3f(v[3 * i], v[3 * i + 1], v[3 * i + 2]);
    b[i] = Eigen::Vector3f(v[9 + 3 * i], v[10 + 3 * i], v[11 + 3 * i]);
  }
  const bool intersects = gpucol::trianglesIntersect(a[0], a[1], a[2], b[0], b[1], b[2]);
  const Eigen::Vector3f af[3] = {a[0], a[1], a[2]}, bf[3] = {b[0], b[1], b[2]};
  const std::optional<gpucol::TriangleContact> contact = gpucol::generateContact(af, bf);
  if (contact) {
    check(intersects, "a contact for a pair trianglesIntersect calls apart");
    check(contact->point.allFinite() && contact->normalOnB.allFinite() && std::isfinite(contact->depth),
          "a contact with a NaN or infinite component");
    check(std::abs(contact->normalOnB.norm() - 1.0f) < 1e-5f, "a contact normal that is not unit length");
    check(contact->depth <= 0, "a positive contact depth");
  }

  // Well-conditioned input: compare with the double reference.
  for (float x : v) {
    if (!std::isfinite(x) || std::abs(x) > 1e6f) return 0;
  }
  const gpucol::test::TriangleD da = gpucol::test::toDouble(a), db = gpucol::test::toDouble(b);
  if (!wellShaped(da) || !wellShaped(db)) return 0;
  const double scale = gpucol::test::pairScale(da, db);
  // Triangles far smaller than the distance between them say nothing about precision; keep sizes comparable.
  const double sizeA = (da[1] - da[0]).norm() + (da[2] - da[0]).norm();
  const double sizeB = (db[1] - db[0]).norm() + (db[2] - db[0]).norm();
  if (!(sizeA > 1e-3 * scale && sizeB > 1e-3 * scale && scale > 1e-20)) return 0;
  const double separation = gpucol::test::signedSeparation(da, db);
  if (std::abs(separation) <= 1e-5 * scale) return 0;
  if (intersects != (separation < 0)) {
    std::fprintf(stderr, "triangle_fuzzer: trianglesIntersect says %d, the double reference's separation is %.17g "
                 "(%.3g of the pair's size)\n", int(intersects), separation, separation / scale);
    std::abort();
  }
  return 0;
}
