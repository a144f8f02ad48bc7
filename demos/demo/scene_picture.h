#pragma once

#include <LinearMath/btVector3.h>

#include <string>
#include <vector>

#include "demo/camera.h"
#include "demo/rgb_image.h"
#include "demo/scene_render.h"

namespace gpucol::scenes {
class WorldScene;
}

namespace gpucol::demo {

/// How a picture of a WorldScene is taken.
struct PictureOptions {
  int width = 1024;         ///< Pixels.
  int height = 768;         ///< Pixels.
  bool perspective = true;  ///< False: orthographic.
  float azimuth = 0.6f;     ///< Radians around the vertical axis from the +z side (about 34 degrees).
  float elevation = 0.3f;   ///< Radians above the horizon (about 17 degrees): mostly from the side.
  RenderOptions render;     ///< Light, background, supersampling, outlines.
};

/// Colour of each collision object of `scene`'s world, in the world's object order: static bodies (the
/// ground, a bin) warm grey; dynamic body k a hue k × 0.618 turns around the colour wheel (the golden ratio
/// keeps any run of neighbours far apart in hue), so every body is told apart from its neighbours.
std::vector<Rgb> objectColours(scenes::WorldScene& scene);

/// The box a picture of `scene` frames: the dynamic bodies' boxes, down to the ground's top face, widened by
/// a quarter of their largest side so that the ground (or the bin) around them shows.
void pictureBounds(scenes::WorldScene& scene, btVector3& boxMin, btVector3& boxMax);

/// The camera a picture of `scene` uses by default: Camera::framing over pictureBounds from the options'
/// side view.
Camera pictureCamera(scenes::WorldScene& scene, const PictureOptions& options);

/// Renders every collision object of `scene` (collisionTriangles) in objectColours through `camera`.
RenderedScene renderScene(scenes::WorldScene& scene, const Camera& camera, const RenderOptions& options = {});

/// Renders `scene` with pictureCamera and writes the PNG to `path` (throws std::runtime_error when it
/// cannot).
void writeScenePicture(scenes::WorldScene& scene, const std::string& path,
                       const PictureOptions& options = {});

}  // namespace gpucol::demo
