#pragma once

#include <string>

namespace gpucol::test {

/// Folder of the real test meshes: $GPUCOL_MESH_DIR, else ../shared/data/meshes beside the repository.
std::string meshDirectory();

/// Full path of a mesh file in meshDirectory(), or "" when the file is absent (tests then skip).
std::string meshPath(const std::string& fileName);

}  // namespace gpucol::test

/// Skips the current test with a clear message when a real mesh file is not available.
#define GPUCOL_REQUIRE_MESH(path_var, file_name)                                                    \
  const std::string path_var = ::gpucol::test::meshPath(file_name);                                \
  if (path_var.empty()) GTEST_SKIP() << "mesh " << (file_name) << " not found in "                 \
                                     << ::gpucol::test::meshDirectory() << " (set GPUCOL_MESH_DIR)"
