#include "gpucol/opencl_status.h"

#include "opencl/host/opencl_started.h"

namespace gpucol {

bool openClStarted() { return opencl::openClContextsCreated().load() > 0; }

}  // namespace gpucol
