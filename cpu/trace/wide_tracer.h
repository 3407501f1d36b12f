// The fast path's tracer (fast_tracer.h) as a template over the tree's width and the structure's
// kind, included by the two translation units that instantiate it: exact_tracer.cpp (with
// make_fast_tracer) and line_space_tracer.cpp.  Internal to cpu/trace.
#pragma once

#include "common/structure/accel.h"
#include "cpu/trace/exact_wide_bvh.h"
#include "cpu/trace/fast_tracer.h"
#include "cpu/trace/reference_trace.h"
#include "cpu/trace/simd.h"
#include "cpu/trace/triangle_blocks.h"

#include <bit>
#include <cmath>
#include <cstddef>
#include <memory>
#include <optional>
#include <type_traits>

namespace ls {
namespace wide_tracer {

// The batch the box tests run in: 8 floats with AVX (LINESPACE_ISA=avx2 or native), else 4 (SSE2,
// the portable x86-64 default; NEON on aarch64).  AVX-512's 16 floats would be wider than an 8-wide
// node, so 8 is the most taken.
#if XSIMD_WITH_AVX
using SimdArch = xsimd::avx;
#else
using SimdArch = Simd4Arch;
#endif
using FloatBatch = xsimd::batch<float, SimdArch>;

using lsk::Hit;
using lsk::LS_INVALID;
using lsk::uint;
using lsk::vec3;

// Rays the order-free walk takes: finite origin, direction and tmin (its slab arithmetic is the
// reference's only there; anything else takes the reference kernel).
LS_ALWAYS_INLINE bool order_free_ray(const vec3& origin, const vec3& dir, float tmin) {
  return std::isfinite(origin.x) && std::isfinite(origin.y) && std::isfinite(origin.z) && std::isfinite(dir.x) &&
         std::isfinite(dir.y) && std::isfinite(dir.z) && !std::isnan(tmin);
}

// The per-ray constants of the SIMD box tests (lsk::ray_box on a node's lanes), broadcast once into
// batches of Batch floats, for nodes that keep per axis a row of lower and a row of upper bounds.
template <class Batch>
struct SlabRay {
  Batch origin[3];
  Batch inv_dir[3];
  uint32_t lo[3];     // byte offset in the node of each axis' lower and upper rows
  uint32_t hi[3];
  uint32_t enter[3];  // the row the ray enters each slab through (lo where inv_dir >= 0), and leaves
  uint32_t leave[3];
  bool parallel[3];   // safe_reciprocal's huge value: the ray runs parallel to that slab
  bool any_parallel;
};

template <class Batch, class Node>
LS_ALWAYS_INLINE void init_slab_ray(SlabRay<Batch>& r, const vec3& origin, const vec3& inv_dir) {
  constexpr float big = 3.0e38f;
  constexpr uint32_t row = uint32_t(sizeof(Node::lo[0]));
  const float o[3] = {origin.x, origin.y, origin.z};  // indexed in memory, not through glm's switch
  const float inv[3] = {inv_dir.x, inv_dir.y, inv_dir.z};
  for (int a = 0; a < 3; ++a) {
    r.origin[a] = Batch(o[a]);
    r.inv_dir[a] = Batch(inv[a]);
    r.lo[a] = uint32_t(offsetof(Node, lo)) + row * uint32_t(a);
    r.hi[a] = uint32_t(offsetof(Node, hi)) + row * uint32_t(a);
    // The rows by arithmetic on the sign, not a branch: GCC made the choice a jump in the Line Space
    // tracer, which rays of random direction signs mispredicted 1.4 times a ray (fireplace).
    const uint32_t descending = uint32_t(!(inv[a] >= 0.0f));
    const uint32_t swap = descending * (r.hi[a] - r.lo[a]);
    r.enter[a] = r.lo[a] + swap;
    r.leave[a] = r.hi[a] - swap;
    r.parallel[a] = std::abs(inv[a]) == big;
  }
  r.any_parallel = r.parallel[0] || r.parallel[1] || r.parallel[2];
}

template <class Batch, class Node>
SlabRay<Batch> make_slab_ray(const vec3& origin, const vec3& inv_dir) {
  SlabRay<Batch> r;
  init_slab_ray<Batch, Node>(r, origin, inv_dir);
  return r;
}

// lsk::ray_box on the lanes of a node whose rows start at `rows` (the node, plus the byte offset of
// the first lane of the batch): the entry distance and the widened exit distance; a lane is hit
// when near <= widened.  The scalar kernel's operations (slab_interval, widen_distance) lane by lane,
// without fused multiply-adds (-ffp-contract=off).  The walk takes finite rays only (order_free_ray),
// so each slab's entry and exit come from the planes its direction says, not as min and max of the
// two: the same values (rounding is monotone), up to the sign of a zero, which no comparison sees.
template <bool kParallel, class Batch>
LS_ALWAYS_INLINE void slab_tests(const char* rows, const SlabRay<Batch>& r, const Batch& tmin, const Batch& tmax, Batch& near,
                                 Batch& widened) {
  constexpr float big = 3.0e38f;
  auto row = [&](uint32_t offset) LS_ALWAYS_LAMBDA { return Batch::load_aligned(reinterpret_cast<const float*>(rows + offset)); };
  Batch tn[3];
  Batch tf[3];
  for (int a = 0; a < 3; ++a) {
    if (kParallel && r.parallel[a]) {
      const auto inside = (r.origin[a] >= row(r.lo[a])) && (r.origin[a] <= row(r.hi[a]));
      tn[a] = xsimd::select(inside, Batch(-big), Batch(big));
      tf[a] = xsimd::select(inside, Batch(big), Batch(-big));
    } else {
      tn[a] = (row(r.enter[a]) - r.origin[a]) * r.inv_dir[a];
      tf[a] = (row(r.leave[a]) - r.origin[a]) * r.inv_dir[a];
    }
  }
  near = glm_max(glm_max(tn[0], tn[1]), glm_max(tn[2], tmin));
  const Batch far = glm_min(glm_min(tf[0], tf[1]), glm_min(tf[2], tmax));
  widened = far + (far & xsimd::bitwise_cast<Batch>(xsimd::batch<int32_t, typename Batch::arch_type>(0x7FFFFFFF))) *
                       Batch(lsk::LS_WIDEN_SLACK);
}

// The batch an exact W-wide node's boxes are tested in: 4 floats, or 8 where the build has AVX and
// W = 8 (an 8-wide node on SSE2 takes two batches).
template <int W>
using ExactBatch = std::conditional_t<W == 8, FloatBatch, Float4>;
template <int W>
using ExactBoxRay = SlabRay<ExactBatch<W>>;

// ray_box on the children of an exact wide node against [tmin, tmax]: the lanes hit (bit l) and
// their entry distances.  An unused lane's box is NaN, which no ray enters: its entry distance is
// NaN on an axis the ray crosses (glm_max keeps a NaN first operand) and +big on one it runs along.
template <bool kParallel, int W>
LS_ALWAYS_INLINE unsigned exact_box_tests(const ExactWideNode<W>& node, const ExactBoxRay<W>& r, const ExactBatch<W>& tmin,
                                          float tmax, float* tnear) {
  using Batch = ExactBatch<W>;
  unsigned bits = 0;
  const Batch tmax_batch(tmax);
  for (int c = 0; c < W; c += int(Batch::size)) {
    Batch near;
    Batch widened;
    slab_tests<kParallel>(reinterpret_cast<const char*>(&node) + sizeof(float) * size_t(c), r, tmin, tmax_batch, near,
                                widened);
    near.store_aligned(tnear + c);
    bits |= lane_bits(near <= widened) << c;
  }
  return bits;
}

// The order-free closest-hit walk below an exact wide node (whose binary node's box the caller has
// tested): nearest child first, a pending child popped only while its entry distance can still hold
// something as close as the current hit, as in the reference.
template <int W>
struct ExactWalk {
  struct Pending {
    uint child;
    uint count;
    float t;
  };
  static constexpr int kStack = W * lsk::TraceContext::LS_STACK_SIZE;  // < W more per wide level
  uint child = 0;  // what the next step visits: a wide node (count 0) or a leaf
  uint count = 0;
  int sp = 0;
  Pending stack[kStack];

