#pragma once

#include <stdexcept>
#include <string>

namespace gpucol {

/// Thrown for bad mesh input: the message names the file (or "arrays"), the element index and the value.
class MeshError : public std::runtime_error {
 public:
  /// Builds the error from a complete, human-readable message.
  explicit MeshError(const std::string& message) : std::runtime_error(message) {}
};

}  // namespace gpucol
