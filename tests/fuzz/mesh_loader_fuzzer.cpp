// libFuzzer target: gpucol::loadMesh on arbitrary bytes. The loader reads files only, so the bytes are written to
// a temporary file whose extension the first byte chooses (PLY, OBJ, STL, OFF: every format the loader reads;
// scripts/fuzz.sh seeds each, ASCII and binary, and passes mesh_loader_fuzzer.dict). Bad input must end in gpucol::MeshError (the loader's contract); anything else (another exception, a
// crash, a sanitizer report) is a finding. A mesh that loads must be valid: indices in range, finite coordinates.
#include <gpucol/mesh_error.h>
#include <gpucol/triangle_mesh.h>
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

namespace {

const char* const kExtensions[] = {".ply", ".obj", ".stl", ".off"};

// One temporary file per process, rewritten for every input.
const std::string& scratchPath(int format) {
  static std::string paths[4];
  if (paths[format].empty()) {
    paths[format] = "/tmp/gpucol_fuzz_" + std::to_string(getpid()) + "_" + std::to_string(format) + kExtensions[format];
  }
  return paths[format];
}

void check(bool condition, const char* what) {
  if (!condition) {
    std::fprintf(stderr, "mesh_loader_fuzzer: %s\n", what);
    std::abort();
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  const int format = data[0] % 4;
  const std::string& path = scratchPath(format);
  std::FILE* file = std::fopen(path.c_str(), "wb");
  if (!file) return 0;
  std::fwrite(data + 1, 1, size - 1, file);
  std::fclose(file);
  try {
    const gpucol::TriangleMesh mesh = gpucol::loadMesh(path);
    const std::size_t vertices = mesh.vertexCount();
    for (std::uint32_t index : mesh.indices()) check(index < vertices, "an index out of range in a loaded mesh");
    for (float x : mesh.positions()) check(std::isfinite(x), "a non-finite coordinate in a loaded mesh");
    try {
      (void)mesh.massProperties();
    } catch (const gpucol::MeshError&) {
      // Open, non-manifold or inward meshes have none; saying so is the contract.
    }
  } catch (const gpucol::MeshError&) {
    // Refused with a message: the expected answer to bad bytes.
  }
  std::remove(path.c_str());
  return 0;
}
