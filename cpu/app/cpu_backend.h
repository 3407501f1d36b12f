// The CPU back end: structures built and rays traced on all CPU threads (or --threads) by the fast
// path, images by the CPU path tracer, and bench with Embree 3 beside.  linespace-cpu and the
// validator's CPU studies use it through the Backend interface (common/render/backend.h).
#pragma once

#include "common/render/backend.h"

#include <memory>

namespace ls {

std::unique_ptr<Backend> make_cpu_backend();

}  // namespace ls
