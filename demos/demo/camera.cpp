#include "demo/camera.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>

namespace gpucol::demo {

Camera::Camera(const btVector3& eye, const btVector3& target, const btVector3& up, bool perspective,
               float scale, int width, int height)
    : m_eye(eye), m_perspective(perspective), m_scale(scale), m_width(width), m_height(height) {
  if (width <= 0 || height <= 0) throw std::invalid_argument("camera: the image size must be positive");
  const btVector3 toTarget = target - eye;
  if (!(toTarget.length() > 0))
    throw std::invalid_argument("camera: the eye and the target are the same point");
  m_forward = toTarget.normalized();
  const btVector3 right = m_forward.cross(up);
  if (!(right.length() > 1e-6f))
    throw std::invalid_argument("camera: 'up' is parallel to the view direction");
  m_right = right.normalized();
  m_up = m_right.cross(m_forward);
  // A near plane a thousandth of the way to the target keeps depth precision and clips what is at the eye.
  m_near = std::max(1e-4f, 1e-3f * toTarget.length());
}

Camera Camera::perspective(const btVector3& eye, const btVector3& target, const btVector3& up,
                           float verticalFov, int width, int height) {
  if (!(verticalFov > 0 && verticalFov < 3.1f))
    throw std::invalid_argument("camera: field of view out of range");
  return Camera(eye, target, up, true, 0.5f * float(height) / std::tan(0.5f * verticalFov), width, height);
}

Camera Camera::orthographic(const btVector3& eye, const btVector3& target, const btVector3& up,
                            float viewHeight, int width, int height) {
  if (!(viewHeight > 0)) throw std::invalid_argument("camera: the view height must be positive");
  return Camera(eye, target, up, false, float(height) / viewHeight, width, height);
}

Camera Camera::framing(const btVector3& boxMin, const btVector3& boxMax, float azimuth, float elevation,
                       bool perspective, int width, int height, float verticalFov) {
  const btVector3 centre = 0.5f * (boxMin + boxMax);
  const float radius = std::max(0.5f * (boxMax - boxMin).length(), 1e-3f);
  const btVector3 back(std::sin(azimuth) * std::cos(elevation), std::sin(elevation),
                       std::cos(azimuth) * std::cos(elevation));
  const btVector3 up(0, 1, 0);
  // The box's corners in a frame looking along -back through the centre: x right, y up, z away from the eye.
  const btVector3 forward = -back;
  const btVector3 right = forward.cross(up).normalized();
  const btVector3 trueUp = right.cross(forward);
  std::array<btVector3, 8> corners;
  for (int i = 0; i < 8; ++i) {
    const btVector3 corner((i & 1) ? boxMax.x() : boxMin.x(), (i & 2) ? boxMax.y() : boxMin.y(),
                           (i & 4) ? boxMax.z() : boxMin.z());
    const btVector3 d = corner - centre;
    corners[std::size_t(i)] = btVector3(d.dot(right), d.dot(trueUp), d.dot(forward));
  }
  constexpr float kSpare = 1.06f;  // A little room around the box, so outlines are not cut by the edge.
  const float aspect = float(width) / float(height);
  if (!perspective) {
    float halfWidth = 0, halfHeight = 0;
    for (const btVector3& c : corners) {
      halfWidth = std::max(halfWidth, std::fabs(c.x()));
      halfHeight = std::max(halfHeight, std::fabs(c.y()));
    }
    const float viewHeight = 2 * kSpare * std::max({halfHeight, halfWidth / aspect, 1e-3f});
    return orthographic(centre + 3 * radius * back, centre, up, viewHeight, width, height);
  }
  // Perspective: the nearest eye distance d at which every corner is inside both half-angles,
  // |x| <= tan(h/2) (d + z) and |y| <= tan(v/2) (d + z).
  const float tanV = std::tan(0.5f * verticalFov) / kSpare;
  const float tanH = tanV * aspect;
  float distance = 1e-3f;
  for (const btVector3& c : corners) {
    distance = std::max({distance, std::fabs(c.x()) / tanH - c.z(), std::fabs(c.y()) / tanV - c.z()});
  }
  // Never inside the box's bounding sphere: the near plane would cut it.
  distance = std::max(distance, 1.05f * radius);
  return Camera::perspective(centre + distance * back, centre, up, verticalFov, width, height);
}

btVector3 Camera::toView(const btVector3& point) const {
  const btVector3 d = point - m_eye;
  return btVector3(d.dot(m_right), d.dot(m_up), d.dot(m_forward));
}

Camera::Projected Camera::viewToPixel(const btVector3& view) const {
  Projected p;
  p.depth = view.z();
  const float factor = m_perspective ? m_scale / view.z() : m_scale;
  p.x = 0.5f * float(m_width) + view.x() * factor;
  p.y = 0.5f * float(m_height) - view.y() * factor;
  return p;
}

Camera::Projected Camera::project(const btVector3& point) const {
  return viewToPixel(toView(point));
}

Camera Camera::scaled(int factor) const {
  Camera out = *this;
  out.m_width *= factor;
  out.m_height *= factor;
  out.m_scale *= float(factor);
  return out;
}

}  // namespace gpucol::demo
