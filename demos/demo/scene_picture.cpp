#include "demo/scene_picture.h"

#include <BulletDynamics/Dynamics/btDiscreteDynamicsWorld.h>

#include <algorithm>
#include <cmath>

#include "demo/collision_triangles.h"
#include "demo/png_writer.h"
#include "scenes/world_scene.h"

namespace gpucol::demo {
namespace {

constexpr Rgb kStaticColour{186, 180, 168};

// HSV (all in 0..1) to RGB bytes.
Rgb fromHsv(float hue, float saturation, float value) {
  const float h = 6 * (hue - std::floor(hue));
  const int sector = int(h) % 6;
  const float f = h - std::floor(h);
  const float p = value * (1 - saturation), q = value * (1 - saturation * f),
              t = value * (1 - saturation * (1 - f));
  float r = 0, g = 0, b = 0;
  switch (sector) {
    case 0:
      r = value, g = t, b = p;
      break;
    case 1:
      r = q, g = value, b = p;
      break;
    case 2:
      r = p, g = value, b = t;
      break;
    case 3:
      r = p, g = q, b = value;
      break;
    case 4:
      r = t, g = p, b = value;
      break;
    default:
      r = value, g = p, b = q;
      break;
  }
  auto byte = [](float v) { return std::uint8_t(std::lround(std::clamp(v, 0.0f, 1.0f) * 255)); };
  return {byte(r), byte(g), byte(b)};
}

}  // namespace

std::vector<Rgb> objectColours(scenes::WorldScene& scene) {
  const btCollisionObjectArray& objects = scene.world().getCollisionObjectArray();
  std::vector<Rgb> colours;
  colours.reserve(std::size_t(objects.size()));
  int dynamic = 0;
  for (int i = 0; i < objects.size(); ++i) {
    if (objects[i]->isStaticOrKinematicObject()) {
      colours.push_back(kStaticColour);
    } else {
      // Start at orange-red rather than pure red; saturation and value leave room for the shading.
      colours.push_back(fromHsv(0.03f + 0.618034f * float(dynamic++), 0.62f, 0.95f));
    }
  }
  return colours;
}

void pictureBounds(scenes::WorldScene& scene, btVector3& boxMin, btVector3& boxMax) {
  const std::vector<btRigidBody*>& bodies = scene.dynamicBodies();
  const float ground = scene.description().groundTop;
  if (bodies.empty()) {
    boxMin = btVector3(-1, ground - 0.5f, -1);
    boxMax = btVector3(1, ground + 1.5f, 1);
    return;
  }
  boxMin = btVector3(BT_LARGE_FLOAT, BT_LARGE_FLOAT, BT_LARGE_FLOAT);
  boxMax = -boxMin;
  for (const btRigidBody* body : bodies) {
    btVector3 low, high;
    body->getAabb(low, high);
    boxMin.setMin(low);
    boxMax.setMax(high);
  }
  boxMin.setY(std::min(boxMin.y(), ground));
  const float widen =
      0.25f * std::max({boxMax.x() - boxMin.x(), boxMax.y() - boxMin.y(), boxMax.z() - boxMin.z()});
  boxMin -= btVector3(widen, 0, widen);
  boxMax += btVector3(widen, 0, widen);
}

Camera pictureCamera(scenes::WorldScene& scene, const PictureOptions& options) {
  btVector3 boxMin, boxMax;
  pictureBounds(scene, boxMin, boxMax);
  return Camera::framing(boxMin, boxMax, options.azimuth, options.elevation, options.perspective,
                         options.width, options.height);
}

RenderedScene renderScene(scenes::WorldScene& scene, const Camera& camera, const RenderOptions& options) {
  return renderTriangles(collisionTriangles(scene.world()), objectColours(scene), camera, options);
}

void writeScenePicture(scenes::WorldScene& scene, const std::string& path, const PictureOptions& options) {
  writePng(renderScene(scene, pictureCamera(scene, options), options.render).image, path);
}

}  // namespace gpucol::demo
