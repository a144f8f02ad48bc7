#pragma once

#include <LinearMath/btVector3.h>

namespace gpucol::demo {

/// Where a picture is taken from: an eye looking at a target, perspective or orthographic, onto a
/// width × height image. Pixel coordinates run right and down from the top left corner of the image; pixel
/// (i, j) covers [i, i + 1) × [j, j + 1), so its centre is at (i + 0.5, j + 0.5).
class Camera {
 public:
  /// A point carried into the image: pixel coordinates and its distance in front of the eye along the view
  /// direction (metres; <= 0 is behind the eye).
  struct Projected {
    float x = 0;      ///< Pixels from the left edge.
    float y = 0;      ///< Pixels from the top edge.
    float depth = 0;  ///< Metres along the view direction.
  };

  /// A perspective camera at `eye` looking at `target` with `up` roughly up, `verticalFov` radians from the
  /// top to the bottom edge of the image.
  static Camera perspective(const btVector3& eye, const btVector3& target, const btVector3& up,
                            float verticalFov, int width, int height);
  /// An orthographic camera looking from `eye` towards `target`, showing `viewHeight` metres from the bottom
  /// edge to the top edge.
  static Camera orthographic(const btVector3& eye, const btVector3& target, const btVector3& up,
                             float viewHeight, int width, int height);
  /// A camera from the side and a little above (y is up): looking from `azimuth` radians around the y axis
  /// (0 looks along -z) and `elevation` radians above the horizon, at the box [boxMin, boxMax], placed so
  /// that the whole box fits in the image with a few percent to spare.
  static Camera framing(const btVector3& boxMin, const btVector3& boxMax, float azimuth, float elevation,
                        bool perspective, int width, int height, float verticalFov = 0.6f);

  /// `point` (world) in pixel coordinates and depth.
  Projected project(const btVector3& point) const;
  /// `point` in the camera's frame: x right, y up, z the distance in front of the eye.
  btVector3 toView(const btVector3& point) const;
  /// A view-frame point (z > 0 for perspective) in pixel coordinates.
  Projected viewToPixel(const btVector3& view) const;

  /// The same view onto an image `factor` times as wide and high (for supersampling).
  Camera scaled(int factor) const;

  /// Image width in pixels.
  int width() const { return m_width; }
  /// Image height in pixels.
  int height() const { return m_height; }
  /// True for a perspective camera.
  bool isPerspective() const { return m_perspective; }
  /// The eye (world).
  const btVector3& eye() const { return m_eye; }
  /// Unit view direction (world), from the eye into the scene.
  const btVector3& forward() const { return m_forward; }
  /// Unit direction of the image's right edge (world).
  const btVector3& right() const { return m_right; }
  /// Unit direction of the image's top edge (world).
  const btVector3& up() const { return m_up; }
  /// Nearest depth drawn (metres): triangles are clipped there.
  float nearDepth() const { return m_near; }

 private:
  Camera(const btVector3& eye, const btVector3& target, const btVector3& up, bool perspective, float scale,
         int width, int height);

  btVector3 m_eye;
  btVector3 m_forward;
  btVector3 m_right;
  btVector3 m_up;
  bool m_perspective = true;
  // Perspective: pixels per unit of x / z (the focal length in pixels). Orthographic: pixels per metre.
  float m_scale = 1;
  int m_width = 1;
  int m_height = 1;
  float m_near = 0.01f;
};

}  // namespace gpucol::demo
