#include "scenes/world_scenes.h"

#include <gpucol/mass_properties.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <memory>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "scenes/pile_meshes.h"
#include "scenes/procedural_meshes.h"

namespace gpucol::scenes {
namespace {

constexpr double kPi = 3.14159265358979323846;

btTransform at(float x, float y, float z, const btQuaternion& rotation = btQuaternion::getIdentity()) {
  return btTransform(rotation, btVector3(x, y, z));
}

// A rotation drawn uniformly (Shoemake's method) from raw mt19937 words, so the scene is the same with every
// standard library (std::uniform_real_distribution's algorithm is implementation-defined).
btQuaternion randomRotation(std::mt19937& random) {
  auto unit = [&random] { return double(random()) / 4294967296.0; };
  const double u1 = unit(), u2 = 2 * kPi * unit(), u3 = 2 * kPi * unit();
  const double a = std::sqrt(1 - u1), b = std::sqrt(u1);
  return btQuaternion(btScalar(a * std::sin(u2)), btScalar(a * std::cos(u2)), btScalar(b * std::sin(u3)),
                      btScalar(b * std::cos(u3)));
}

// Largest distance of a vertex from the mesh's origin.
float boundingRadius(const TriangleMesh& mesh) {
  float radius2 = 0;
  const std::vector<float>& xyz = mesh.positions();
  for (std::size_t i = 0; i < xyz.size(); i += 3) {
    radius2 = std::max(radius2, xyz[i] * xyz[i] + xyz[i + 1] * xyz[i + 1] + xyz[i + 2] * xyz[i + 2]);
  }
  return std::sqrt(radius2);
}

ConvexPiece box(const btVector3& half, const btVector3& centre = btVector3(0, 0, 0)) {
  return {ConvexPiece::Kind::Box, half, btTransform(btQuaternion::getIdentity(), centre), {}};
}

// A torus about the z axis as capsules along the chords of its ring (about the mesh's tube).
std::vector<ConvexPiece> torusPieces(float major, float minor, int capsules) {
  std::vector<ConvexPiece> pieces;
  for (int k = 0; k < capsules; ++k) {
    const double a0 = 2 * kPi * k / capsules, a1 = 2 * kPi * (k + 1) / capsules, mid = 0.5 * (a0 + a1);
    const btVector3 p0(btScalar(major * std::cos(a0)), btScalar(major * std::sin(a0)), 0);
    const btVector3 p1(btScalar(major * std::cos(a1)), btScalar(major * std::sin(a1)), 0);
    // The capsule lies along its y axis: turned about z by `mid`, y points along the chord.
    pieces.push_back({ConvexPiece::Kind::Capsule,
                      btVector3(minor, 0.5f * (p1 - p0).length(), 0),
                      btTransform(btQuaternion(btVector3(0, 0, 1), btScalar(mid)), 0.5f * (p0 + p1)),
                      {}});
  }
  return pieces;
}

// makeLShape's two arms as boxes, carried into the frame the mesh was moved to: p' = R^T (p - t) for the
// transform p = R p' + t that inPrincipalFrame reports.
std::vector<ConvexPiece> lShapePieces(float size, float depth, const std::array<double, 9>& rotation,
                                      const std::array<double, 3>& translation) {
  const float s = size, w = size / 3.0f;
  const std::vector<ConvexPiece> original = {
      box(btVector3(s / 2, w / 2, depth / 2), btVector3(0, w / 2 - s / 2, 0)),
      box(btVector3(w / 2, (s - w) / 2, depth / 2), btVector3(w / 2 - s / 2, (w + s) / 2 - s / 2, 0))};
  btScalar m[9];
  for (int i = 0; i < 9; ++i) m[i] = btScalar(rotation[std::size_t(i)]);
  const btMatrix3x3 r(m[0], m[1], m[2], m[3], m[4], m[5], m[6], m[7], m[8]);
  const btTransform toPrincipal =
      btTransform(r, btVector3(btScalar(translation[0]), btScalar(translation[1]), btScalar(translation[2])))
          .inverse();
  std::vector<ConvexPiece> pieces;
  for (ConvexPiece piece : original) {
    piece.pose = toPrincipal * piece.pose;
    pieces.push_back(piece);
  }
  return pieces;
}

float massOf(const TriangleMesh& mesh) {
  return float(mesh.massProperties(kSceneDensity).mass);
}

// The 6 m bin of the pile of 50 as one watertight mesh (makePileScene's), for the tori scene.
TriangleMesh binMesh() { return makeBin(3.5f, 3.0f, 0.5f, 2.5f); }

// The static bin of the piles as mesh 0 and body 0 of `scene`, with its convex pieces: `inside` metres wide
// inside; walls, floor and height scale with `scale` (1 for the pile of 1.5 m cells: 0.5 m thick walls 2.5 m
// high on a 0.5 m floor).
void addBin(SceneDescription& scene, float inside, float scale) {
  const float h = inside / 2, t = 0.5f * scale, height = 2.5f * scale;
  // The reference's pieces: the floor spans the walls' footprint; the x walls run the full length, the z
  // walls fit between them.
  const std::vector<std::pair<btVector3, btVector3>> binBoxes = {
      {btVector3(h + t, t / 2, h + t), btVector3(0, -t / 2, 0)},
      {btVector3(t / 2, height / 2, h + t), btVector3(h + t / 2, height / 2, 0)},
      {btVector3(t / 2, height / 2, h + t), btVector3(-h - t / 2, height / 2, 0)},
      {btVector3(h, height / 2, t / 2), btVector3(0, height / 2, h + t / 2)},
      {btVector3(h, height / 2, t / 2), btVector3(0, height / 2, -h - t / 2)}};
  std::vector<ConvexPiece> binPieces;
  for (const auto& [half, centre] : binBoxes) binPieces.push_back(box(half, centre));
  // One watertight surface: boxes merged into one mesh would leave the faces where they meet inside it (a
  // wall's bottom face on the floor), and a body pressed into the floor there would be pushed down.
  scene.meshes.insert(scene.meshes.begin(),
                      std::make_shared<const TriangleMesh>(makeBin(h + t, h, t, height)));
  scene.convexPieces.insert(scene.convexPieces.begin(), binPieces);
  scene.bodies.insert(scene.bodies.begin(), {0, 0.0f, at(0, 0, 0)});
}

// Bodies per row of a pile's grid: 4 up to 50 bodies, more above so that the pile's height stays that of 50.
int pileRow(int bodies) {
  return std::max(4, int(std::ceil(4.0 * std::sqrt(double(bodies) / 50.0))));
}

// `bodies` dynamic bodies cycling through meshes 1, 2, ... of `scene` (mesh 0 is the bin), in random
// orientations from `seed`, on a `perRow` × `perRow` grid of `cell`-metre cells, layer after layer `cell`
// apart, the first `firstLayer` above y = 0. Returns the number of layers.
int dropOnGrid(SceneDescription& scene, int bodies, int perRow, float cell, float firstLayer, unsigned seed) {
  const std::size_t kinds = scene.meshes.size() - 1;
  std::vector<float> masses;
  for (std::size_t kind = 0; kind < kinds; ++kind) masses.push_back(massOf(*scene.meshes[kind + 1]));
  std::mt19937 random(seed);
  for (int i = 0; i < bodies; ++i) {
    const int layer = i / (perRow * perRow), row = (i / perRow) % perRow, column = i % perRow;
    const float x = (float(column) - 0.5f * float(perRow - 1)) * cell,
                z = (float(row) - 0.5f * float(perRow - 1)) * cell;
    const float y = firstLayer + float(layer) * cell;
    const std::size_t kind = std::size_t(i) % kinds;
    scene.bodies.push_back({kind + 1, masses[kind], at(x, y, z, randomRotation(random))});
  }
  return bodies / (perRow * perRow);
}

// Completes a pile whose dynamic meshes and convex pieces are in `scene`: the bin and the grid for `bodies`
// bodies in cells of `cell` metres (1.5: the pile's, whose bin has scale 1), the bodies, the ground and the
// extent.
void fillPile(SceneDescription& scene, int bodies, unsigned seed, float cell) {
  if (bodies < 0) throw std::invalid_argument("scene '" + scene.name + "': negative body count");
  const int perRow = pileRow(bodies);
  const float inside = cell * float(perRow);
  addBin(scene, inside, cell / 1.5f);
  const int layers = dropOnGrid(scene, bodies, perRow, cell, cell * (2.0f / 3.0f), seed);
  scene.groundTop = 0;
  scene.extent = 10.0f + inside + float(layers) * cell;
}

}  // namespace

SceneDescription makeStackScene(int boxes, float gap, unsigned seed) {
  if (boxes < 1) throw std::invalid_argument("stack scene: at least one box");
  SceneDescription scene;
  scene.name = "stack";
  scene.meshes.push_back(std::make_shared<const TriangleMesh>(makeBox(10.0f, 0.5f, 10.0f)));
  scene.meshes.push_back(std::make_shared<const TriangleMesh>(makeBox(0.5f, 0.5f, 0.5f)));
  scene.convexPieces = {{box(btVector3(10.0f, 0.5f, 10.0f))}, {box(btVector3(0.5f, 0.5f, 0.5f))}};
  scene.bodies.push_back({0, 0.0f, at(0, -0.5f, 0)});
  const float mass = massOf(*scene.meshes[1]);
  std::mt19937 random(seed);
  // Raw mt19937 words, as randomRotation, so the stack is the same with every standard library.
  auto within = [&random](float half) { return half * float(2.0 * double(random()) / 4294967295.0 - 1.0); };
  for (int i = 0; i < boxes; ++i) {
    const float y = 0.5f + gap + float(i) * (1.0f + gap);
    if (seed == 0) {
      scene.bodies.push_back({1, mass, at(0, y, 0)});
      continue;
    }
    const float x = within(kStackShift), z = within(kStackShift);
    scene.bodies.push_back({1, mass, at(x, y, z, btQuaternion(btVector3(0, 1, 0), within(kStackTurn)))});
  }
  scene.groundTop = 0;
  scene.extent = std::max(10.0f, float(boxes) * (1.0f + gap));
  scene.trackedBody = boxes - 1;
  return scene;
}

SceneDescription makePileScene(int bodies, unsigned seed) {
  SceneDescription scene;
  scene.name = "pile";
  scene.meshes.push_back(std::make_shared<const TriangleMesh>(makeBox(0.35f, 0.35f, 0.35f)));
  scene.meshes.push_back(std::make_shared<const TriangleMesh>(makeIcosphere(0.4f, 2)));
  scene.meshes.push_back(std::make_shared<const TriangleMesh>(makeTorus(0.3f, 0.12f, 24, 12)));
  // The L is not symmetric about its origin: its principal frame puts the centre of mass at the body's
  // origin.
  std::array<double, 9> lRotation{};
  std::array<double, 3> lTranslation{};
  scene.meshes.push_back(std::make_shared<const TriangleMesh>(
      makeLShape(0.8f, 0.3f).inPrincipalFrame(kSceneDensity, &lRotation, &lTranslation)));
  scene.convexPieces = {{box(btVector3(0.35f, 0.35f, 0.35f))},
                        {{ConvexPiece::Kind::Sphere, btVector3(0.4f, 0, 0), btTransform::getIdentity(), {}}},
                        torusPieces(0.3f, 0.12f, 12),
                        lShapePieces(0.8f, 0.3f, lRotation, lTranslation)};
  fillPile(scene, bodies, seed, 1.5f);  // cells above the largest body's bounding diameter (the L's, 1.4 m)
  return scene;
}

SceneDescription makeThinPileScene(int bodies, unsigned seed) {
  SceneDescription scene;
  scene.name = "thin";
  const btVector3 rod(0.4f, 0.04f, 0.04f), plate(0.3f, 0.025f, 0.3f);
  scene.meshes.push_back(std::make_shared<const TriangleMesh>(makeBox(rod.x(), rod.y(), rod.z())));
  scene.meshes.push_back(std::make_shared<const TriangleMesh>(makeBox(plate.x(), plate.y(), plate.z())));
  scene.meshes.push_back(std::make_shared<const TriangleMesh>(makeTorus(0.3f, 0.05f, 32, 8)));
  scene.meshes.push_back(std::make_shared<const TriangleMesh>(makeCross(0.4f, 0.08f, 0.08f)));
  // The cross's two bars overlap at its centre: a compound may, and the mesh is their union.
  scene.convexPieces = {{box(rod)},
                        {box(plate)},
                        torusPieces(0.3f, 0.05f, 16),
                        {box(btVector3(0.4f, 0.04f, 0.04f)), box(btVector3(0.04f, 0.4f, 0.04f))}};
  fillPile(scene, bodies, seed, 1.5f);  // the pile's cells, above the plate's bounding diameter (0.85 m)
  scene.fallTolerance = 0.25f;          // half the floor: a centre deeper than that has gone through
  return scene;
}

SceneDescription makeRealMeshPileScene(const PileMeshes& meshes, int bodies, unsigned seed) {
  if (meshes.meshes.empty() || meshes.meshes.size() != meshes.convexPieces.size())
    throw std::invalid_argument("mesh pile scene: needs meshes, each with its convex pieces");
  SceneDescription scene;
  scene.name = "meshes";
  float radius = 0;
  for (const auto& mesh : meshes.meshes) radius = std::max(radius, boundingRadius(*mesh));
  scene.meshes = meshes.meshes;
  scene.convexPieces = meshes.convexPieces;
  fillPile(scene, bodies, seed, 2.2f * radius);  // a little above the largest bounding diameter
  return scene;
}

SceneDescription makeToriAndCratesScene(int bodies, unsigned seed, int detail) {
  if (bodies < 0) throw std::invalid_argument("tori scene: negative body count");
  if (detail < 1) throw std::invalid_argument("tori scene: detail must be at least 1");
  SceneDescription scene;
  scene.name = detail == 1 ? "tori" : "tori-x" + std::to_string(detail);
  scene.meshes.push_back(std::make_shared<const TriangleMesh>(binMesh()));
  scene.meshes.push_back(
      std::make_shared<const TriangleMesh>(makeTorus(0.4f, 0.12f, 32 * detail, 16 * detail)));
  scene.meshes.push_back(std::make_shared<const TriangleMesh>(makeBox(0.3f, 0.3f, 0.3f, 4 * detail)));
  const float masses[2] = {massOf(*scene.meshes[1]), massOf(*scene.meshes[2])};
  scene.bodies.push_back({0, 0.0f, at(0, 0, 0)});
  std::mt19937 random(seed);
  constexpr int kPerRow = 4;
  constexpr float kCell = 1.5f;  // Above the torus's bounding diameter (1.04 m).
  for (int i = 0; i < bodies; ++i) {
    const int layer = i / (kPerRow * kPerRow), row = (i / kPerRow) % kPerRow, column = i % kPerRow;
    const float x = (float(column) - 1.5f) * kCell, z = (float(row) - 1.5f) * kCell;
    const float y = 1.0f + float(layer) * kCell;
    // A checkerboard of tori and crates, shifted by one each layer: tori land on crates and crates in tori.
    const std::size_t kind = std::size_t(row + column + layer) % 2;
    scene.bodies.push_back({kind + 1, masses[kind], at(x, y, z, randomRotation(random))});
  }
  scene.groundTop = 0;
  scene.extent = 10.0f + float(bodies / (kPerRow * kPerRow)) * kCell;
  return scene;
}

SceneDescription makeMeshDropScene(const TriangleMesh& mesh, int count, unsigned seed) {
  if (count < 1) throw std::invalid_argument("mesh scene: at least one copy");
  SceneDescription scene;
  scene.name = mesh.name();
  auto body = std::make_shared<const TriangleMesh>(mesh.inPrincipalFrame(kSceneDensity));
  const float radius = boundingRadius(*body);
  const float spacing = 2.4f * radius;
  const int perRow = int(std::ceil(std::sqrt(double(count))));
  const float halfWidth = 0.5f * float(perRow) * spacing + 2 * radius;
  scene.meshes.push_back(std::make_shared<const TriangleMesh>(makeBox(halfWidth, 0.5f * radius, halfWidth)));
  scene.meshes.push_back(body);
  scene.bodies.push_back({0, 0.0f, at(0, -0.5f * radius, 0)});
  const float mass = massOf(*body);
  std::mt19937 random(seed);
  for (int i = 0; i < count; ++i) {
    const float x = (float(i % perRow) - 0.5f * float(perRow - 1)) * spacing;
    const float z = (float(i / perRow) - 0.5f * float(perRow - 1)) * spacing;
    scene.bodies.push_back({1, mass, at(x, 2 * radius, z, randomRotation(random))});
  }
  scene.groundTop = 0;
  scene.extent = 2 * halfWidth;
  return scene;
}

}  // namespace gpucol::scenes
