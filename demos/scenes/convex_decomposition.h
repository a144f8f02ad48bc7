#pragma once
// A closed mesh as convex hulls, for the convex reference of a real mesh: Khaled Mamou's hierarchical
// approximate convex decomposition (HACD), as Bullet's extras ship it (libbullet-extras-dev's libHACD).
#include <gpucol/triangle_mesh.h>

#include <cstddef>
#include <vector>

#include "scenes/scene_description.h"

namespace gpucol::scenes {

/// How finely HACD splits a mesh.
struct DecompositionOptions {
  /// Fewest hulls HACD stops at, when no merge would exceed `concavity`.
  std::size_t minHulls = 2;
  /// Largest concavity a merged cluster may have, in HACD's normalised units (the mesh scaled to HACD's
  /// default size of 1000 across): lower values give more, tighter hulls.
  double concavity = 100;
  /// Most vertices per hull.
  std::size_t maxHullVertices = 64;
  /// HACD's extra sample points (on faces, and inside concave clusters): a finer concavity measure at several
  /// times the run time.
  bool extraPoints = false;
};

/// The hulls of `mesh`'s decomposition as ConvexPiece::Kind::Hull pieces in the mesh's frame. Throws
/// std::runtime_error when HACD fails or gives no hull.
std::vector<ConvexPiece> decomposeConvex(const TriangleMesh& mesh, const DecompositionOptions& options = {});

}  // namespace gpucol::scenes
