#include "bullet/warn_once.h"

#include <iostream>
#include <mutex>
#include <set>

namespace gpucol {

void warnOnce(const std::string& key, const std::string& message) {
  static std::mutex mutex;
  static std::set<std::string> warned;
  const std::lock_guard<std::mutex> lock(mutex);
  if (!warned.insert(key).second) return;
  std::cerr << "gpucol: " << message << "\n";
}

}  // namespace gpucol
