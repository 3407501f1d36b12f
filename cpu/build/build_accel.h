// Builds any of the four structures of docs/design.md §3: the BVHs (cpu/build/bvh_builder.h), the
// Line Space's layout (line_space_builder.h), the fast path's trees (cpu/trace/fast_tracer.h), then
// the candidate search on them.  A 2l-ls:auto structure needs its plan first (build_structures.h).
#pragma once

#include "common/model/scene.h"
#include "common/model/structure_name.h"
#include "common/structure/accel.h"

namespace ls {

// Builds any of the four structures of docs/design.md §3.  A 2l-ls:auto structure must come with its
// plan in options.ls.objects (build_planned_accel, build_structures.h, makes both); InputError otherwise.
Accel build_accel(const Scene& scene, const StructureSpec& spec, const AccelOptions& options = {});

// The two halves of build_accel, for the 2l-ls:auto planner, which plans on the BVHs in between:
// build_bvhs refuses what the memory budget cannot hold and builds the BVHs (flat, or the objects'
// and the top level); finish_accel lays out the Line Space, makes the fast path and searches the
// candidates, adding its time to accel.build_seconds.
Accel build_bvhs(const Scene& scene, const StructureSpec& spec, const AccelOptions& options);
void finish_accel(const Scene& scene, const AccelOptions& options, Accel& accel);

}  // namespace ls
