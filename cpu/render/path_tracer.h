// The CPU path tracer: Lambertian surfaces, emissive triangles as area lights with next-event
// estimation and multiple importance sampling (power heuristic), a background radiance for rays that
// leave the scene, and the acceleration structure chosen per bounce by a schedule.
//
// Bounces (docs/design.md §3): bounce 0 is the camera ray and the shadow ray from its hit; bounce k >= 1 is
// the k-th indirect segment and the shadow ray from its hit.  The image of bounce k holds what the
// rays of bounce k found: emission hit by its segment (MIS-weighted; weight 1 at bounce 0) plus the
// light its shadow ray let through.  The total image is their sum.  At the last bounce the light
// sample takes the full weight, since no further segment could find that light by BSDF sampling:
// the render is then an unbiased estimate of light paths with at most bounces + 2 segments.
//
// It runs as a wavefront, one sample per pixel per pass: all rays of one bounce are traced as one
// batch on all threads, so the time spent tracing each bounce is measured apart from shading.
// Random numbers are keyed by (seed, pixel, sample, bounce, dimension): a render whose schedule is
// exact before bounce k follows exactly the same paths as the all-exact render up to bounce k.
#pragma once

#include "common/model/scene.h"
#include "common/render/render_types.h"
#include "common/structure/accel.h"

#include <map>
#include <string>

namespace ls {

// structures: built structures keyed by canonical name; every schedule entry (and the throughput
// switch's structure, when it is on) must be present.
// tracer: where the batches are traced (empty: trace_rays, and trace_occlusion for shadow rays, on
// all CPU threads).
RenderResult render(const Scene& scene, const std::map<std::string, Accel>& structures, const RenderOptions& options,
                    const Progress& progress = {}, const BatchTracer& tracer = {});

}  // namespace ls
