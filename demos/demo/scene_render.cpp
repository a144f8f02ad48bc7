#include "demo/scene_render.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace gpucol::demo {
namespace {

// Creases between faces of one object whose normals differ by more than this are outlined: 40 degrees keeps a
// box's 90-degree edges and skips the facets of the procedural spheres (about 14 degrees) and tori (15 and
// 30).
const float kCreaseCosine = std::cos(40.0f * 3.14159265f / 180.0f);
constexpr float kSilhouetteShade = 0.45f;
constexpr float kCreaseShade = 0.7f;

struct Buffers {
  RgbImage colour;
  std::vector<float> nearness;  // 1 / depth (perspective) or -depth (orthographic): both affine on screen.
  std::vector<int> object;
  std::vector<int> triangle;
};

struct ScreenVertex {
  float x, y, nearness;
};

// Fills the screen triangle (a, b, c) with the pixels whose centres it covers (edges included).
void rasterize(const ScreenVertex& a, const ScreenVertex& b, const ScreenVertex& c, Rgb colour, int object,
               int triangle, Buffers& buffers) {
  const float area = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
  if (!(std::fabs(area) > 1e-12f)) return;
  const int width = buffers.colour.width(), height = buffers.colour.height();
  const int x0 = std::max(0, int(std::floor(std::min({a.x, b.x, c.x}) - 0.5f)));
  const int x1 = std::min(width - 1, int(std::ceil(std::max({a.x, b.x, c.x}) - 0.5f)));
  const int y0 = std::max(0, int(std::floor(std::min({a.y, b.y, c.y}) - 0.5f)));
  const int y1 = std::min(height - 1, int(std::ceil(std::max({a.y, b.y, c.y}) - 0.5f)));
  const float inverseArea = 1.0f / area;
  for (int y = y0; y <= y1; ++y) {
    const float py = float(y) + 0.5f;
    for (int x = x0; x <= x1; ++x) {
      const float px = float(x) + 0.5f;
      // Barycentric weights from the edge functions, signed so that all three are >= 0 inside.
      const float wa = ((b.x - px) * (c.y - py) - (b.y - py) * (c.x - px)) * inverseArea;
      const float wb = ((c.x - px) * (a.y - py) - (c.y - py) * (a.x - px)) * inverseArea;
      const float wc = 1.0f - wa - wb;
      if (wa < 0 || wb < 0 || wc < 0) continue;
      const float nearness = wa * a.nearness + wb * b.nearness + wc * c.nearness;
      const std::size_t i = std::size_t(y) * std::size_t(width) + std::size_t(x);
      if (nearness <= buffers.nearness[i]) continue;
      buffers.nearness[i] = nearness;
      buffers.colour.at(x, y) = colour;
      buffers.object[i] = object;
      buffers.triangle[i] = triangle;
    }
  }
}

// The part of the view-space triangle in front of the near plane (0, 3 or 4 corners: Sutherland-Hodgman
// against one plane).
int clipNear(const std::array<btVector3, 3>& in, float near, std::array<btVector3, 4>& out) {
  int count = 0;
  for (int i = 0; i < 3; ++i) {
    const btVector3& p = in[std::size_t(i)];
    const btVector3& q = in[std::size_t((i + 1) % 3)];
    const bool pIn = p.z() >= near, qIn = q.z() >= near;
    if (pIn) out[std::size_t(count++)] = p;
    if (pIn != qIn) out[std::size_t(count++)] = p + (q - p) * ((near - p.z()) / (q.z() - p.z()));
  }
  return count;
}

}  // namespace

