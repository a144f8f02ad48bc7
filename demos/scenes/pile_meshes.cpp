#include "scenes/pile_meshes.h"

#include <gpucol/mesh_error.h>
#include <gpucol/mesh_report.h>

#include <algorithm>
#include <array>

#include "scenes/world_scenes.h"

namespace gpucol::scenes {
namespace {

// The mesh scaled about its bounding box's centre so that the box's largest side is `size`.
TriangleMesh scaledTo(const TriangleMesh& mesh, float size) {
  const std::vector<float>& xyz = mesh.positions();
  std::array<float, 3> lo{xyz[0], xyz[1], xyz[2]}, hi = lo;
  for (std::size_t i = 0; i < xyz.size(); ++i) {
    lo[i % 3] = std::min(lo[i % 3], xyz[i]);
    hi[i % 3] = std::max(hi[i % 3], xyz[i]);
  }
  const float side = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]});
  const float scale = size / side;
  std::vector<float> scaled(xyz.size());
  for (std::size_t i = 0; i < xyz.size(); ++i) scaled[i] = (xyz[i] - 0.5f * (lo[i % 3] + hi[i % 3])) * scale;
  return TriangleMesh::fromArrays(std::move(scaled), mesh.indices(), mesh.name());
}

}  // namespace

PileMeshes loadPileMeshes(const std::vector<std::string>& paths, float size,
                          const DecompositionOptions& decomposition) {
  PileMeshes out;
  for (const std::string& path : paths) {
    const TriangleMesh loaded = loadMesh(path);
    if (!loaded.report().closed || loaded.report().nonManifoldEdges > 0)
      throw MeshError("mesh pile: '" + path + "' is not a closed solid: " + loaded.report().summary());
    auto mesh = std::make_shared<const TriangleMesh>(scaledTo(loaded, size).inPrincipalFrame(kSceneDensity));
    out.convexPieces.push_back(decomposeConvex(*mesh, decomposition));
    out.meshes.push_back(std::move(mesh));
  }
  return out;
}

}  // namespace gpucol::scenes
