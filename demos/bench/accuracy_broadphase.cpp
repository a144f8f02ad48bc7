// The broad phase's studies of `gpucol-bench accuracy` (mapping-function square root, grid cell size).
#include <iostream>

#include "accuracy_row.h"

namespace gpucol::bench {

void runBroadphaseAccuracyStudies(const AccuracyContext&, std::vector<AccuracyRow>&) {
  std::cout << "broadphase studies: not written yet\n";
}

}  // namespace gpucol::bench