RenderedScene renderTriangles(const std::vector<WorldTriangle>& triangles,
                              const std::vector<Rgb>& objectColours, const Camera& finalCamera,
                              const RenderOptions& options) {
  if (options.supersample < 1 || options.supersample > 8) {
    throw std::invalid_argument("render: supersample must be 1 to 8");
  }
  const int factor = options.supersample;
  const Camera camera = finalCamera.scaled(factor);
  Buffers buffers;
  buffers.colour = RgbImage(camera.width(), camera.height(), options.background);
  const std::size_t pixels = std::size_t(camera.width()) * std::size_t(camera.height());
  buffers.nearness.assign(pixels, -std::numeric_limits<float>::infinity());
  buffers.object.assign(pixels, -1);
  buffers.triangle.assign(pixels, -1);
  const btVector3 light =
      options.lightDirection.length() > 0 ? options.lightDirection.normalized() : btVector3(0, 1, 0);
  std::vector<btVector3> normals(triangles.size(), btVector3(0, 0, 0));

  for (std::size_t t = 0; t < triangles.size(); ++t) {
    const WorldTriangle& triangle = triangles[t];
    btVector3 normal = (triangle.b - triangle.a).cross(triangle.c - triangle.a);
    if (!(normal.length() > 0) || !std::isfinite(normal.length())) continue;  // Degenerate or not finite.
    normal.normalize();
    const btVector3 towardsEye = camera.isPerspective() ? camera.eye() - triangle.a : -camera.forward();
    if (normal.dot(towardsEye) < 0) normal = -normal;
    normals[t] = normal;
    const float shade = options.ambient + (1 - options.ambient) * std::max(0.0f, float(normal.dot(light)));
    const std::size_t object = std::size_t(triangle.object);
    const Rgb base = object < objectColours.size() ? objectColours[object] : Rgb{128, 128, 128};

    const std::array<btVector3, 3> view{camera.toView(triangle.a), camera.toView(triangle.b),
                                        camera.toView(triangle.c)};
    std::array<btVector3, 4> clipped;
    const int corners = clipNear(view, camera.nearDepth(), clipped);
    std::array<ScreenVertex, 4> screen{};
    for (int i = 0; i < corners; ++i) {
      const Camera::Projected p = camera.viewToPixel(clipped[std::size_t(i)]);
      screen[std::size_t(i)] = {p.x, p.y, camera.isPerspective() ? 1.0f / p.depth : -p.depth};
    }
    for (int i = 1; i + 1 < corners; ++i) {
      rasterize(screen[0], screen[std::size_t(i)], screen[std::size_t(i + 1)], scaled(base, shade),
                triangle.object, int(t), buffers);
    }
  }

  if (options.outlines) {
    // Decide every pixel from the buffers before darkening any, so the outline is the same whatever the
    // order.
    RgbImage outlined = buffers.colour;
    const int width = camera.width(), height = camera.height();
    for (int y = 0; y < height; ++y) {
      for (int x = 0; x < width; ++x) {
        const std::size_t i = std::size_t(y) * std::size_t(width) + std::size_t(x);
        if (buffers.object[i] < 0) continue;
        float shade = 1;
        const int neighbours[4][2] = {{1, 0}, {-1, 0}, {0, 1}, {0, -1}};
        for (const auto& d : neighbours) {
          const int nx = x + d[0], ny = y + d[1];
          if (!buffers.colour.contains(nx, ny)) continue;
          const std::size_t j = std::size_t(ny) * std::size_t(width) + std::size_t(nx);
          if (buffers.object[j] != buffers.object[i]) {
            shade = std::min(shade, kSilhouetteShade);
          } else if (buffers.triangle[j] != buffers.triangle[i] &&
                     normals[std::size_t(buffers.triangle[j])].dot(
                         normals[std::size_t(buffers.triangle[i])]) < kCreaseCosine) {
            shade = std::min(shade, kCreaseShade);
          }
        }
        if (shade < 1) outlined.at(x, y) = scaled(buffers.colour.at(x, y), shade);
      }
    }
    buffers.colour = std::move(outlined);
  }

  RenderedScene out;
  out.image = buffers.colour.downsampled(factor);
  out.objectAt.assign(std::size_t(out.image.width()) * std::size_t(out.image.height()), -1);
  // The sample just below and right of each pixel's centre stands for the pixel.
  const int sample = factor / 2;
  for (int y = 0; y < out.image.height(); ++y) {
    for (int x = 0; x < out.image.width(); ++x) {
      out.objectAt[std::size_t(y) * std::size_t(out.image.width()) + std::size_t(x)] =
          buffers.object[std::size_t(y * factor + sample) * std::size_t(camera.width()) +
                         std::size_t(x * factor + sample)];
    }
  }
  return out;
}

}  // namespace gpucol::demo
