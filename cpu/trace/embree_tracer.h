// Embree 3 as the correctness and performance peer: the same world-space triangles, one Embree
// geometry per instance (geomID = instance id, primID = triangle id), robust and high-quality build.
#pragma once

#include "common/kernels/layouts.h"
#include "common/model/scene.h"

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

namespace ls {

// The instruction sets Embree's kernels can be limited to (its `isa=` device setting), "best" first:
// Embree's own choice, the widest of its compiled targets this CPU runs.  Our fast path is compiled
// for one instruction set (LINESPACE_ISA: SSE2 by default), Embree picks at run time, so a ratio
// between the two depends on which one Embree ran; `bench --embree-isa` sets it.
const std::vector<std::string>& embree_isa_names();

// What Embree runs for `isa` ("best" or one of the above) on this CPU: the requested set, or the
// best this CPU has of Embree's targets where that is below it.
std::string embree_effective_isa(const std::string& isa);

// What EmbreeTracer throws when Embree's memory would pass its max_bytes.
struct EmbreeOverBudget : InputError {
  using InputError::InputError;
};

// Embree 3 takes a ray only with 0 <= tmin <= tmax and every origin and direction component within
// +-1.844e18 (FLT_LARGE, RayK::valid()); its kernels abort on others.  Empty when every ray is in
// that domain, else the first one outside it, described, for an InputError.
std::string embree_ray_domain_error(const lsk::Ray* rays, size_t count);

// The share of rays whose Embree hit is not ours: a hit against a miss, or (closest hit) a t more
// than 1e-3 of its magnitude apart.  Embree drops triangles past +-1.844e18 and misses at tiny
// scales, where its timing would be of other work.
double embree_disagreement(const lsk::Hit* embree, const lsk::Hit* ours, size_t count, bool any_hit);

class EmbreeTracer {
 public:
  // isa: one of embree_isa_names(); an unknown name is an InputError.  max_bytes: 0 for no limit,
  // else Embree's own memory may not pass it: the build is cancelled (its memory monitor) and the
  // constructor throws EmbreeOverBudget, which names the limit.
  explicit EmbreeTracer(const Scene& scene, const std::string& isa = "best", size_t max_bytes = 0);
  ~EmbreeTracer();
  EmbreeTracer(const EmbreeTracer&) = delete;
  EmbreeTracer& operator=(const EmbreeTracer&) = delete;

  // Closest hit (rtcIntersect1) or occlusion (rtcOccluded1) for each ray, on all threads.  Hits use
  // the hit-file convention (t = +inf and ids 0xFFFFFFFF on a miss; u, v weights of vertices 1, 2);
  // an occlusion query reports t = ray.tmin and the invalid ids when occluded (Embree gives no ids).
  void trace(const lsk::Ray* rays, lsk::Hit* hits, size_t count, bool any_hit) const;

  double build_seconds() const;
  const std::string& isa() const;  // embree_effective_isa of the constructor's isa
  size_t bytes() const;  // Embree's own memory, as reported by its memory monitor

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace ls
