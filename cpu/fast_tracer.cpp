#include "fast_tracer.h"

#include "accel.h"
#include "huge_pages.h"
#include "parallel.h"
#include "simd.h"
#include "wide_bvh.h"

#include <bit>

namespace ls {

// The batch the box tests run in: 8 floats with AVX (LINESPACE_ISA=native on these machines), else
// 4 (SSE2, the portable x86-64 default; NEON on aarch64).  AVX-512's 16 floats would be wider than a
// 4-wide treelet's 6 boxes, so 8 is the most taken.
#if XSIMD_WITH_AVX
using SimdArch = xsimd::avx;
#else
using SimdArch = Simd4Arch;
#endif
using FloatBatch = xsimd::batch<float, SimdArch>;

// Triangles are tested four at a time (a leaf holds at most four, unless they cannot be separated).
using Tri4 = Float4;
static_assert(Tri4::size == 4, "triangle blocks hold four triangles");

Traversal parse_traversal(const std::string& text) {
  if (text == "reference") return Traversal::Reference;
  if (text == "fast") return Traversal::Fast;
  throw InputError("traversal '" + text + "' is not reference or fast");
}

const char* traversal_name(Traversal t) { return t == Traversal::Fast ? "fast" : "reference"; }

std::string fast_path_isa() {
  return std::string(SimdArch::name()) + " (" + std::to_string(FloatBatch::size) + " floats)";
}

namespace {

using lsk::Hit;
using lsk::LS_INVALID;
using lsk::uint;
using lsk::vec3;

// The per-ray constants of the box tests.
struct BoxRay {
  float origin[3];
  float inv_dir[3];
  bool parallel[3];  // safe_reciprocal's huge value: the ray runs parallel to that slab
  bool any_parallel;
};

BoxRay make_box_ray(const vec3& origin, const vec3& inv_dir) {
  constexpr float big = 3.0e38f;
  BoxRay r;
  for (int a = 0; a < 3; ++a) {
    r.origin[a] = origin[a];
    r.inv_dir[a] = inv_dir[a];
    r.parallel[a] = std::abs(inv_dir[a]) == big;
  }
  r.any_parallel = r.parallel[0] || r.parallel[1] || r.parallel[2];
  return r;
}

// lsk::ray_box for every lane of a wide node: entry distance and widened exit distance; a lane is hit
// when tnear <= tfar.  Same operations in the same order as the scalar kernel (slab_interval,
// widen_distance), and no fused multiply-adds (-ffp-contract=off), hence the same bits.
template <int K>
inline void box_tests(const WideNode<K>& node, const BoxRay& r, float tmin, float tmax, float* tnear, float* tfar) {
  constexpr float big = 3.0e38f;
  constexpr float slack = 3.81469727e-6f;  // widen_distance's 2^-18
  for (int c = 0; c < WideNode<K>::kPadded; c += int(FloatBatch::size)) {
    FloatBatch tn[3];
    FloatBatch tf[3];
    for (int a = 0; a < 3; ++a) {
      const FloatBatch lo = FloatBatch::load_aligned(&node.lo[a][c]);
      const FloatBatch hi = FloatBatch::load_aligned(&node.hi[a][c]);
      const FloatBatch o(r.origin[a]);
      if (r.any_parallel && r.parallel[a]) {
        const auto inside = (o >= lo) && (o <= hi);
        tn[a] = xsimd::select(inside, FloatBatch(-big), FloatBatch(big));
        tf[a] = xsimd::select(inside, FloatBatch(big), FloatBatch(-big));
      } else {
        const FloatBatch inv(r.inv_dir[a]);
        const FloatBatch t0 = (lo - o) * inv;
        const FloatBatch t1 = (hi - o) * inv;
        tn[a] = glm_min(t0, t1);
        tf[a] = glm_max(t0, t1);
      }
    }
    const FloatBatch near = glm_max(glm_max(tn[0], tn[1]), glm_max(tn[2], FloatBatch(tmin)));
    const FloatBatch far = glm_min(glm_min(tf[0], tf[1]), glm_min(tf[2], FloatBatch(tmax)));
    const FloatBatch widened = far + xsimd::abs(far) * FloatBatch(slack);
    near.store_aligned(tnear + c);
    widened.store_aligned(tfar + c);
  }
}

// Four triangles of a leaf in SoA layout: v[vertex][axis][lane].  Lanes past the leaf's count are 0.
struct alignas(16) TriBlock {
  float v[3][3][4];
};

// lsk::scale_pow2(x, e) lane by lane for e in [-126, 126] (what unit_exponent returns): x * 2^e is
// exact unless the result would be denormal, where the kernel flushes to a signed zero instead; a
// zero, an infinity or a NaN stays itself.  The kernel's two half-steps give the same exact product.
inline Tri4 scale_pow2_lanes(const Tri4& x, const Int4& e, const Tri4& pow2_e) {
  const Int4 field = (xsimd::bitwise_cast<Int4>(x) >> 23) & Int4(255);
  const auto flush = ((field - Int4(127) + e) < Int4(-126)) && (field != Int4(255));
  const Int4 bits = xsimd::select(flush, xsimd::bitwise_cast<Int4>(x * Tri4(0.0f)), xsimd::bitwise_cast<Int4>(x * pow2_e));
  return xsimd::bitwise_cast<Tri4>(bits);
}

inline Tri4 max_abs_lanes(const Tri4& x, const Tri4& y, const Tri4& z) {
  return glm_max(glm_max(xsimd::abs(x), xsimd::abs(y)), xsimd::abs(z));
}

// The first half of lsk::ray_triangle on four triangles at once: translate, scale by the power of two,
// shear, edge functions; the same operations lane by lane, hence the same values.  Returns a lane
// mask (bit l) of the triangles the kernel may hit: those whose edge-function signs do not already
// reject them, and those with a zero edge function (the kernel then recomputes it in double).  The
// kernel itself decides these, so a hit is the kernel's hit bit for bit.
inline unsigned maybe_hit_lanes(const TriBlock& block, const lsk::TriRay& r) {
  Tri4 d[3][3];  // translated vertices: d[vertex][axis]
  for (int k = 0; k < 3; ++k)
    for (int a = 0; a < 3; ++a) d[k][a] = Tri4::load_aligned(block.v[k][a]) - Tri4(r.origin[a]);
  const Tri4 m = glm_max(glm_max(max_abs_lanes(d[0][0], d[0][1], d[0][2]), max_abs_lanes(d[1][0], d[1][1], d[1][2])),
                          max_abs_lanes(d[2][0], d[2][1], d[2][2]));
  // unit_exponent(m) = clamp(-float_exponent(m), -126, 126); lanes with m == 0 end as zero edges.
  const Int4 neg_exp = Int4(127) - ((xsimd::bitwise_cast<Int4>(m) >> 23) & Int4(255));
  const Int4 ks = xsimd::select(neg_exp > Int4(126), Int4(126), xsimd::select(neg_exp < Int4(-126), Int4(-126), neg_exp));
  const Tri4 pow2_ks = xsimd::bitwise_cast<Tri4>((ks + Int4(127)) << 23);
  Tri4 sx[3];
  Tri4 sy[3];
  const Tri4 shear_x(r.sx);
  const Tri4 shear_y(r.sy);
  for (int k = 0; k < 3; ++k) {
    const Tri4 px = scale_pow2_lanes(d[k][r.kx], ks, pow2_ks);
    const Tri4 py = scale_pow2_lanes(d[k][r.ky], ks, pow2_ks);
    const Tri4 pz = scale_pow2_lanes(d[k][r.kz], ks, pow2_ks);
    sx[k] = px - shear_x * pz;
    sy[k] = py - shear_y * pz;
  }
  const Tri4 eu = sx[2] * sy[1] - sy[2] * sx[1];
  const Tri4 ev = sx[0] * sy[2] - sy[0] * sx[2];
  const Tri4 ew = sx[1] * sy[0] - sy[1] * sx[0];
  const Tri4 zero(0.0f);
  const auto any_zero = (eu == zero) || (ev == zero) || (ew == zero);
  const auto rejected = ((eu < zero) || (ev < zero) || (ew < zero)) && ((eu > zero) || (ev > zero) || (ew > zero));
  const auto maybe = any_zero || !rejected;
  alignas(16) bool lanes[4];
  maybe.store_aligned(lanes);
  return unsigned(lanes[0]) | unsigned(lanes[1]) << 1 | unsigned(lanes[2]) << 2 | unsigned(lanes[3]) << 3;
}

// What a node visit asks of the traversal.
enum class Visit { Descend, Skip, Stop };

// The reference's loop (trace_bvh / trace_two_level), node for node, on a wide tree.  Starts at the
// treelet root of wide node w (its box already tested by the caller).  visit(ls, leaf, first, count)
// is called for every node the reference visits: an inner node (leaf = false) is descended only on
// Visit::Descend; Visit::Stop ends the walk and returns true.
//
// Each wide node's boxes are tested once, when the walk enters it, against the current t = h0; later
// decisions at its inner positions (after a pop, with a smaller current t = h) reuse them.  This is
// exact: the reference tests tnear <= widen(min(tf, h)), tnear does not depend on t, and widen is
// monotone, so for h <= h0 that is tnear <= widen(min(tf, h0)) && tnear <= widen(h).  (A NaN tmax is
// ignored by the reference's min and never changes: the second test is then skipped.)  The walk is
// depth first, so a node's results sit in the slot of its wide depth until every pending position of
// it has been popped.
template <int K, class VisitFn, class PrefetchFn>
inline bool walk(const WideTree<K>& tree, uint w, const BoxRay& ray, float tmin, const Hit& hit, VisitFn&& visit,
                 PrefetchFn&& prefetch_leaf) {
  using Node = WideNode<K>;
  constexpr int kMaxDepth = lsk::TraceContext::LS_STACK_SIZE / K + 1;
  alignas(64) float tnear[kMaxDepth][Node::kPadded];
  alignas(64) float tfar[kMaxDepth][Node::kPadded];
  const bool nan_t = hit.t != hit.t;
  uint stack_w[lsk::TraceContext::LS_STACK_SIZE];
  uint stack_pos[lsk::TraceContext::LS_STACK_SIZE];
  int stack_depth[lsk::TraceContext::LS_STACK_SIZE];
  float stack_t[lsk::TraceContext::LS_STACK_SIZE];
  int sp = 0;
  uint pos = 1;
  int depth = 0;
  while (true) {
    const Node& node = tree.nodes[w];
    const bool root = pos == 1;
    const uint lane = pos - 2;
    const bool leaf = !root && node.count[lane] > 0;
    const Visit v = visit(root ? node.root_ls : node.ls[lane], leaf, leaf ? node.first[lane] : 0u, leaf ? node.count[lane] : 0u,
                          leaf ? node.block[lane] : LS_INVALID);
    if (v == Visit::Stop) return true;
    if (v == Visit::Descend && !leaf) {
      if (root) {
        box_tests(node, ray, tmin, hit.t, tnear[depth], tfar[depth]);
        // Start loading what the boxes say may come next: the traversal is bound by memory latency.
        for (uint p = Node::kBottom; p < 2u * Node::kBottom; ++p) {
          const uint l = p - 2u;
          if (!(tnear[depth][l] <= tfar[depth][l])) continue;
          const char* next = node.count[l] == 0u ? reinterpret_cast<const char*>(&tree.nodes[node.first[l]])
                                                 : prefetch_leaf(node.block[l]);
          const size_t bytes = node.count[l] == 0u ? sizeof(Node) : sizeof(TriBlock);
          if (next)
            for (size_t line = 0; line < bytes; line += 64) __builtin_prefetch(next + line);
        }
      }
      const float* tn = tnear[depth];
      const float* tf = tfar[depth];
      const float limit = lsk::widen_distance(hit.t);
      const uint c0 = 2u * pos;
      const uint c1 = c0 + 1u;
      const float tn0 = tn[c0 - 2u];
      const float tn1 = tn[c1 - 2u];
      const bool hit0 = tn0 <= tf[c0 - 2u] && (nan_t || tn0 <= limit);
      const bool hit1 = tn1 <= tf[c1 - 2u] && (nan_t || tn1 <= limit);
      // A bottom-level inner node continues as the root of its own wide node, one wide level down.
      auto go = [&](uint c, uint& to_w, uint& to_pos, int& to_depth) {
        if (c >= Node::kBottom && node.count[c - 2u] == 0u) {
          to_w = node.first[c - 2u];
          to_pos = 1u;
          to_depth = depth + 1;
        } else {
          to_w = w;
          to_pos = c;
          to_depth = depth;
        }
      };
      if (hit0 && hit1) {
        const bool first0 = tn0 <= tn1;
        go(first0 ? c1 : c0, stack_w[sp], stack_pos[sp], stack_depth[sp]);
        stack_t[sp] = first0 ? tn1 : tn0;
        ++sp;
        go(first0 ? c0 : c1, w, pos, depth);
        continue;
      }
      if (hit0 || hit1) {
        go(hit0 ? c0 : c1, w, pos, depth);
        continue;
      }
    }
    // Pop the nearest pending node that can still hold something closer than the current hit.
    bool found = false;
    const float limit = lsk::widen_distance(hit.t);
    while (sp > 0 && !found) {
      --sp;
      if (stack_t[sp] <= limit) {
        w = stack_w[sp];
        pos = stack_pos[sp];
        depth = stack_depth[sp];
        found = true;
      }
    }
    if (!found) return false;
  }
}

// What the fast path keeps of the object level: the wide trees of the object BVHs (or of the flat
// BVH) and the SoA triangle blocks.  Shared by the tracers of every top level (animation).
template <int K>
struct ObjectPart {
  WideTree<K> tree;
  std::vector<TriBlock> blocks;
};

template <int K>
class WideTracer final : public FastTracer {
 public:
  WideTracer(const Accel& accel) : two_level_(accel.spec.two_level()) {
    const std::vector<uint32_t> none;
    const std::vector<uint32_t>& node_ls = accel.spec.line_space() ? accel.node_ls : none;
    auto part = std::make_shared<ObjectPart<K>>();
    if (two_level_) {
      part->tree = build_wide_tree<K>(accel.nodes, node_ls, accel.object_roots);
      top_ = build_wide_tree<K>(accel.top_nodes, none, {0u});
    } else {
      part->tree = build_wide_tree<K>(accel.nodes, node_ls, {0u});
    }
    // SoA copies of each leaf's triangles, four to a block: offsets first, then filled in parallel.
    size_t total = 0;
    for (WideNode<K>& node : part->tree.nodes)
      for (int lane = 0; lane < WideNode<K>::kLanes; ++lane)
        if (node.count[lane] > 0) {
          node.block[lane] = uint32_t(total);
          total += (node.count[lane] + 3u) / 4u;
        }
    resize_huge(part->blocks, total);  // zeros: lanes past a leaf's count stay 0
    ls::parallel_for(size_t(0), part->tree.nodes.size(), [&](size_t n) {
      const WideNode<K>& node = part->tree.nodes[n];
      for (int lane = 0; lane < WideNode<K>::kLanes; ++lane)
        for (uint32_t k = 0; k < node.count[lane]; ++k) {
          const lsk::Triangle& t = accel.tris[node.first[lane] + k];
          TriBlock& block = part->blocks[node.block[lane] + k / 4u];
          const glm::vec4* v[3] = {&t.v0, &t.v1, &t.v2};
          for (int i = 0; i < 3; ++i)
            for (int a = 0; a < 3; ++a) block.v[i][a][k % 4u] = (*v[i])[a];
        }
    });
    part_ = std::move(part);
    blocks_ = part_->blocks.data();
  }

