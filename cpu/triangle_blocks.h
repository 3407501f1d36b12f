// The fast path's triangles: each BVH leaf's triangles copied into blocks of four in SoA layout, and
// the watertight test (common/kernels/ray_triangle.h) run on a block four lanes at a time.
//
// The SIMD part is the kernel's first half (ray_triangle_edges) — translate, power-of-two rescale
// with its flush-to-zero rule, shear, edge functions — with the same operations lane by lane, hence
// the same values.  A lane whose edge signs reject the triangle is dropped; a lane with a zero edge
// function (the kernel recomputes those in double) goes through the whole scalar kernel; every other
// lane is finished by the kernel's own second half (ray_triangle_finish) on the lane's values.  So a
// hit's t, u and v are the kernel's bit for bit, and lanes are offered in the leaf's order.
#pragma once

#include "simd.h"
#include "trace_context.h"

#include <bit>
#include <cstdint>
#include <vector>

namespace ls {

// Four triangles of a leaf: v[vertex][axis][lane], and each lane's index into tris[] (LS_INVALID
// past the leaf's end, where the vertices are 0).
struct alignas(16) TriBlock {
  float v[3][3][4];
  uint32_t prim[4];
};

// The blocks of every leaf of one BVH array, in leaf order; a leaf of n triangles has (n + 3) / 4
// consecutive blocks starting at block_of[leaf].
struct TriangleBlocks {
  std::vector<TriBlock> blocks;
  std::vector<uint32_t> block_of;  // per BVH node: its first block (leaves), LS_INVALID (inner nodes)
  size_t bytes() const { return blocks.size() * sizeof(TriBlock) + block_of.size() * sizeof(uint32_t); }
};

TriangleBlocks build_triangle_blocks(const std::vector<lsk::BvhNode>& nodes, const std::vector<lsk::Triangle>& tris);

namespace block_lanes {

// lsk::scale_pow2(x, e) lane by lane for e in [-126, 126] (what unit_exponent returns): x * 2^e is
// exact unless the result would be denormal, where the kernel flushes to a signed zero instead; a
// zero, an infinity or a NaN stays itself.  The kernel's two half-steps give the same exact product.
LS_ALWAYS_INLINE Float4 scale_pow2(const Float4& x, const Int4& e, const Float4& pow2_e) {
  const Int4 field = (xsimd::bitwise_cast<Int4>(x) >> 23) & Int4(255);
  const auto flush = ((field - Int4(127) + e) < Int4(-126)) && (field != Int4(255));
  const Int4 bits = xsimd::select(flush, xsimd::bitwise_cast<Int4>(x * Float4(0.0f)), xsimd::bitwise_cast<Int4>(x * pow2_e));
  return xsimd::bitwise_cast<Float4>(bits);
}

LS_ALWAYS_INLINE Float4 max_abs(const Float4& x, const Float4& y, const Float4& z) {
  return glm_max(glm_max(xsimd::abs(x), xsimd::abs(y)), xsimd::abs(z));
}

}  // namespace block_lanes

// ray_triangle_edges on the four lanes of a block.  Returns the lanes to look at further: `full`
// (a zero edge function: the scalar kernel decides) and `finish` (signs that do not reject: finish
// with the lane's edges).  Lanes whose vertices all sit on the origin are in neither (the kernel
// rejects them before computing edges: their edges are 0, so they land in `full`, which rejects).
struct BlockEdges {
  alignas(16) float a[3][4];  // per axis, per lane: p0 - origin scaled by 2^ks
  alignas(16) int32_t ks[4];
  alignas(16) float eu[4];
  alignas(16) float ev[4];
  alignas(16) float ew[4];
  unsigned full = 0;
  unsigned finish = 0;
};

LS_ALWAYS_INLINE void block_edges(const TriBlock& block, const lsk::TriRay& r, BlockEdges& out) {
  using namespace block_lanes;
  Float4 d[3][3];  // translated vertices: d[vertex][axis]
  for (int k = 0; k < 3; ++k)
    for (int a = 0; a < 3; ++a) d[k][a] = Float4::load_aligned(block.v[k][a]) - Float4(r.origin[a]);
  const Float4 m = glm_max(glm_max(max_abs(d[0][0], d[0][1], d[0][2]), max_abs(d[1][0], d[1][1], d[1][2])),
                           max_abs(d[2][0], d[2][1], d[2][2]));
  // unit_exponent(m) = clamp(-float_exponent(m), -126, 126); lanes with m == 0 end as zero edges.
  const Int4 neg_exp = Int4(127) - ((xsimd::bitwise_cast<Int4>(m) >> 23) & Int4(255));
  const Int4 ks = xsimd::select(neg_exp > Int4(126), Int4(126), xsimd::select(neg_exp < Int4(-126), Int4(-126), neg_exp));
  const Float4 pow2_ks = xsimd::bitwise_cast<Float4>((ks + Int4(127)) << 23);
  Float4 sx[3];
  Float4 sy[3];
  const Float4 shear_x(r.sx);
  const Float4 shear_y(r.sy);
  for (int k = 0; k < 3; ++k) {
    const Float4 px = scale_pow2(d[k][r.kx], ks, pow2_ks);
    const Float4 py = scale_pow2(d[k][r.ky], ks, pow2_ks);
    const Float4 pz = scale_pow2(d[k][r.kz], ks, pow2_ks);
    if (k == 0) {
      px.store_aligned(out.a[r.kx]);
      py.store_aligned(out.a[r.ky]);
      pz.store_aligned(out.a[r.kz]);
    }
    sx[k] = px - shear_x * pz;
    sy[k] = py - shear_y * pz;
  }
  const Float4 eu = sx[2] * sy[1] - sy[2] * sx[1];
  const Float4 ev = sx[0] * sy[2] - sy[0] * sx[2];
  const Float4 ew = sx[1] * sy[0] - sy[1] * sx[0];
  const Float4 zero(0.0f);
  const auto any_zero = (eu == zero) || (ev == zero) || (ew == zero);
  const auto rejected = ((eu < zero) || (ev < zero) || (ew < zero)) && ((eu > zero) || (ev > zero) || (ew > zero));
  out.full = lane_bits(any_zero);
  out.finish = lane_bits(!any_zero && !rejected);
  if (out.finish != 0u) {
    ks.store_aligned(out.ks);
    eu.store_aligned(out.eu);
    ev.store_aligned(out.ev);
    ew.store_aligned(out.ew);
  }
}

// lsk::TraceContext::trace_leaf over a leaf's blocks: the leaf's `count` triangles from block
// `first_block` on, tested and offered in the leaf's order.  Returns true when any_hit is set and a
// hit was found (the caller stops).  Flattened: the kernel's halves are inlined into it.
[[gnu::flatten]] inline bool trace_blocks(const lsk::TraceContext& c, const TriBlock* blocks, uint32_t first_block, uint32_t count,
                         const lsk::TriRay& tri_ray, float tmin, uint32_t instance, bool any_hit, lsk::Hit& hit,
                         uint32_t& hit_prim) {
  BlockEdges e;
  for (uint32_t b = 0; b < count; b += 4u) {
    const TriBlock& blk = blocks[first_block + b / 4u];
    block_edges(blk, tri_ray, e);
    unsigned lanes = e.full | e.finish;
    if (count - b < 4u) lanes &= (1u << (count - b)) - 1u;
    while (lanes != 0u) {
      const unsigned l = unsigned(std::countr_zero(lanes));
      lanes &= lanes - 1u;
      const lsk::vec3 p0(blk.v[0][0][l], blk.v[0][1][l], blk.v[0][2][l]);
      const lsk::vec3 p1(blk.v[1][0][l], blk.v[1][1][l], blk.v[1][2][l]);
      const lsk::vec3 p2(blk.v[2][0][l], blk.v[2][1][l], blk.v[2][2][l]);
      float t;
      float u;
      float v;
      bool hits;
      if (e.full >> l & 1u) {
        hits = lsk::ray_triangle(tri_ray, tmin, hit.t, p0, p1, p2, t, u, v);
      } else {
        lsk::TriEdges edges;
        edges.a = lsk::vec3(e.a[0][l], e.a[1][l], e.a[2][l]);
        edges.ks = e.ks[l];
        edges.eu = e.eu[l];
        edges.ev = e.ev[l];
        edges.ew = e.ew[l];
        edges.pad = 0.0f;
        hits = lsk::ray_triangle_finish(tri_ray, tmin, hit.t, p0, p1, p2, edges, t, u, v);
      }
      if (!hits) continue;
      const uint32_t i = blk.prim[l];
      const uint32_t inst = instance == lsk::LS_INVALID ? c.tri_instances[i] : instance;
      if (lsk::offer_hit(t, u, v, inst, c.tri_ids[i], hit)) {
        hit_prim = i;
        if (any_hit) return true;
      }
    }
  }
  return false;
}

}  // namespace ls
