#include "narrowphase/triangle_contact.h"

#include "narrowphase/triangle_plane.h"
#include "shared_math/triangle_test.h"

namespace gpucol {

std::optional<TriangleContact> generateContact(const Eigen::Vector3f (&a)[3], const Eigen::Vector3f (&b)[3]) {
  bool intersects = false;
  return detail::generateContactAndTest(a, b, intersects);
}

namespace detail {

std::optional<TriangleContact> generateContactAndTest(const Eigen::Vector3f (&af)[3],
                                                      const Eigen::Vector3f (&bf)[3], bool& intersects) {
  // Double arithmetic on the float input (see triangle_plane.h); the test and the rule are
  // gpucol_triangle_contact's (thesis §5.3.4 runs Möller's test, §3.5, before generating contacts).
  double a[3][3], b[3][3];
  for (int v = 0; v < 3; ++v) {
    for (int k = 0; k < 3; ++k) {
      a[v][k] = af[v][k];
      b[v][k] = bf[v][k];
    }
  }
  const GpucolContact r = gpucol_triangle_contact(a, b);
  intersects = r.intersects != 0;
  if (!r.contact) return std::nullopt;
  auto toFloat = [](const double(&v)[3]) {
    return Eigen::Vector3f(static_cast<float>(v[0]), static_cast<float>(v[1]), static_cast<float>(v[2]));
  };
  return TriangleContact{toFloat(r.point), toFloat(r.normalOnB), static_cast<float>(r.depth),
                         r.onFaceOfB != 0, r.sameFacing != 0,    toFloat(r.deepest)};
}

}  // namespace detail

}  // namespace gpucol