  // The object part of `other`, a new wide top tree over accel.top_nodes.
  WideTracer(const WideTracer& other, const Accel& accel)
      : two_level_(other.two_level_), part_(other.part_), blocks_(other.blocks_),
        top_(build_wide_tree<K>(accel.top_nodes, {}, {0u})) {}

  std::shared_ptr<const FastTracer> with_top_level(const Accel& accel) const override {
    if (!two_level_) return std::make_shared<WideTracer>(*this);
    return std::make_shared<WideTracer>(*this, accel);
  }
  const void* object_part() const override { return part_.get(); }

  void trace(lsk::TraceContext& c, const lsk::Ray* rays, Hit* hits, size_t count, bool any_hit) const override {
    if (two_level_)
      for (size_t i = 0; i < count; ++i) hits[i] = trace_two_level(c, rays[i], any_hit);
    else
      for (size_t i = 0; i < count; ++i) hits[i] = trace_flat(c, rays[i], any_hit);
  }

  size_t bytes() const override { return part_->tree.bytes() + top_.bytes() + part_->blocks.size() * sizeof(TriBlock); }
  int width() const override { return 1 << K; }

 private:
  // lsk::TraceContext::trace_bvh on the wide tree.
  bool trace_bvh(lsk::TraceContext& c, uint root, const vec3& origin, const vec3& dir, float tmin, uint instance,
                 bool any_hit, bool use_ls, Hit& hit, uint& hit_prim) const {
    const lsk::TriRay tri_ray = lsk::make_tri_ray(origin, dir);
    const vec3 inv_dir = lsk::safe_reciprocal(dir);
    float t_root;
    if (!lsk::ray_box(origin, inv_dir, tmin, hit.t, c.nodes[root].lo, c.nodes[root].hi, t_root)) return false;
    auto visit = [&](uint ls, bool leaf, uint first, uint count, uint block) {
      if (use_ls && ls != LS_INVALID) {
        const uint answer = c.ls_lookup(ls, origin, dir, inv_dir, tmin, instance, hit, hit_prim);
        if (answer == lsk::TraceContext::LS_ACCEPTED && any_hit) return Visit::Stop;
        if (answer != lsk::TraceContext::LS_FALLBACK) return Visit::Skip;
      }
      if (!leaf) return Visit::Descend;
      const bool stop = block == LS_INVALID ? c.trace_leaf(first, count, tri_ray, tmin, instance, any_hit, hit, hit_prim)
                                            : trace_leaf(c, block, first, count, tri_ray, tmin, instance, any_hit, hit, hit_prim);
      return stop ? Visit::Stop : Visit::Skip;
    };
    const uint w = part_->tree.wide_of[root];
    if (w == LS_INVALID) {  // a root that is a leaf has no wide node
      const lsk::BvhNode& node = c.nodes[root];
      return visit(use_ls ? c.node_ls[root] : LS_INVALID, true, node.first, node.count, LS_INVALID) == Visit::Stop;
    }
    auto leaf_block = [&](uint block) { return reinterpret_cast<const char*>(&blocks_[block]); };
    return walk(part_->tree, w, make_box_ray(origin, inv_dir), tmin, hit, visit, leaf_block);
  }

