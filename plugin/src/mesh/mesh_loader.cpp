#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <assimp/Importer.hpp>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <unordered_map>

#include "gpucol/mesh_error.h"
#include "gpucol/triangle_mesh.h"
#include "mesh/ply_precheck.h"

namespace gpucol {

namespace {

/// Post-processing, chosen so assimp never changes the file's topology behind the user's back:
/// Triangulate splits polygons (quads, n-gons) into triangles over the same vertices (thesis §2.3);
/// points and lines stay and are refused below. Not used on purpose: JoinIdenticalVertices (drops
/// unreferenced vertices and welds coincident ones: bunny-69451 would lose 1,113 vertices, the
/// teapot 403), FindDegenerates and FindInvalidData (remove triangles silently), PreTransformVertices
/// (the node transforms are applied below, in double), SortByPType (splits meshes for nothing).
constexpr unsigned kPostProcess = aiProcess_Triangulate | aiProcess_ValidateDataStructure;

/// Bit pattern of a position with -0 folded onto +0, so welding joins exactly equal coordinates only.
struct PositionKey {
  std::uint32_t bits[3];
  bool operator==(const PositionKey& o) const {
    return bits[0] == o.bits[0] && bits[1] == o.bits[1] && bits[2] == o.bits[2];
  }
};

struct PositionKeyHash {
  std::size_t operator()(const PositionKey& k) const {
    std::uint64_t h = 1469598103934665603ull;  // FNV-1a over the three words
    for (std::uint32_t w : k.bits) h = (h ^ w) * 1099511628211ull;
    return std::size_t(h);
  }
};

PositionKey keyOf(const float* p) {
  PositionKey key{};
  for (int k = 0; k < 3; ++k) {
    const float v = p[k] == 0.0f ? 0.0f : p[k];
    std::memcpy(&key.bits[k], &v, sizeof v);
  }
  return key;
}

std::vector<char> readWholeFile(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    throw MeshError(path + ": cannot read mesh file: it is a directory");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw MeshError(path + ": cannot open mesh file: " + std::strerror(errno));
  std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) throw MeshError(path + ": cannot read mesh file: " + std::strerror(errno));
  if (bytes.empty()) throw MeshError(path + ": the mesh file is empty");
  return bytes;
}

/// Appends one assimp mesh, mapped by the node's accumulated transform, to the output arrays.
void appendMesh(const aiMesh& mesh, unsigned meshIndex, const aiMatrix4x4& transform, const std::string& path,
                std::vector<float>& xyz, std::vector<std::uint32_t>& indices) {
  std::vector<std::uint32_t> faceIndices;
  faceIndices.reserve(3 * std::size_t(mesh.mNumFaces));
  std::vector<std::uint32_t> uses(mesh.mNumVertices, 0);
  for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
    const aiFace& face = mesh.mFaces[f];
    if (face.mNumIndices != 3) {
      std::ostringstream out;
      out << path << ": mesh " << meshIndex << " ('" << mesh.mName.C_Str() << "') face " << f << " has "
          << face.mNumIndices
          << (face.mNumIndices == 1   ? " index (a point)"
              : face.mNumIndices == 2 ? " indices (a line)"
                                      : " indices")
          << "; gpucol needs triangles (polygons are triangulated, points and lines are refused)";
      throw MeshError(out.str());
    }
    for (unsigned k = 0; k < 3; ++k) {
      const unsigned v = face.mIndices[k];
      if (v < mesh.mNumVertices) ++uses[v];  // out-of-range indices are reported by fromArrays
      faceIndices.push_back(v);
    }
  }

  if (xyz.size() / 3 + mesh.mNumVertices > std::size_t(UINT32_MAX)) {
    std::ostringstream out;
    out << path << ": the scene has more than " << UINT32_MAX << " vertices, beyond 32-bit triangle indices";
    throw MeshError(out.str());
  }
  // Positions in double through the node transform, stored as float like the rest of gpucol. A
  // non-finite coordinate is named before the transform would smear it over x, y and z (0 * NaN).
  const std::size_t base = xyz.size() / 3;
  std::vector<float> local(3 * std::size_t(mesh.mNumVertices));
  for (unsigned v = 0; v < mesh.mNumVertices; ++v) {
    const aiVector3D& p = mesh.mVertices[v];
    for (int k = 0; k < 3; ++k) {
      if (!std::isfinite(p[k])) {
        std::ostringstream out;
        out << path << ": vertex " << base + v << " has a non-finite coordinate "
            << "xyz"[k] << " = " << p[k];
        throw MeshError(out.str());
      }
    }
    for (int r = 0; r < 3; ++r) {
      local[3 * std::size_t(v) + r] = float(double(transform[r][0]) * p.x + double(transform[r][1]) * p.y +
                                            double(transform[r][2]) * p.z + double(transform[r][3]));
    }
  }