  void start(uint entry) {
    child = entry;
    count = 0;
    sp = 0;
  }

  // A walk whose one step is the Line Space lane of binary node b (a BVH whose root has a Line Space).
  void start_at_lane(uint b) {
    child = b;
    count = kLsLane;
    sp = 0;
  }

  // The nearest pending child that can still hold something as close as a hit at t; false: none.
  bool pop(float t) {
    const float limit = lsk::widen_distance(t);
    while (sp > 0) {
      --sp;
      if (stack[sp].t <= limit) {
        child = stack[sp].child;
        count = stack[sp].count;
        return true;
      }
    }
    return false;
  }

  // Visits the next wide node or leaf; leaf(child, count) tests a leaf's primitives against the
  // running hit and returns true to end the walk there (an occlusion query's first hit).  When the
  // boxes admit several children, all of them start loading at once.  False when the walk is over.
  template <bool kParallel, class LeafFn, class PrefetchFn>
  LS_ALWAYS_INLINE bool step(const ExactWideTree<W>& tree, const ExactBoxRay<W>& ray, const ExactBatch<W>& tmin, const Hit& hit,
                             LeafFn&& leaf, PrefetchFn&& prefetch_leaf) {
    if (count != 0u) {
      if (leaf(child, count)) return false;  // the query stops at this leaf
      return pop(hit.t);
    }
    const ExactWideNode<W>& node = tree.nodes[child];
    alignas(32) float tn[W];
    unsigned lanes = exact_box_tests<kParallel>(node, ray, tmin, hit.t, tn);
    if (lanes == 0u) return pop(hit.t);
    unsigned near = unsigned(std::countr_zero(lanes));
    lanes &= lanes - 1u;
    if (lanes == 0u) {  // one child: go on with it
      child = node.child[near];
      count = node.count[near];
      return true;
    }
    auto push = [&](unsigned l) LS_ALWAYS_LAMBDA {
      stack[sp++] = Pending{node.child[l], node.count[l], tn[l]};
      if (node.count[l] == 0u) {
        const char* p = reinterpret_cast<const char*>(&tree.nodes[node.child[l]]);
        for (size_t line = 0; line < sizeof(ExactWideNode<W>); line += 64) __builtin_prefetch(p + line);
      } else {
        prefetch_leaf(node.child[l], node.count[l]);
      }
    };
    unsigned other = unsigned(std::countr_zero(lanes));
    lanes &= lanes - 1u;
    if (tn[other] < tn[near]) std::swap(near, other);
    if (lanes == 0u) {  // two: push the farther, go on with the nearer
      push(other);
    } else {  // three or more: push them farthest first, go on with the nearest
      unsigned order[W] = {near, other};
      unsigned n = 2;
      for (; lanes != 0u; lanes &= lanes - 1u) {
        unsigned l = unsigned(std::countr_zero(lanes));
        unsigned j = n++;
        while (j > 0u && tn[order[j - 1u]] > tn[l]) {
          order[j] = order[j - 1u];
          --j;
        }
        order[j] = l;
      }
      for (unsigned k = n - 1u; k > 0u; --k) push(order[k]);
      near = order[0];
    }
    child = node.child[near];
    count = node.count[near];
    return true;
  }
};

// One ray's whole order-free walk below `entry`.
template <int W, class LeafFn, class PrefetchFn>
LS_ALWAYS_INLINE void walk_exact(const ExactWideTree<W>& tree, uint entry, const ExactBoxRay<W>& ray, float tmin, const Hit& hit,
                       LeafFn&& leaf, PrefetchFn&& prefetch_leaf) {
  if (hit.t != hit.t) return;  // a NaN tmax: no t is <= it, the reference finds nothing either
  const ExactBatch<W> tmin_batch(tmin);
  ExactWalk<W> walk;
  walk.start(entry);
  if (ray.any_parallel)  // rays parallel to a slab are rare: the others run straight-line box tests
    while (walk.template step<true>(tree, ray, tmin_batch, hit, leaf, prefetch_leaf)) {
    }
  else
    while (walk.template step<false>(tree, ray, tmin_batch, hit, leaf, prefetch_leaf)) {
    }
}

// What the fast path keeps of the object level: the exact wide tree of the object BVHs (or of the
// flat BVH) and the triangle blocks.  Shared by the tracers of every top level (animation).
template <int W>
struct ObjectPart {
  TriangleBlocks blocks;
  ExactWideTree<W> exact;
};

// W: the wide trees' width (4 or 8); kLs: a Line Space structure (its wide trees have Line Space
// lanes).  The two kinds are instantiated in two translation units (exact_tracer.cpp and
// line_space_tracer.cpp): in one, the Line Space walk's code took GCC's inlining budget from the
// exact walk (bvh on fireplace 1,602 -> 1,854 instructions a ray).
template <int W, bool kLs>
class WideTracer final : public FastTracer {
 public:
  // Every query but the reference's any hit (trace --any-hit: the triangle it reports is the first
  // in the reference's order), which the reference kernels answer, walks the wide trees order-free;
  // shadow rays are occlusion queries (occluded()).
  WideTracer(const Accel& accel) : two_level_(accel.spec.two_level()) {
    const std::vector<uint32_t> none;
    const std::vector<uint32_t>& node_ls = kLs ? accel.node_ls : none;
    auto part = std::make_shared<ObjectPart<W>>();
    const std::vector<uint32_t> roots = two_level_ ? accel.object_roots : std::vector<uint32_t>{0u};
    part->exact = build_exact_wide_tree<W>(accel.nodes, node_ls, roots);
    part->blocks = build_triangle_blocks(accel.nodes, accel.tris, part->exact);
    if (two_level_) build_top(accel);
    part_ = std::move(part);
    blocks_ = part_->blocks.blocks.data();
  }

