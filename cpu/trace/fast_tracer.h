// The fast CPU path beside the scalar single-source reference (common/kernels/traverse_bvh.h), with
// SIMD box and triangle tests (xsimd).  It gives the reference's closest hits bit for bit by an
// order-free walk of a 4- or 8-wide BVH (exact_wide_bvh.h), Line Space nodes as lanes of it: the
// closest hit depends neither on the visiting order nor, since a lookup's answer is a function of
// the ray and its node alone (common/kernels/ls_lookup.h), on which lookups run before which.
// Triangles are tested four at a time (triangle_blocks.h) with the kernel's arithmetic, so hits, t,
// u and v are identical; the Line Space counters count the lookups this walk makes, which depend
// on its order.  Any-hit queries take the reference kernels (the triangle they report is the first
// in the reference's order); occlusion queries, which only ask whether something is hit, take the
// order-free walk.
#pragma once

#include "common/structure/accel.h"
#include "common/structure/trace_context.h"

#include <cstddef>
#include <memory>
#include <string>

namespace ls {

struct Accel;


class FastTracer {
 public:
  virtual ~FastTracer() = default;
  // Traces rays [0, count) against the buffers of `context` (made by Accel::context() of the Accel
  // this tracer was made for); Line Space counters are added to context.ls_counters.
  virtual void trace(lsk::TraceContext& context, const lsk::Ray* rays, lsk::Hit* hits, size_t count,
                     bool any_hit) const = 0;
  // Occlusion queries (shadow rays): hits[i] misses exactly where the reference's any hit misses;
  // where something is hit it holds *a* hit in [tmin, tmax], not necessarily the one the reference's
  // order finds first, since the structures are walked order-free here.
  virtual void occluded(lsk::TraceContext& context, const lsk::Ray* rays, lsk::Hit* hits, size_t count) const = 0;
  // lsk::TraceContext::ls_find_candidate of the shafts [first, end) of an LS node on the fast path,
  // the same candidates bit for bit, into prims[0, end - first): each search segment is a
  // closest-hit query in the LS node's own subtree, which the order-free walk answers (the node is
  // an entry of the exact wide tree).  centres: ls_patch_centres(ls), the ends of search ray 0.
  virtual void find_candidates(lsk::TraceContext& context, const lsk::LsNode& ls, const lsk::vec3* centres, uint32_t first,
                               uint32_t end, uint32_t further_rays, uint32_t instance, uint32_t* prims) const = 0;
  virtual size_t bytes() const = 0;  // the wide nodes and their index
  virtual int exact_width() const = 0;  // the order-free walk's nodes: 4 or 8
  // A tracer for the same Accel after its top level was rebuilt or refitted (top_level_update.h):
  // the wide top tree is collapsed anew, the object wide trees and triangle blocks are shared, not
  // copied.  Flat structures have no top level: the tracer is returned as it is.
  virtual std::shared_ptr<const FastTracer> with_top_level(const Accel& accel) const = 0;
  // The address of the object part (object wide trees and triangle blocks): tests check it stays.
  virtual const void* object_part() const = 0;
};

// exact_width: the order-free walk's nodes, 4 or 8; other widths are an InputError.  The Accel's
// arrays must stay where they are.
std::shared_ptr<const FastTracer> make_fast_tracer(const Accel& accel, int exact_width);

// The SIMD instruction set the fast path was compiled for, e.g. "sse2 (4 floats)".
std::string fast_path_isa();

}  // namespace ls
