#pragma once
// Real meshes made ready for a pile (makeRealMeshPileScene): checked to be solids, scaled, moved to their
// principal frames and decomposed into convex hulls for the reference, once, before any pile is built.
#include <gpucol/triangle_mesh.h>

#include <memory>
#include <string>
#include <vector>

#include "scenes/convex_decomposition.h"
#include "scenes/scene_description.h"

namespace gpucol::scenes {

/// Meshes in their principal frames, each with the convex pieces of its solid.
struct PileMeshes {
  std::vector<std::shared_ptr<const TriangleMesh>> meshes;  ///< In their principal frames.
  std::vector<std::vector<ConvexPiece>> convexPieces;       ///< Per mesh, its hulls (decomposeConvex).
};

/// Loads each file, scales it so that the largest side of its bounding box is `size` metres, moves it to its
/// principal frame and decomposes it. Throws MeshError (with the mesh's report) for a mesh that is not a
/// closed solid: an open or non-manifold mesh has no inside to pile.
PileMeshes loadPileMeshes(const std::vector<std::string>& paths, float size,
                          const DecompositionOptions& decomposition = {});

}  // namespace gpucol::scenes