  // The object part of `other`, a new wide top tree over accel.top_nodes.
  WideTracer(const WideTracer& other, const Accel& accel)
      : two_level_(other.two_level_), part_(other.part_), blocks_(other.blocks_) {
    build_top(accel);
  }

  std::shared_ptr<const FastTracer> with_top_level(const Accel& accel) const override {
    if (!two_level_) return std::make_shared<WideTracer>(*this);
    return std::make_shared<WideTracer>(*this, accel);
  }
  const void* object_part() const override { return part_.get(); }

  void trace(lsk::TraceContext& c, const lsk::Ray* rays, Hit* hits, size_t count, bool any_hit) const override {
    trace_all(c, rays, hits, count, any_hit ? Query::AnyHit : Query::Closest);
  }

  void occluded(lsk::TraceContext& c, const lsk::Ray* rays, Hit* hits, size_t count) const override {
    trace_all(c, rays, hits, count, Query::Occlusion);
  }

  void find_candidates(lsk::TraceContext& c, const lsk::LsNode& ls, const vec3* centres, uint32_t first, uint32_t end,
                       uint32_t further_rays, uint32_t instance, uint32_t* prims) const override {
    // The shafts in index order: start patch s / (5 N^2), end patch its rank among the patches off
    // the start face (lsk::ls_shaft_patches), stepped on without dividing.
    const uint nn = ls.n * ls.n;
    uint start_patch, first_end_patch;
    lsk::ls_shaft_patches(first, ls.n, start_patch, first_end_patch);
    uint end_rank = first - start_patch * 5u * nn;
    uint start_face_first = (start_patch / nn) * nn;  // the start face's first patch
    for (uint32_t s = first; s != end; ++s) {
      const uint end_patch_s = end_rank >= start_face_first ? end_rank + nn : end_rank;
      uint prim = LS_INVALID;
      vec3 a = centres[start_patch];
      vec3 d;
      if (c.ls_segment(a, centres[end_patch_s], d)) {  // search ray 0 joins the patch centres
        Hit hit = c.ls_search_hit();
        trace_bvh<true>(c, ls.node, a, d, 0.0f, hit.t, instance, Query::Closest, false, hit, prim);
      }
      for (uint k = 1u; k <= further_rays && prim == LS_INVALID; ++k) {
        if (!c.ls_search_segment(ls, s, k, a, d)) continue;
        Hit hit = c.ls_search_hit();
        trace_bvh<true>(c, ls.node, a, d, 0.0f, hit.t, instance, Query::Closest, false, hit, prim);
      }
      prims[s - first] = prim;
      if (++end_rank == 5u * nn) {
        end_rank = 0u;
        if (++start_patch % nn == 0u) start_face_first += nn;
      }
    }
  }

