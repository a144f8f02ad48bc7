#include "support/test_paths.h"

#include <cstdlib>
#include <filesystem>

namespace gpucol::test {

std::string meshDirectory() {
  if (const char* dir = std::getenv("GPUCOL_MESH_DIR"); dir != nullptr && *dir != '\0') return dir;
  return GPUCOL_TEST_MESH_DIR;
}

std::string meshPath(const std::string& fileName) {
  const std::filesystem::path path = std::filesystem::path(meshDirectory()) / fileName;
  return std::filesystem::exists(path) ? path.string() : std::string();
}

}  // namespace gpucol::test