  Hit trace_flat(lsk::TraceContext& c, const lsk::Ray& ray, bool any_hit) const {
    Hit hit = lsk::empty_hit(ray);
    uint prim = LS_INVALID;
    trace_bvh(c, 0u, ray.origin, ray.dir, ray.tmin, LS_INVALID, any_hit, c.ls_enabled != 0u, hit, prim);
    return lsk::finish_hit(hit);
  }

  Hit trace_two_level(lsk::TraceContext& c, const lsk::Ray& ray, bool any_hit) const {
    Hit hit = lsk::empty_hit(ray);
    uint prim = LS_INVALID;
    const vec3 inv_dir = lsk::safe_reciprocal(ray.dir);
    float t_root;
    if (!lsk::ray_box(ray.origin, inv_dir, ray.tmin, hit.t, c.top_nodes[0].lo, c.top_nodes[0].hi, t_root))
      return lsk::finish_hit(hit);
    const bool use_ls = c.ls_enabled != 0u;
    auto visit = [&](uint, bool leaf, uint first, uint count, uint) {
      if (!leaf) return Visit::Descend;
      for (uint i = first; i < first + count; ++i) {
        const lsk::InstanceRecord& rec = c.instances[i];
        vec3 o;
        vec3 d;
        c.instance_ray(rec, ray.origin, ray.dir, o, d);
        if (trace_bvh(c, rec.root, o, d, ray.tmin, rec.instance, any_hit, use_ls, hit, prim)) return Visit::Stop;
      }
      return Visit::Skip;
    };
    const uint w = top_.wide_of[0];
    if (w == LS_INVALID)
      visit(LS_INVALID, true, c.top_nodes[0].first, c.top_nodes[0].count, LS_INVALID);
    else
      walk(top_, w, make_box_ray(ray.origin, inv_dir), ray.tmin, hit, visit, [](uint) { return static_cast<const char*>(nullptr); });
    return lsk::finish_hit(hit);
  }