  // OBJ and STL importers give every face corner its own vertex, which would leave a closed solid
  // looking like a triangle soup with only boundary edges. When every vertex is used exactly once,
  // the file carried no shared vertices for assimp to keep, so exactly equal positions are welded
  // (first occurrence keeps its order). PLY and OFF keep the file's own vertex list and are untouched.
  bool cornerSplit = mesh.mNumVertices == 3 * mesh.mNumFaces;
  for (std::uint32_t u : uses) cornerSplit = cornerSplit && u == 1;
  std::vector<std::uint32_t> remap(mesh.mNumVertices);
  if (cornerSplit) {
    std::unordered_map<PositionKey, std::uint32_t, PositionKeyHash> welded;
    welded.reserve(mesh.mNumVertices);
    std::size_t next = base;
    for (unsigned v = 0; v < mesh.mNumVertices; ++v) {
      const auto [it, inserted] = welded.emplace(keyOf(&local[3 * std::size_t(v)]), std::uint32_t(next));
      if (inserted) {
        xyz.insert(xyz.end(), &local[3 * std::size_t(v)], &local[3 * std::size_t(v)] + 3);
        ++next;
      }
      remap[v] = it->second;
    }
  } else {
    xyz.insert(xyz.end(), local.begin(), local.end());
    for (unsigned v = 0; v < mesh.mNumVertices; ++v) remap[v] = std::uint32_t(base + v);
  }

  // A mirroring node transform turns outward counter-clockwise triangles inward; swapping two
  // corners keeps the winding outward, as it was in the file's own frame.
  const bool mirrored = transform.Determinant() < 0;
  for (std::size_t t = 0; t < faceIndices.size(); t += 3) {
    for (int k = 0; k < 3; ++k) {
      const int corner = mirrored && k > 0 ? 3 - k : k;
      const std::uint32_t v = faceIndices[t + std::size_t(corner)];
      // Keep an out-of-range index out of range so fromArrays names it.
      indices.push_back(v < mesh.mNumVertices ? remap[v] : std::uint32_t(base + v));
    }
  }
}

void appendNode(const aiScene& scene, const aiNode& node, const aiMatrix4x4& parent, const std::string& path,
                std::vector<float>& xyz, std::vector<std::uint32_t>& indices) {
  const aiMatrix4x4 transform = parent * node.mTransformation;
  for (unsigned i = 0; i < node.mNumMeshes; ++i) {
    const unsigned m = node.mMeshes[i];
    appendMesh(*scene.mMeshes[m], m, transform, path, xyz, indices);
  }
  for (unsigned c = 0; c < node.mNumChildren; ++c)
    appendNode(scene, *node.mChildren[c], transform, path, xyz, indices);
}

}  // namespace

TriangleMesh loadMesh(const std::string& path) {
  const std::vector<char> bytes = readWholeFile(path);
  Assimp::Importer importer;
  const aiScene* scene = nullptr;
  if (reachesAssimpPlyReader(bytes.data(), bytes.size(), path)) {
    // assimp's PLY reader is not safe on malformed input (see ply_precheck.h): check first. Every file it
    // would read, not only those with the exact magic line, so none reaches it unchecked.
    const std::string checked = checkPlyStructure(bytes.data(), bytes.size(), path);
    scene = importer.ReadFileFromMemory(checked.data(), checked.size(), kPostProcess, "ply");
  } else {
    // Other formats may reference side files (OBJ's .mtl), so assimp opens the path itself.
    scene = importer.ReadFile(path, kPostProcess);
  }
  if (scene == nullptr)
    throw MeshError(path + ": assimp cannot read the mesh file: " + importer.GetErrorString());
  if ((scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE) != 0 || scene->mRootNode == nullptr ||
      scene->mNumMeshes == 0)
    throw MeshError(path + ": the file holds no triangle mesh");

  std::vector<float> xyz;
  std::vector<std::uint32_t> indices;
  appendNode(*scene, *scene->mRootNode, aiMatrix4x4(), path, xyz, indices);
  return TriangleMesh::fromArrays(std::move(xyz), std::move(indices), path);
}

}  // namespace gpucol
