// How a two-level structure's top level is brought to a posed scene (cpu/build/top_level_update.h
// does it), and what that took: named here for the back ends' shared interface.
#pragma once

#include "common/model/scene.h"

#include <cstddef>
#include <string>

namespace ls {

// Rebuild: a fresh SAH build over the new boxes, exactly what build_accel() would make on the posed
// scene (same nodes, same records, bit for bit).  Refit: the old tree and instance order with every
// box recomputed bottom-up; cheaper, but its boxes loosen as instances drift from where the tree was
// built.  Which is the default was measured (docs/performance.md, "Rigid animation").
enum class TopLevelMode { Rebuild, Refit };

// "rebuild" or "refit"; throws InputError.
inline TopLevelMode parse_top_level_mode(const std::string& text) {
  if (text == "rebuild") return TopLevelMode::Rebuild;
  if (text == "refit") return TopLevelMode::Refit;
  throw InputError("top-level update '" + text + "' is not rebuild or refit");
}

inline const char* top_level_mode_name(TopLevelMode mode) { return mode == TopLevelMode::Refit ? "refit" : "rebuild"; }

struct TopLevelUpdate {
  double seconds = 0.0;       // the whole update: boxes, BVH or refit, records, wide top tree
  double wide_seconds = 0.0;  // of which the fast path's wide top tree
  size_t top_nodes = 0;
};

}  // namespace ls
