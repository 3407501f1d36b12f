// A 64-bit fingerprint of what a loaded scene renders: geometry, normals, materials, instances, camera
// and background (not names).  Partials of a sharded render merge only when they were rendered from the
// same scene, wherever its file lay on each machine (render_partial.h).
#pragma once

#include "common/model/scene.h"

#include <cstdint>
#include <string>

namespace ls {

uint64_t scene_fingerprint(const Scene& scene);
std::string fingerprint_text(uint64_t fingerprint);  // 16 hex digits

}  // namespace ls
