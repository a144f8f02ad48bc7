// The demo's scene picture: what collisionTriangles collects, and the pixels renderTriangles draws for a box
// on the ground seen from known cameras (positions worked out by hand from the box's corners).
#include "demo/scene_picture.h"

#include <BulletDynamics/Dynamics/btDiscreteDynamicsWorld.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>

#include "demo/collision_triangles.h"
#include "demo/scene_render.h"
#include "scenes/world_scene.h"
#include "scenes/world_scenes.h"

namespace gpucol::demo {
namespace {

using scenes::CollisionBackend;
using scenes::WorldOptions;
using scenes::WorldScene;

// The stack scene's bodies are added in order: object 0 is the ground, object k the k-th box from the bottom.
constexpr int kGround = 0;
constexpr int kFirstBox = 1;

WorldScene makeBoxes(int boxes, CollisionBackend backend = CollisionBackend::Gpucol) {
  WorldOptions options;
  options.backend = backend;
  return WorldScene(scenes::makeStackScene(boxes), options);
}

// True when `pixel` is `base` times one factor in [0, 1] on all three channels (what flat shading draws),
// within rounding.
bool isShadeOf(Rgb pixel, Rgb base) {
  const int brightest = std::max({base.r, base.g, base.b});
  const float factor = float(brightest == base.r   ? pixel.r
                             : brightest == base.g ? pixel.g
                                                   : pixel.b) /
                       float(brightest);
  if (factor <= 0 || factor > 1.01f) return false;
  return std::abs(int(pixel.r) - int(std::lround(base.r * factor))) <= 2 &&
         std::abs(int(pixel.g) - int(std::lround(base.g * factor))) <= 2 &&
         std::abs(int(pixel.b) - int(std::lround(base.b * factor))) <= 2;
}

TEST(CollisionTriangles, EveryObjectsShapeOnBothBackends) {
  // One box (12 triangles) on a ground box (12 triangles): every triangle of both, whatever the shape class.
  for (CollisionBackend backend : {CollisionBackend::Gpucol, CollisionBackend::GImpact}) {
    WorldScene scene = makeBoxes(1, backend);
    const std::vector<WorldTriangle> triangles = collisionTriangles(scene.world());
    ASSERT_EQ(triangles.size(), 24u) << scenes::backendName(backend);
    int perObject[2] = {0, 0};
    btVector3 boxMin(1e9f, 1e9f, 1e9f), boxMax(-1e9f, -1e9f, -1e9f);
    for (const WorldTriangle& t : triangles) {
      ASSERT_GE(t.object, 0);
      ASSERT_LT(t.object, 2);
      ++perObject[t.object];
      if (t.object != kFirstBox) continue;
      for (const btVector3& v : {t.a, t.b, t.c}) boxMin.setMin(v), boxMax.setMax(v);
    }
    EXPECT_EQ(perObject[kGround], 12);
    EXPECT_EQ(perObject[kFirstBox], 12);
    // The box's triangles are placed by its world transform: the unit cube resting on y = 0.
    EXPECT_NEAR(boxMin.x(), -0.5f, 1e-5f);
    EXPECT_NEAR(boxMax.x(), 0.5f, 1e-5f);
    EXPECT_NEAR(boxMin.y(), 0.0f, 1e-5f);
    EXPECT_NEAR(boxMax.y(), 1.0f, 1e-5f);
  }
}

TEST(SceneRender, BoxOnGroundFromTheSideOrthographic) {
  WorldScene scene = makeBoxes(1);
  // Looking along -z at (0, 0.5) with 4 m from the bottom to the top edge on 200 rows: 50 pixels per metre,
  // the image centre (100, 100) at x = 0, y = 0.5. The box [-0.5, 0.5] × [0, 1] covers columns 75..125 and
  // rows 75..125; the ground's front face [-10, 10] × [-1, 0] covers rows 125..175, every column.
  const Camera camera =
      Camera::orthographic(btVector3(0, 0.5f, 10), btVector3(0, 0.5f, 0), btVector3(0, 1, 0), 4.0f, 200, 200);
  const RenderOptions options;
  const RenderedScene picture = renderScene(scene, camera, options);
  ASSERT_EQ(picture.image.width(), 200);
  ASSERT_EQ(picture.image.height(), 200);
  const std::vector<Rgb> colours = objectColours(scene);
  ASSERT_EQ(colours.size(), 2u);
  EXPECT_NE(colours[kGround], colours[kFirstBox]);

  for (int y = 0; y < 200; ++y) {
    for (int x = 0; x < 200; ++x) {
      // Pixels two or more away from an edge of the box or the ground's top: decided without ambiguity.
      const bool inBox = x >= 77 && x <= 122 && y >= 77 && y <= 122;
      const bool inGround = y >= 127 && y <= 172;
      const bool background = y <= 72 || (y <= 122 && (x <= 72 || x >= 127)) || y >= 178;
      if (inBox) {
        ASSERT_EQ(picture.object(x, y), kFirstBox) << x << ", " << y;
      } else if (inGround) {
        ASSERT_EQ(picture.object(x, y), kGround) << x << ", " << y;
      } else if (background) {
        ASSERT_EQ(picture.object(x, y), -1) << x << ", " << y;
        ASSERT_EQ(picture.image.at(x, y), options.background) << x << ", " << y;
      }
    }
  }
  // The box's front face (normal +z, towards the eye) in its own colour, shaded by the documented rule:
  // ambient + (1 - ambient) * max(0, n . light).
  const float cosine = float(options.lightDirection.normalized().z());
  const Rgb expected = scaled(colours[kFirstBox], options.ambient + (1 - options.ambient) * cosine);
  const Rgb centre = picture.image.at(100, 100);
  EXPECT_NEAR(centre.r, expected.r, 1);
  EXPECT_NEAR(centre.g, expected.g, 1);
  EXPECT_NEAR(centre.b, expected.b, 1);
  EXPECT_TRUE(isShadeOf(picture.image.at(150, 150), colours[kGround]));
}

TEST(SceneRender, DefaultCameraShowsTheBoxAtItsProjectedCentre) {
  WorldScene scene = makeBoxes(1);
  PictureOptions options;
  options.width = 320;
  options.height = 240;
  for (bool perspective : {true, false}) {
    options.perspective = perspective;
    const Camera camera = pictureCamera(scene, options);
    const RenderedScene picture = renderScene(scene, camera, options.render);
    ASSERT_EQ(picture.image.width(), 320);
    ASSERT_EQ(picture.image.height(), 240);
    const Camera::Projected centre = camera.project(btVector3(0, 0.5f, 0));
    ASSERT_GT(centre.depth, 0);
    const int x = int(centre.x), y = int(centre.y);
    ASSERT_TRUE(picture.image.contains(x, y));
    EXPECT_EQ(picture.object(x, y), kFirstBox);
    EXPECT_TRUE(isShadeOf(picture.image.at(x, y), objectColours(scene)[kFirstBox]));
    // The bottom corners see the ground around the box (the 20 m ground fills the view's lower part).
    EXPECT_EQ(picture.object(0, 239), kGround);
    EXPECT_EQ(picture.object(319, 239), kGround);
  }
}

TEST(SceneRender, NearestSurfaceWinsLookingDownOnTwoBoxes) {
  WorldScene scene = makeBoxes(2);
  // From straight above, the upper box hides the lower one and the ground under it: without the depth test,
  // whichever was drawn last would show. Both orders of drawing are tried.
  const Camera camera =
      Camera::perspective(btVector3(0, 10, 0), btVector3(0, 0, 0), btVector3(0, 0, -1), 0.8f, 64, 64);
  std::vector<WorldTriangle> triangles = collisionTriangles(scene.world());
  for (int order = 0; order < 2; ++order) {
    if (order == 1) std::reverse(triangles.begin(), triangles.end());
    const RenderedScene picture = renderTriangles(triangles, objectColours(scene), camera);
    EXPECT_EQ(picture.object(32, 32), kFirstBox + 1) << "order " << order;
    EXPECT_EQ(picture.object(1, 1), kGround) << "order " << order;
  }
}

TEST(SceneRender, TrianglesThroughTheEyeAreClippedNotWrapped) {
  // A ground triangle reaching from far in front of the eye to behind it: only the part in front is drawn,
  // below the horizon; nothing of the part behind the eye wraps round into the sky.
  const std::vector<WorldTriangle> triangles = {
      {btVector3(-50, 0, 50), btVector3(50, 0, 50), btVector3(0, 0, -50), 0}};
  const Camera camera =
      Camera::perspective(btVector3(0, 1, 0), btVector3(0, 1, -1), btVector3(0, 1, 0), 1.0f, 64, 64);
  const RenderedScene picture = renderTriangles(triangles, {Rgb{200, 50, 50}}, camera);
  for (int x = 0; x < 64; ++x) {
    for (int y = 0; y < 31; ++y) ASSERT_EQ(picture.object(x, y), -1) << x << ", " << y;
    ASSERT_EQ(picture.object(x, 63), 0) << x;
  }
}

}  // namespace
}  // namespace gpucol::demo
