// The top level of a two-level structure (2L-BVH, 2L-LS): a BVH over the instances' world boxes (each
// object's root box carried into the world by the instance's transform) and one InstanceRecord per
// instance (world-to-object rows), in top-level order.  build_accel() builds it once with the object
// BVHs; update_top_level() brings it to a posed scene (rigid animation) and touches nothing
// else: object BVH nodes, triangles, Line Space nodes, candidates and normals keep their bytes and
// their addresses, and the fast path keeps its object wide trees and triangle blocks (only its wide
// top tree is collapsed again).
#pragma once

#include "common/structure/accel.h"
#include "common/structure/top_level.h"

#include <string>

namespace ls {

// Fills accel.top_nodes and accel.instances from the scene's instance transforms; the object BVHs
// (accel.nodes, accel.object_roots) must be in place.
void build_top_level(const Scene& scene, const BvhBuildOptions& options, Accel& accel);


// Brings the top level of a two-level `accel` (built by build_accel on this scene's meshes and
// instances) to the instance transforms of `posed`, and bumps accel.top_level_version.  Throws
// InputError when accel is flat or the posed scene's instances are not the ones it was built for.
TopLevelUpdate update_top_level(const Scene& posed, Accel& accel, TopLevelMode mode = TopLevelMode::Rebuild);

}  // namespace ls