  size_t bytes() const override { return part_->exact.bytes() + part_->blocks.bytes() + top_exact_.bytes(); }
  int exact_width() const override { return W; }

 private:
  // The top level: the exact wide tree, whose leaf lanes hold their first instance.
  void build_top(const Accel& accel) { top_exact_ = build_exact_wide_tree<W>(accel.top_nodes, {}, {0u}, ExactLeaves::Instances); }

  // What a trace asks: the closest hit, the reference's any hit (the first in its order), or only
  // whether anything is hit (some hit, found in any order: the fast path's shadow rays).
  enum class Query { Closest, AnyHit, Occlusion };

  void trace_all(lsk::TraceContext& c, const lsk::Ray* rays, Hit* hits, size_t count, Query q) const {
    if constexpr (kLs)
      if (q != Query::AnyHit && c.ls_enabled != 0u) return trace_in_flight(c, rays, hits, count, q);
    for (size_t i = 0; i < count; ++i) {
      const lsk::Ray& ray = rays[i];
      // A flat structure's trace_bvh makes this choice itself; the top walk of a two-level one does not.
      if (two_level_ && (q == Query::AnyHit || !order_free_ray(ray.origin, ray.dir, ray.tmin)))
        hits[i] = trace_ray_reference(c, ray, true, q != Query::Closest);
      else
        hits[i] = two_level_ ? trace_two_level(c, ray, q) : trace_flat(c, ray, q);
    }
  }

  // The ray's BlockRay, made when first asked: many rays that enter an instance's box never reach
  // a triangle of it.
  struct LazyBlockRay {
    const vec3& origin;
    const vec3& dir;
    BlockRay made;  // not zeroed first: that cost 40 instructions a ray
    bool ready = false;
    LazyBlockRay(const vec3& o, const vec3& d) : origin(o), dir(d) {}
    LS_ALWAYS_INLINE const BlockRay& operator()() {
      if (!ready) {
        make_block_ray(origin, dir, made);
        ready = true;
      }
      return made;
    }
  };

  // One query in one BVH (the flat one, or an instance's object): the ray as the walks need it.
  struct ObjectQuery {
    const vec3& origin;
    const vec3& dir;
    vec3 inv_dir;
    float tmin;
    float tmax;  // as launched: a Line Space lookup's window
    uint instance;
    bool any_hit;
    bool use_ls;
    ExactBoxRay<W> exact_ray;
    LazyBlockRay tri_ray;
    LS_ALWAYS_INLINE ObjectQuery(const vec3& o, const vec3& d, const vec3& inv, float t0, float t1, uint inst, bool any, bool ls)
        : origin(o), dir(d), inv_dir(inv), tmin(t0), tmax(t1), instance(inst), any_hit(any), use_ls(ls), tri_ray(o, d) {
      init_slab_ray<ExactBatch<W>, ExactWideNode<W>>(exact_ray, o, inv);
    }
  };

  // The order-free walk below `entry`, leaves tested against tri_ray(), Line Space lanes answered
  // by ls_node.  True: an occlusion query's hit (any_hit is one here: the reference's any hit never
  // walks order-free).
  LS_ALWAYS_INLINE bool run_exact(lsk::TraceContext& c, uint entry, ObjectQuery& q, Hit& hit, uint& hit_prim) const {
    bool stopped = false;
    auto run = [&](auto&& ray_for_leaf) LS_ALWAYS_LAMBDA {
      walk_exact(
          part_->exact, entry, q.exact_ray, q.tmin, hit,
          [&](uint child, uint n) {
            if constexpr (kLs) {
              if (n == kLsLane) return stopped = ls_node(c, child, q, hit, hit_prim);
              return stopped = blocks_behind_call(c, child, n, ray_for_leaf(), q.tmin, q.instance, q.any_hit, hit, hit_prim);
            }
            return stopped = trace_blocks(c, blocks_, child, n, ray_for_leaf(), q.tmin, q.instance, q.any_hit, hit, hit_prim);
          },
          [&](uint child, uint n) {
            if (!kLs || n != kLsLane) prefetch_block(child / 4u);
          });
    };
    if (q.instance == LS_INVALID) {  // flat: nearly every walk reaches a leaf
      const BlockRay& tr = q.tri_ray();
      run([&]() -> const BlockRay& { return tr; });
    } else {  // an instance's object: many walks end before any leaf
      run(q.tri_ray);
    }
    return stopped;
  }

  // The Line Space node at binary node b (a lane, or the root of a BVH): its lookup, and its
  // subtree's exact walk where the lookup refuses (or use_ls is off).  True: an occlusion query's
  // hit.  Out of line: the subtree's walk calls back into run_exact.
  __attribute__((noinline)) bool ls_node(lsk::TraceContext& c, uint b, ObjectQuery& q, Hit& hit, uint& hit_prim) const {
    const lsk::BvhNode& node = c.nodes[b];
    const uint ls = q.use_ls ? c.node_ls[b] : LS_INVALID;
    if (ls != LS_INVALID && c.ls_skip == lsk::TraceContext::LS_SKIP_LOOKUPS) return false;  // profiling: "empty"
    const uint answer = ls == LS_INVALID ? lsk::TraceContext::LS_FALLBACK
                                         : c.ls_lookup(ls, node.lo, node.hi, q.origin, q.dir, q.inv_dir, q.tmin, q.tmax,
                                                       q.instance, hit, hit_prim);
    if (ls != LS_INVALID && skipped_walk(c, answer)) return false;
    return answered(c, b, answer, q, hit, hit_prim);
  }

