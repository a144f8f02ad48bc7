#pragma once

#include <LinearMath/btVector3.h>

#include <vector>

#include "demo/camera.h"
#include "demo/collision_triangles.h"
#include "demo/rgb_image.h"

namespace gpucol::demo {

/// How renderTriangles shades and finishes a picture.
struct RenderOptions {
  /// Direction towards the light (world, need not be unit): from above, a little to the right of and in
  /// front of the default side view, so that a box's top, front and side faces get three different shades.
  btVector3 lightDirection{0.25f, 1.0f, 0.55f};
  /// Share of a colour that faces turned away from the light keep (the rest follows the light's cosine).
  float ambient = 0.35f;
  Rgb background{233, 238, 244};  ///< Colour where no triangle is.
  /// Samples per pixel along each axis: the picture is drawn this many times larger and shrunk
  /// (anti-aliasing).
  int supersample = 2;
  /// Darken the pixels along each object's silhouette and along creases sharper than 40 degrees within one
  /// object (a box's edges), so that touching bodies of similar shade stay apart.
  bool outlines = true;
};

/// A rendered picture and, for each of its pixels, which object was drawn there.
struct RenderedScene {
  RgbImage image;  ///< The picture, camera.width() × camera.height().
  std::vector<int>
      objectAt;  ///< Row by row: the object drawn at the pixel (one central sample), -1 for none.
  /// The object at pixel (x, y), -1 for background; unchecked.
  int object(int x, int y) const {
    return objectAt[std::size_t(y) * std::size_t(image.width()) + std::size_t(x)];
  }
};

/// Draws `triangles` as seen by `camera`: flat-shaded (each triangle lit by its face normal, turned towards
/// the eye, so the winding does not matter), hidden surfaces removed by a depth buffer, triangles cut at the
/// near plane. Triangle t is drawn in `objectColours[t.object]` (objects without a colour are mid grey).
RenderedScene renderTriangles(const std::vector<WorldTriangle>& triangles,
                              const std::vector<Rgb>& objectColours, const Camera& camera,
                              const RenderOptions& options = {});

}  // namespace gpucol::demo
