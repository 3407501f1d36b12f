// Ray sets for `rays`, `bench` and the tests, all deterministic in (scene, kind, count, seed):
//   primary  camera rays through uniformly random image positions
//   diffuse  the first diffuse bounce: a primary ray's exact hit, offset, then a cosine-weighted
//            direction about the geometric normal (the rays the paper's MRays/s are about)
//   random   origins uniform in the world bounds, directions uniform on the sphere
//   shadow   segments (tmax = 1) between the origins of two diffuse rays: visibility between surface
//            points, for any-hit queries
#pragma once

#include "common/model/scene.h"
#include "common/structure/accel.h"

#include <string>
#include <vector>

namespace ls {

enum class RayKind { Primary, Diffuse, Random, Shadow };

RayKind parse_ray_kind(const std::string& text);  // throws InputError

// `exact` must be an exact structure of `scene` (used by diffuse rays to find primary hits).
// Throws InputError when diffuse rays are asked of a scene the camera sees nothing of.
std::vector<lsk::Ray> generate_rays(const Scene& scene, const Accel& exact, RayKind kind, size_t count, uint32_t seed);

}  // namespace ls