  // linespace-profile --skip refused-walks: a refused lookup's subtree is not walked.
  static LS_ALWAYS_INLINE bool skipped_walk(const lsk::TraceContext& c, uint answer) {
    return answer == lsk::TraceContext::LS_FALLBACK && c.ls_skip == lsk::TraceContext::LS_SKIP_REFUSED_WALKS;
  }

  // What a lookup's answer at binary node b asks: nothing more (accepted, empty), or the subtree's
  // exact walk (refused).  True: an occlusion query's hit.
  LS_ALWAYS_INLINE bool answered(lsk::TraceContext& c, uint b, uint answer, ObjectQuery& q, Hit& hit, uint& hit_prim) const {
    if (answer == lsk::TraceContext::LS_ACCEPTED) return q.any_hit && hit.triangle != LS_INVALID;
    if (answer == lsk::TraceContext::LS_EMPTY) return false;
    return walk_refused(c, b, q, hit, hit_prim);
  }

  __attribute__((noinline)) bool walk_refused(lsk::TraceContext& c, uint b, ObjectQuery& q, Hit& hit, uint& hit_prim) const {
    const lsk::BvhNode& node = c.nodes[b];
    if (node.count > 0)
      return trace_blocks(c, blocks_, part_->blocks.lane_of[b], node.count, q.tri_ray(), q.tmin, q.instance, q.any_hit, hit,
                          hit_prim);
    return run_exact(c, part_->exact.entry_of[b], q, hit, hit_prim);
  }

  // Rays in flight (Line Space structures, closest hit and occlusion): a lookup waits on two
  // dependent cache misses, the shaft's candidate word and then the candidate's record, and a ray
  // makes about one lookup, so one ray alone has nothing to overlap them with.  kInFlight rays walk
  // in turn instead: a walk that reaches a Line Space lane computes its shaft, starts loading the
  // word and parks; on its next turn it reads the word and starts loading the record; on the turn
  // after it runs the lookup on loaded lines and walks on.  A lookup that reads no record lands on
  // the turn that reads the word.  The answers are order-free, so every ray gets the hit (and the
  // counters) it gets alone.
  static constexpr int kInFlight = 8;
  enum class Phase { Free, Word, Record };
  struct Flight {
    Phase phase = Phase::Free;
    size_t index = 0;  // of the ray in the call
    const lsk::Ray* ray = nullptr;
    Hit hit;
    uint prim = LS_INVALID;
    // The object walk: the flat BVH's, or the current instance's (two-level).
    std::optional<ObjectQuery> q;
    ExactWalk<W> walk;
    bool in_object = false;
    // The two-level top walk, and the instances of the leaf it is at: [next_instance, end_instance).
    ExactWalk<W> top;
    ExactBoxRay<W> top_ray;
    bool top_over = false;    // no top walk (its root is a leaf) or its walk has ended
    bool at_top_leaf = false;  // the instances of top's leaf have been started
    bool any_hit = false;
    uint next_instance = 0;
    uint end_instance = 0;
    vec3 object_origin;  // the current instance's ray: what q refers to
    vec3 object_dir;
    // The lookup it is parked at (walk.child is its binary node).
    uint ls = LS_INVALID;
    uint shaft = 0;
    uint prim_candidate = LS_INVALID;  // the shaft's candidate, read on the turn after parking
    uint reverse_shaft = 0;  // --ls-behind reverse or empty: loaded too, in case the first candidate's plane hit is behind
    float t_in = 0.0f;
    float t_out = 0.0f;
  };
  enum class Flown { Parked, Over, Stopped };  // an object walk's turn: parked, ended, or ended the query

  void trace_in_flight(lsk::TraceContext& c, const lsk::Ray* rays, Hit* hits, size_t count, Query query) const {
    Flight flights[kInFlight];
    size_t next = 0;
    // Starts the next ray that parks in f; the rays before it that finish without parking (or that
    // no flight takes) are traced here.  f is free when the rays run out.
    auto launch = [&](Flight& f) {
      f.phase = Phase::Free;
      while (next < count) {
        const size_t i = next++;
        const lsk::Ray& ray = rays[i];
        if (!order_free_ray(ray.origin, ray.dir, ray.tmin) || ray.tmax != ray.tmax) {
          hits[i] = two_level_ ? trace_ray_reference(c, ray, true, query != Query::Closest) : trace_flat(c, ray, query);
          continue;
        }
        f.index = i;
        f.ray = &ray;
        f.hit = lsk::empty_hit(ray);
        f.prim = LS_INVALID;
        if (two_level_ ? take_off_two_level(c, f, query) : take_off_flat(c, f, query)) return;
        hits[i] = lsk::finish_hit(f.hit);
      }
    };
    int live = 0;
    for (Flight& f : flights) {
      launch(f);
      live += f.phase != Phase::Free;
    }
    while (live > 0) {
      for (Flight& f : flights) {
        if (f.phase == Phase::Free || (f.phase == Phase::Word && load_record(c, f))) continue;
        if (land(c, f)) continue;
        hits[f.index] = lsk::finish_hit(f.hit);
        launch(f);
        live -= f.phase == Phase::Free;
      }
    }
  }

