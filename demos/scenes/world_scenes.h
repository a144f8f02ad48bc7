#pragma once

#include <gpucol/triangle_mesh.h>

#include "scenes/pile_meshes.h"
#include "scenes/scene_description.h"

namespace gpucol::scenes {

/// Density of every dynamic body of the built-in scenes (kg/m^3, water), so masses follow volumes.
inline constexpr double kSceneDensity = 1000.0;

/// Largest sideways shift of a box of a seeded stack from the stack's axis (metres).
inline constexpr float kStackShift = 0.05f;
/// Largest turn of a box of a seeded stack about the vertical (radians, about 11°).
inline constexpr float kStackTurn = 0.2f;

/// `boxes` unit cubes (makeBox, 12 triangles each) stacked on a static 20 m × 1 m × 20 m box whose top face
/// is at y = 0; box i starts with its bottom face `gap` metres above the top of box i - 1 (0: exactly
/// resting). Seed 0 stacks them square on one axis; another seed shifts each box sideways by up to
/// kStackShift and turns it about the vertical by up to kStackTurn. The top box is the tracked body.
SceneDescription makeStackScene(int boxes = 10, float gap = 0.0f, unsigned seed = 0);

/// `bodies` procedural meshes, cycling box, icosphere, torus, L-shape, about 0.8 m across, in random
/// orientations (from `seed`) on a 4 × 4 grid of 1.5 m cells, layer after layer 1.5 m apart, above a static
/// bin: one mesh made of a 7 m × 0.5 m × 7 m floor (top face at y = 0) and four 0.5 m thick, 2.5 m high walls
/// around a 6 m × 6 m inside. Above 50 bodies the grid and the bin widen by sqrt(bodies / 50). Each mesh
/// comes with its convex pieces (boxes, a sphere, capsules around the torus, the L's two boxes).
SceneDescription makePileScene(int bodies = 50, unsigned seed = 1);

/// makePileScene's layout and bin with thin bodies: rods (0.8 m × 8 cm × 8 cm boxes), plates (0.6 m × 5 cm
/// × 0.6 m boxes), tori (ring 0.3 m, tube 5 cm, 32 × 8) and crosses (makeCross: arms 0.4 m, 8 cm wide and
/// thick), cycling in that order. Convex pieces: the boxes, 16 capsules around each torus, the cross's two
/// bars.
SceneDescription makeThinPileScene(int bodies = 50, unsigned seed = 1);

/// makePileScene's layout with `meshes` (cycling in their order), the grid's cells and the bin scaled to the
/// meshes' size: cells 2.2 largest bounding radii wide, the bin's walls and height scaled with them.
SceneDescription makeRealMeshPileScene(const PileMeshes& meshes, int bodies = 50, unsigned seed = 1);

/// `bodies` tori (ring 0.4 m, tube 0.12 m, 1024 × detail² triangles) and crates (0.6 m boxes, 192 × detail²
/// triangles) in a checkerboard, in random orientations (fixed seed), 4 × 4 to a layer 1.5 m apart, above the
/// pile scene's bin: the GImpact pile that GImpact and gpucol::CollisionDispatcher step side by side. Named
/// "tori", or "tori-x<detail>" above detail 1.
SceneDescription makeToriAndCratesScene(int bodies = 32, unsigned seed = 1, int detail = 1);

/// `count` copies of `mesh`, moved to its principal frame (throws MeshError for a mesh without mass
/// properties: open, non-manifold, inward winding), in random orientations (fixed seed) on a square grid
/// spaced 1.2 bounding diameters apart, their lowest points half a diameter above a static ground box whose
/// size follows the grid's.
SceneDescription makeMeshDropScene(const TriangleMesh& mesh, int count, unsigned seed = 1);

}  // namespace gpucol::scenes
