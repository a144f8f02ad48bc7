#pragma once

#include <string>

namespace gpucol {

/// Prints "gpucol: <message>" to stderr the first time `key` is warned about in this process, and nothing after:
/// a problem that repeats every step (a NaN transform, an open mesh's inertia) is said once, not 60 times a second.
void warnOnce(const std::string& key, const std::string& message);

}  // namespace gpucol