  // f's turn at Phase::Word: reads its shaft's candidate word.  True when the lookup needs the
  // candidate's record (and the reverse shaft's, with --ls-behind reverse or empty): they start
  // loading and f lands on its next turn.  False when it needs none, an empty shaft or, in exact mode,
  // a line that enters the box before tmin: f lands at once.
  bool load_record(lsk::TraceContext& c, Flight& f) const {
    const lsk::LsNode& node = c.ls_nodes[f.ls];
    f.prim_candidate = c.ls_candidate(node, f.shaft);
    if (f.prim_candidate == LS_INVALID || !c.ls_reads_first_record(f.t_in, f.q->tmin)) return false;
    __builtin_prefetch(&c.ls_records[f.prim_candidate]);
    if (c.ls_behind != lsk::TraceContext::LS_BEHIND_EXACT) {
      const uint reverse_prim = c.ls_candidate(node, f.reverse_shaft);
      if (reverse_prim != LS_INVALID) __builtin_prefetch(&c.ls_records[reverse_prim]);
    }
    f.phase = Phase::Record;
    return true;
  }

  // The first turn of a flat structure's ray: true when it parks.
  bool take_off_flat(lsk::TraceContext& c, Flight& f, Query query) const {
    const lsk::Ray& ray = *f.ray;
    // launch has checked the ray against order_free_ray, and a flat structure's object ray is the ray.
    if (start_object<true>(c, f, 0u, ray.origin, ray.dir, LS_INVALID, query != Query::Closest, true) != Begun::Walk)
      return false;
    return fly_object(c, f) == Flown::Parked;
  }

  // What start_object found: an object walk to fly, nothing left to walk, or an occlusion query's hit.
  enum class Begun { Walk, Over, Stopped };

  // f's object walk in the BVH of root `root` for the (object-space) ray origin + t dir, which f.q
  // will refer to: trace_bvh's set-up of an order-free walk.  What needs no walk is traced here: a
  // root that is a leaf, and a ray outside the order-free walk's arithmetic (the reference kernel;
  // kOrderFree: the caller knows the ray is inside it).  Inlined: once a ray, its call cost more
  // than its body (fireplace, f-ls:8:6 without Line Space nodes: 23 instructions a ray).
  template <bool kOrderFree = false>
  LS_ALWAYS_INLINE Begun start_object(lsk::TraceContext& c, Flight& f, uint root, const vec3& origin, const vec3& dir, uint instance,
                     bool any_hit, bool use_ls) const {
    const lsk::Ray& ray = *f.ray;
    if (!kOrderFree && !order_free_ray(origin, dir, ray.tmin))
      return trace_bvh_reference(c, root, origin, dir, ray.tmin, ray.tmax, instance, any_hit, use_ls, f.hit, f.prim)
                 ? Begun::Stopped
                 : Begun::Over;
    const vec3 inv_dir = lsk::safe_reciprocal(dir);
    const uint root_entry = part_->exact.entry_of[root];
    const bool root_ls = c.node_ls[root] != LS_INVALID;
    if (root_entry == LS_INVALID || root_ls) {  // a leaf, or a Line Space at the root: its box first
      const lsk::BvhNode& node = c.nodes[root];
      float t_root;
      if (!lsk::ray_box(origin, inv_dir, ray.tmin, f.hit.t, node.lo, node.hi, t_root)) return Begun::Over;
      if (!root_ls) {
        BlockRay tri_ray;
        make_block_ray(origin, dir, tri_ray);
        return trace_blocks(c, blocks_, part_->blocks.lane_of[root], node.count, tri_ray, ray.tmin, instance, any_hit, f.hit,
                            f.prim)
                   ? Begun::Stopped
                   : Begun::Over;
      }
    }
    f.q.emplace(origin, dir, inv_dir, ray.tmin, ray.tmax, instance, any_hit, use_ls);
    if (root_ls)
      f.walk.start_at_lane(root);
    else
      f.walk.start(root_entry);
    return Begun::Walk;
  }

  // The first turn of a two-level structure's ray (trace_two_level's set-up): true when it parks.
  bool take_off_two_level(lsk::TraceContext& c, Flight& f, Query query) const {
    const lsk::Ray& ray = *f.ray;
    const vec3 inv_dir = lsk::safe_reciprocal(ray.dir);
    float t_root;
    if (!lsk::ray_box(ray.origin, inv_dir, ray.tmin, f.hit.t, c.top_nodes[0].lo, c.top_nodes[0].hi, t_root)) return false;
    f.any_hit = query != Query::Closest;
    f.in_object = false;
    f.at_top_leaf = false;
    const lsk::BvhNode& root = c.top_nodes[0];
    f.top_over = root.count > 0;
    if (f.top_over) {
      f.next_instance = root.first;
      f.end_instance = root.first + root.count;
    } else {
      f.next_instance = f.end_instance = 0;
      init_slab_ray<ExactBatch<W>, ExactWideNode<W>>(f.top_ray, ray.origin, inv_dir);
      f.top.start(top_exact_.entry_of[0]);
    }
    return fly(c, f);
  }

