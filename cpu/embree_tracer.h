// Embree 3 as the correctness and performance peer: the same world-space triangles, one Embree
// geometry per instance (geomID = instance id, primID = triangle id), robust and high-quality build.
#pragma once

#include "kernels/layouts.h"
#include "scene.h"

#include <cstddef>
#include <memory>

namespace ls {

class EmbreeTracer {
 public:
  explicit EmbreeTracer(const Scene& scene);
  ~EmbreeTracer();
  EmbreeTracer(const EmbreeTracer&) = delete;
  EmbreeTracer& operator=(const EmbreeTracer&) = delete;

  // Closest hit (rtcIntersect1) or occlusion (rtcOccluded1) for each ray, on all threads.  Hits use
  // the hit-file convention (t = +inf and ids 0xFFFFFFFF on a miss; u, v weights of vertices 1, 2);
  // an occlusion query reports t = ray.tmin and the invalid ids when occluded (Embree gives no ids).
  void trace(const lsk::Ray* rays, lsk::Hit* hits, size_t count, bool any_hit) const;

  double build_seconds() const;
  size_t bytes() const;  // Embree's own memory, as reported by its memory monitor

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace ls