  // lsk::TraceContext::trace_leaf with the four-lane filter in front: the triangles it cannot rule
  // out go through the kernel's ray_triangle and offer_hit in the leaf's order, as in the reference.
  bool trace_leaf(lsk::TraceContext& c, uint block, uint first, uint count, const lsk::TriRay& tri_ray, float tmin,
                  uint instance, bool any_hit, Hit& hit, uint& hit_prim) const {
    for (uint b = 0; b < count; b += 4u) {
      unsigned maybe = maybe_hit_lanes(blocks_[block + b / 4u], tri_ray);
      if (count - b < 4u) maybe &= (1u << (count - b)) - 1u;
      while (maybe != 0u) {
        const uint i = first + b + uint(std::countr_zero(maybe));
        maybe &= maybe - 1u;
        const TriBlock& blk = blocks_[block + b / 4u];
        const uint l = i - first - b;
        // The block holds the very floats of tris[i]: no second memory stream for the survivors.
        const vec3 p0(blk.v[0][0][l], blk.v[0][1][l], blk.v[0][2][l]);
        const vec3 p1(blk.v[1][0][l], blk.v[1][1][l], blk.v[1][2][l]);
        const vec3 p2(blk.v[2][0][l], blk.v[2][1][l], blk.v[2][2][l]);
        float t;
        float u;
        float v;
        if (lsk::ray_triangle(tri_ray, tmin, hit.t, p0, p1, p2, t, u, v)) {
          const uint inst = instance == LS_INVALID ? c.tri_instances[i] : instance;
          if (lsk::offer_hit(t, u, v, inst, c.tri_ids[i], hit)) {
            hit_prim = i;
            if (any_hit) return true;
          }
        }
      }
    }
    return false;
  }

  bool two_level_;
  std::shared_ptr<const ObjectPart<K>> part_;
  const TriBlock* blocks_ = nullptr;  // part_->blocks.data(): one load less on the hot path
  WideTree<K> top_;
};

}  // namespace

std::shared_ptr<const FastTracer> make_fast_tracer(const Accel& accel, int width) {
  if (width == 8) return std::make_shared<WideTracer<3>>(accel);
  if (width == 4) return std::make_shared<WideTracer<2>>(accel);
  throw InputError("wide BVH width must be 4 or 8, not " + std::to_string(width));
}

}  // namespace ls