  // f's ray walks on until it parks at a Line Space lane (true) or its query is over (false).
  bool fly(lsk::TraceContext& c, Flight& f) const {
    if (!two_level_) return fly_object(c, f) == Flown::Parked;
    const lsk::Ray& ray = *f.ray;
    const bool use_ls = c.ls_enabled != 0u;
    for (;;) {
      if (f.in_object) {
        const Flown flown = fly_object(c, f);
        if (flown == Flown::Parked) return true;
        f.in_object = false;
        if (flown == Flown::Stopped) return false;
      }
      if (f.next_instance < f.end_instance) {  // the next instance of the leaf: trace_bvh's cases
        const lsk::InstanceRecord& rec = c.instances[f.next_instance++];
        c.instance_ray(rec, ray.origin, ray.dir, f.object_origin, f.object_dir);
        const Begun begun = start_object(c, f, rec.root, f.object_origin, f.object_dir, rec.instance, f.any_hit, use_ls);
        if (begun == Begun::Stopped) return false;
        f.in_object = begun == Begun::Walk;
        continue;
      }
      if (f.top_over) return false;
      if (f.top.count != 0u) {  // at a leaf of the instance tree: its instances, then the walk on
        if (!f.at_top_leaf) {
          f.next_instance = f.top.child;
          f.end_instance = f.top.child + f.top.count;
          f.at_top_leaf = true;
          continue;
        }
        f.at_top_leaf = false;
        if (!f.top.pop(f.hit.t)) return false;
        continue;
      }
      const ExactBatch<W> tmin_batch(ray.tmin);
      auto none = [](uint, uint) LS_ALWAYS_LAMBDA { return false; };  // never called: leaves are taken above
      auto no_prefetch = [](uint, uint) LS_ALWAYS_LAMBDA {};
      const bool more = f.top_ray.any_parallel
                            ? f.top.template step<true>(top_exact_, f.top_ray, tmin_batch, f.hit, none, no_prefetch)
                            : f.top.template step<false>(top_exact_, f.top_ray, tmin_batch, f.hit, none, no_prefetch);
      if (!more) return false;
    }
  }

  // The object walk (flat BVH or an instance's) on until it parks, ends, or ends the query.
  Flown fly_object(lsk::TraceContext& c, Flight& f) const {
    ObjectQuery& q = *f.q;
    bool stopped = false;
    auto leaf = [&](uint child, uint n) LS_ALWAYS_LAMBDA {
      return stopped = blocks_behind_call(c, child, n, q.tri_ray(), q.tmin, q.instance, q.any_hit, f.hit, f.prim);
    };
    auto prefetch = [&](uint child, uint n) LS_ALWAYS_LAMBDA {
      if (n != kLsLane) prefetch_block(child / 4u);
    };
    const ExactBatch<W> tmin_batch(q.tmin);
    for (;;) {
      if (f.walk.count == kLsLane) {  // a Line Space lane: park, or answer it here
        if (park(c, f)) return Flown::Parked;
        if (ls_node(c, f.walk.child, q, f.hit, f.prim)) return Flown::Stopped;
        if (!f.walk.pop(f.hit.t)) return Flown::Over;
        continue;
      }
      const bool more = q.exact_ray.any_parallel
                            ? f.walk.template step<true>(part_->exact, q.exact_ray, tmin_batch, f.hit, leaf, prefetch)
                            : f.walk.template step<false>(part_->exact, q.exact_ray, tmin_batch, f.hit, leaf, prefetch);
      if (!more) return stopped ? Flown::Stopped : Flown::Over;
    }
  }

  // Parks f at the Line Space lane its walk reached: its shaft, and the candidate word loading.
  // False where the lookup has no shaft to load (ls_node answers it at once).
  bool park(lsk::TraceContext& c, Flight& f) const {
    const uint ls = f.q->use_ls ? c.node_ls[f.walk.child] : LS_INVALID;
    if (ls == LS_INVALID || c.ls_cos2 < 0.0f || c.ls_skip == lsk::TraceContext::LS_SKIP_LOOKUPS) return false;
    const lsk::LsNode& node = c.ls_nodes[ls];
    const ObjectQuery& q = *f.q;
    if (!lsk::ls_line_shaft(q.origin, q.dir, q.inv_dir, node.lo, node.hi, node.scale, node.n, f.shaft, f.t_in, f.t_out))
      return false;
    __builtin_prefetch(&c.ls_candidates[c.ls_candidate_word(node, f.shaft)]);
    if (c.ls_behind != lsk::TraceContext::LS_BEHIND_EXACT) {  // the reverse shaft's candidate answers when the first's plane hit is behind tmin
      f.reverse_shaft = lsk::ls_reverse_shaft(f.shaft, node.n);
      __builtin_prefetch(&c.ls_candidates[c.ls_candidate_word(node, f.reverse_shaft)]);
    }
    f.ls = ls;
    f.phase = Phase::Word;
    return true;
  }

  // f's lookup on its loaded lines, then its walk on: true when it parks again.
  bool land(lsk::TraceContext& c, Flight& f) const {
    ObjectQuery& q = *f.q;
    const uint b = f.walk.child;
    const lsk::BvhNode& node = c.nodes[b];
    const uint answer = c.ls_shaft_lookup(c.ls_nodes[f.ls], f.shaft, f.prim_candidate, f.t_in, f.t_out, node.lo, node.hi,
                                          q.origin, q.dir, q.inv_dir, q.tmin, q.tmax, q.instance, f.hit, f.prim);
    if (!skipped_walk(c, answer) && answered(c, b, answer, q, f.hit, f.prim)) return false;  // an occlusion query's hit
    if (!f.walk.pop(f.hit.t)) {
      if (!two_level_) return false;
      f.in_object = false;  // the instance's walk is over: the top walk goes on
    }
    return fly(c, f);
  }

  // lsk::TraceContext::trace_bvh on the wide trees: the order-free walk, except for the reference's
  // any hit and rays outside the order-free walk's arithmetic (order_free_ray), which take the
  // reference kernel.  Returns true when an any-hit or occlusion query found its hit (the caller
  // stops).  Always inlined: GCC otherwise chose by a hair whether an instance's walk sat in the top
  // walk or behind a call (2l-bvh on cornell 3,611 or 3,797 instructions a ray, from one change
  // elsewhere).  kSearch: the LS build's search gets its own copy of the walks it inlines; sharing
  // them added a caller to the instance's exact walk, which GCC then left out of line (2l-bvh on
  // generated 3,388 -> 3,483).
  template <bool kSearch = false>
  LS_ALWAYS_INLINE bool trace_bvh(lsk::TraceContext& c, uint root, const vec3& origin, const vec3& dir, float tmin, float tmax,
                                  uint instance, Query q, bool use_ls, Hit& hit, uint& hit_prim) const {
    const bool any_hit = q != Query::Closest;
    if (q == Query::AnyHit || !order_free_ray(origin, dir, tmin))
      return trace_bvh_reference(c, root, origin, dir, tmin, tmax, instance, any_hit, use_ls, hit, hit_prim);
    const vec3 inv_dir = lsk::safe_reciprocal(dir);
    ObjectQuery query(origin, dir, inv_dir, tmin, tmax, instance, any_hit, use_ls);
    const uint root_entry = part_->exact.entry_of[root];
    const bool root_ls = kLs && c.node_ls[root] != LS_INVALID;
    // The entry's node tests the root's children, which pass only where the root's box would.
    if (root_entry != LS_INVALID && !root_ls) return run_exact(c, root_entry, query, hit, hit_prim);
    const lsk::BvhNode& node = c.nodes[root];
    float t_root;
    if (!lsk::ray_box(origin, inv_dir, tmin, hit.t, node.lo, node.hi, t_root)) return false;
    if (!root_ls)  // a root that is a leaf (many small objects of a two-level structure)
      return trace_blocks(c, blocks_, part_->blocks.lane_of[root], node.count, query.tri_ray(), tmin, instance, any_hit, hit,
                          hit_prim);
    return ls_node(c, root, query, hit, hit_prim);  // a Line Space at the root
  }

  Hit trace_flat(lsk::TraceContext& c, const lsk::Ray& ray, Query q) const {
    Hit hit = lsk::empty_hit(ray);
    uint prim = LS_INVALID;
    trace_bvh(c, 0u, ray.origin, ray.dir, ray.tmin, ray.tmax, LS_INVALID, q, c.ls_enabled != 0u, hit, prim);
    return lsk::finish_hit(hit);
  }

  Hit trace_two_level(lsk::TraceContext& c, const lsk::Ray& ray, Query q) const {
    Hit hit = lsk::empty_hit(ray);
    uint prim = LS_INVALID;
    const vec3 inv_dir = lsk::safe_reciprocal(ray.dir);
    float t_root;
    if (!lsk::ray_box(ray.origin, inv_dir, ray.tmin, hit.t, c.top_nodes[0].lo, c.top_nodes[0].hi, t_root))
      return lsk::finish_hit(hit);
    const bool use_ls = c.ls_enabled != 0u;
    auto instances = [&](uint first, uint count) {  // true: the query stops
      for (uint i = first; i < first + count; ++i) {
        const lsk::InstanceRecord& rec = c.instances[i];
        vec3 o;
        vec3 d;
        c.instance_ray(rec, ray.origin, ray.dir, o, d);
        if (trace_bvh(c, rec.root, o, d, ray.tmin, ray.tmax, rec.instance, q, use_ls, hit, prim)) return true;
      }
      return false;
    };
    const lsk::BvhNode& root = c.top_nodes[0];
    if (root.count > 0)
      instances(root.first, root.count);
    else
      [&]() __attribute__((noinline)) {  // its own function, with the instances' walks inlined in it (fewer spills)
        walk_exact(top_exact_, top_exact_.entry_of[0],
                   make_slab_ray<ExactBatch<W>, ExactWideNode<W>>(ray.origin, inv_dir), ray.tmin, hit, instances,
                   [](uint, uint) {});
      }();
    return lsk::finish_hit(hit);
  }

  // trace_blocks behind a call, for the Line Space walks.  Inlined into each of them (the flights'
  // walk, the refused subtrees' walk) it cost 1-3 % more instructions a ray (f-ls:8:6 on fireplace
  // 2,078 -> 2,049, 2l-ls:4:6 on generated 3,270 -> 3,172); the exact tracer's walk calls it already.
  __attribute__((noinline)) bool blocks_behind_call(const lsk::TraceContext& c, uint lane, uint count, const BlockRay& r,
                                                    float tmin, uint instance, bool any_hit, Hit& hit, uint& prim) const {
    return trace_blocks(c, blocks_, lane, count, r, tmin, instance, any_hit, hit, prim);
  }

  void prefetch_block(uint block) const {
    const char* p = reinterpret_cast<const char*>(&blocks_[block]);
    for (size_t line = 0; line < sizeof(TriBlock); line += 64) __builtin_prefetch(p + line);
  }

  bool two_level_;
  std::shared_ptr<const ObjectPart<W>> part_;
  const TriBlock* blocks_ = nullptr;  // part_->blocks.blocks.data(): one load less on the hot path
  ExactWideTree<W> top_exact_;
};

}  // namespace wide_tracer

// The tracer of the Line Space structures (line_space_tracer.cpp); exact_width 4 or 8, checked by
// make_fast_tracer (exact_tracer.cpp).
std::shared_ptr<const FastTracer> make_line_space_tracer(const Accel& accel, int exact_width);

}  // namespace ls
