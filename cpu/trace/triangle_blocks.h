// The fast path's triangles: each BVH leaf's triangles copied into blocks of four in SoA layout, and
// the watertight test (common/kernels/ray_triangle.h) run on a block four lanes at a time.
//
// The SIMD part is the kernel's first half (ray_triangle_edges) — translate, power-of-two rescale
// with its flush-to-zero rule, shear, edge functions — and the distance of its second half
// (ray_triangle_plane: det, t from the triangle's plane normal, which the block keeps, and the
// interval test), with the same operations lane by lane, hence the same values.  A lane whose edge
// signs reject the triangle is dropped; a lane with a zero edge function (the kernel recomputes those
// in double) goes through the whole scalar kernel; a lane whose t lies in the interval gets the
// kernel's weights.  So a hit's t, u and v are the kernel's bit for bit, and lanes are offered in the
// leaf's order.
#pragma once

#include "common/structure/trace_context.h"
#include "cpu/trace/simd.h"

#include <algorithm>
#include <bit>
#include <cstdint>
#include <limits>
#include <vector>

namespace ls {

// Four triangles of a leaf: v[vertex][axis][lane], the plane normals n[axis][lane] and each lane's
// index into tris[] (LS_INVALID past the leaf's end, where the vertices are 0).  A *lane index* is
// block * 4 + lane.
struct alignas(16) TriBlock {
  float v[3][3][4];
  float n[3][4];
  uint32_t prim[4];
};

// The triangles of one BVH array in blocks.  The leaves of each exact wide node share its blocks:
// those of at most four triangles packed first fit, largest first, so that none straddles two
// blocks and a ray that hits two of them may find one block loaded already; a longer leaf gets
// blocks of its own.  A leaf's child becomes its first lane index.  Every binary leaf outside the
// exact leaves (the treelets' leaves above the entries) gets blocks of its own.  A binary leaf
// inside an exact leaf is a run of that leaf's lanes: its triangles stay in the builder's order
// either way.
struct TriangleBlocks {
  std::vector<TriBlock> blocks;
  std::vector<uint32_t> lane_of;  // per binary node: a leaf's first lane index; LS_INVALID for inner nodes
  size_t bytes() const { return blocks.size() * sizeof(TriBlock) + lane_of.size() * sizeof(uint32_t); }
};

template <int W>
struct ExactWideTree;
template <int W>  // 4 or 8
TriangleBlocks build_triangle_blocks(const std::vector<lsk::BvhNode>& nodes, const std::vector<lsk::Triangle>& tris,
                                     ExactWideTree<W>& exact);

namespace block_lanes {

// lsk::scale_pow2(x, e) lane by lane for e in [-126, 126] (what unit_exponent returns): x * 2^e,
// exact, unless the result would be denormal, where the kernel flushes to a signed zero instead
// (biased exponent field < 1 - e; an infinity or a NaN, field 255, never is).  The kernel's two
// half-steps give the same exact product.  A zero gives a zero of its sign either way.
LS_ALWAYS_INLINE Float4 scale_pow2(const Float4& x, const Int4& one_minus_e, const Float4& pow2_e) {
  const Int4 bits = xsimd::bitwise_cast<Int4>(x);
  const Int4 field = (bits >> 23) & Int4(255);
  const Int4 scaled = xsimd::bitwise_cast<Int4>(x * pow2_e);
  return xsimd::bitwise_cast<Float4>(xsimd::select(field < one_minus_e, bits & Int4(int32_t(0x80000000u)), scaled));
}

// lsk::triangle_plane_normal on the four lanes of a block whose vertices are set, into block.n: the
// kernel's operations lane by lane (edges from p0, the largest |coordinate| of the two, unit_exponent
// on its exponent field, the four-lane scale_pow2, glm's cross).  A lane with an infinite or NaN
// edge takes the kernel itself (max and the scale would not see a NaN the same way).  Unused lanes
// (zero vertices) get a zero normal, as the kernel gives them.
LS_ALWAYS_INLINE void plane_normals(TriBlock& block) {
  const Float4 magnitude = xsimd::bitwise_cast<Float4>(Int4(0x7FFFFFFF));
  Float4 f1[3];
  Float4 f2[3];
  Float4 m(0.0f);
  auto finite = xsimd::batch_bool<float, Simd4Arch>(true);
  for (int a = 0; a < 3; ++a) {
    const Float4 p0 = Float4::load_aligned(block.v[0][a]);
    f1[a] = Float4::load_aligned(block.v[1][a]) - p0;
    f2[a] = Float4::load_aligned(block.v[2][a]) - p0;
    const Float4 abs1 = f1[a] & magnitude, abs2 = f2[a] & magnitude;
    m = glm_max(m, glm_max(abs1, abs2));  // max is exact: any order
    const Float4 inf(std::numeric_limits<float>::infinity());
    finite = finite && abs1 < inf && abs2 < inf;  // false for a NaN too
  }
  // unit_exponent(m): clamp(127 - field, -126, 126) (a denormal m has field 0).  Its 0 for m == 0
  // is not needed: every edge coordinate is then a signed zero, which any scale leaves as it is.
  const Int4 field = xsimd::bitwise_cast<Int4>(m) >> 23;
  Int4 e = Int4(127) - field;
  e = xsimd::select(e > Int4(126), Int4(126), xsimd::select(e < Int4(-126), Int4(-126), e));
  const Int4 one_minus_e = Int4(1) - e;
  const Float4 pow2_e = xsimd::bitwise_cast<Float4>((e + Int4(127)) << 23);
  for (int a = 0; a < 3; ++a) {
    f1[a] = scale_pow2(f1[a], one_minus_e, pow2_e);
    f2[a] = scale_pow2(f2[a], one_minus_e, pow2_e);
  }
  (f1[1] * f2[2] - f2[1] * f1[2]).store_aligned(block.n[0]);
  (f1[2] * f2[0] - f2[2] * f1[0]).store_aligned(block.n[1]);
  (f1[0] * f2[1] - f2[0] * f1[1]).store_aligned(block.n[2]);
  for (unsigned rest = ~lane_bits(finite) & 15u; rest != 0u; rest &= rest - 1u) {
    const unsigned l = unsigned(std::countr_zero(rest));
    auto vertex = [&](int p) { return lsk::vec3(block.v[p][0][l], block.v[p][1][l], block.v[p][2][l]); };
    const lsk::vec3 n = lsk::triangle_plane_normal(vertex(0), vertex(1), vertex(2));
    for (int a = 0; a < 3; ++a) block.n[a][l] = n[a];
  }
}

}  // namespace block_lanes

// ray_triangle_edges on the four lanes of a block.  Returns the lanes to look at further: `full`
// (a zero edge function: the scalar kernel decides) and `finish` (signs that do not reject: finish
// with the lane's edges).  Lanes whose vertices all sit on the origin are in neither (the kernel
// rejects them before computing edges: their edges are 0, so they land in `full`, which rejects).
struct BlockEdges {
  alignas(16) float a[3][4];  // per sheared axis (kx, ky, kz), per lane: p0 - origin scaled by 2^ks
  alignas(16) int32_t ks[4];
  alignas(16) float eu[4];
  alignas(16) float ev[4];
  alignas(16) float ew[4];
  alignas(16) float t[4];  // block_distances: the kernel's t before positive_zero
  unsigned full = 0;
  unsigned finish = 0;
};

// The ray as block_edges reads it, made once per ray from its TriRay: the origin and the shear
// broadcast into lanes, the origin in the sheared axes' order (kx, ky, kz).
struct BlockRay {
  lsk::TriRay tri;
  Float4 origin[3];  // origin component of sheared axis a, in every lane
  Float4 shear_x;
  Float4 shear_y;
  Float4 dir[3];     // the scaled direction (tri.dir), x, y, z, in every lane
  uint32_t axis[3];  // kx, ky, kz
  uint32_t row_of[3];  // the sheared axis of x, y and z (axis[row_of[i]] == i)
};

// b for a ray: b.tri is lsk::make_tri_ray(origin, dir), bit for bit (the same operations: the
// direction rescaled four lanes at once by block_lanes::scale_pow2, the three quotients of the shear
// in one division), and the lanes broadcast from it.  The kernel's own version picks components by
// selects, and its result was copied about: this saves 10-11 instructions a ray (callgrind, bvh).
LS_ALWAYS_INLINE void make_block_ray(const lsk::vec3& origin, const lsk::vec3& dir, BlockRay& b) {
  lsk::TriRay& r = b.tri;
  const int e = lsk::unit_exponent(lsk::max_abs(dir));
  alignas(16) float d[4] = {dir.x, dir.y, dir.z, 0.0f};
  block_lanes::scale_pow2(Float4::load_aligned(d), Int4(1 - e), Float4(lsk::pow2(e))).store_aligned(d);
  const float ax = std::abs(d[0]);
  const float ay = std::abs(d[1]);
  const float az = std::abs(d[2]);
  // The kernel's choice, ax >= ay ? (ax >= az ? 0 : 2) : (ay >= az ? 1 : 2), read from a table by
  // the three comparisons, and its winding swap by arithmetic: as branches they were mispredicted
  // about once a ray.
  static constexpr uint8_t kz_of[8] = {2, 1, 2, 1, 2, 2, 0, 0};  // index: (ax >= ay) * 4 + (ax >= az) * 2 + (ay >= az)
  const uint32_t kz = kz_of[unsigned(ax >= ay) * 4u + unsigned(ax >= az) * 2u + unsigned(ay >= az)];
  const bool swap = d[kz] < 0.0f;  // keep the winding, as the kernel does
  const uint32_t kx = (kz + 1u + uint32_t(swap)) % 3u;
  const uint32_t ky = (kz + 2u - uint32_t(swap)) % 3u;
  alignas(16) float shear[4] = {d[kx], d[ky], 1.0f, 1.0f};
  (Float4::load_aligned(shear) / Float4(d[kz])).store_aligned(shear);  // sx, sy, sz
  r.origin = origin;
  r.dir_exp = e;
  r.dir = lsk::vec3(d[0], d[1], d[2]);
  r.kx = kx;
  r.ky = ky;
  r.kz = kz;
  r.sx = shear[0];
  r.sy = shear[1];
  r.sz = shear[2];
  r.pad0 = 0.0f;
  r.pad1 = 0.0f;
  r.pad2 = 0.0f;
  b.axis[0] = kx;
  b.axis[1] = ky;
  b.axis[2] = kz;
  const float o[3] = {origin.x, origin.y, origin.z};  // indexed in memory, not through glm's switch
  for (uint32_t a = 0; a < 3; ++a) {
    b.origin[a] = Float4(o[b.axis[a]]);
    b.dir[a] = Float4(d[a]);
    b.row_of[b.axis[a]] = a;
  }
  b.shear_x = Float4(shear[0]);
  b.shear_y = Float4(shear[1]);
}

// The vertices are read in the ray's axis order (kx, ky, kz) straight from the block, so no axis is
// picked from registers at run time.  The maximum over the nine coordinates does not depend on that
// order (max is exact); only a NaN could make it, and a NaN coordinate rejects the lane whatever
// the scale (its edge functions and t are NaN), as it does in the kernel.
LS_ALWAYS_INLINE void block_edges(const TriBlock& block, const BlockRay& r, BlockEdges& out) {
  using namespace block_lanes;
  const Float4 magnitude = xsimd::bitwise_cast<Float4>(Int4(0x7FFFFFFF));  // |x| = x & magnitude
  Float4 d[3][3];  // translated vertices: d[vertex][sheared axis]
  Float4 largest[3];  // per vertex, the largest and the smallest |coordinate|: each vertex's
  Float4 least[3];    // magnitudes die here, not after both trees (fewer registers spilled)
  for (int k = 0; k < 3; ++k) {
    Float4 abs_d[3];
    for (int a = 0; a < 3; ++a) {
      d[k][a] = Float4::load_aligned(block.v[k][r.axis[a]]) - r.origin[a];
      abs_d[a] = d[k][a] & magnitude;
    }
    largest[k] = glm_max(glm_max(abs_d[0], abs_d[1]), abs_d[2]);
    least[k] = glm_min(glm_min(abs_d[0], abs_d[1]), abs_d[2]);
  }
  const Float4 m = glm_max(glm_max(largest[0], largest[1]), largest[2]);
  // unit_exponent(m) = clamp(-float_exponent(m), -126, 126), with the clamp done on m: its exponent
  // field clamped to [1, 253] is m clamped to [2^-126, 2^126] (m >= 0), two float ops where SSE2 has
  // no integer min or max.  Lanes with m == 0 end as zero edges; a NaN m (a NaN coordinate) gets
  // some scale, which does not matter (above).
  const Float4 m_clamped = glm_min(glm_max(m, Float4(0x1p-126f)), Float4(0x1p126f));
  const Int4 field = xsimd::bitwise_cast<Int4>(m_clamped) >> 23;  // [1, 253] (255 for a NaN): no sign bit
  const Int4 ks = Int4(127) - field;
  const Float4 pow2_ks = xsimd::bitwise_cast<Float4>((Int4(254) - field) << 23);
  // A flush to zero needs a coordinate below 2^(-126 - ks); where none is, the product alone is exact.
  const Int4 one_minus_ks = Int4(1) - ks;
  const Float4 smallest = glm_min(glm_min(least[0], least[1]), least[2]);
  const bool may_flush = lane_bits(((xsimd::bitwise_cast<Int4>(smallest) >> 23) < one_minus_ks)) != 0u;
  // The rest on the scaled vertices p[vertex][sheared axis]: written once, inlined into both branches
  // below, so that p stays in registers (where the two joined, GCC stored all nine to the stack).
  auto edges = [&](const Float4(&p)[3][3]) LS_ALWAYS_LAMBDA {
    for (int a = 0; a < 3; ++a) p[0][a].store_aligned(out.a[a]);
    Float4 sx[3];
    Float4 sy[3];
    for (int k = 0; k < 3; ++k) {
      sx[k] = p[k][0] - r.shear_x * p[k][2];
      sy[k] = p[k][1] - r.shear_y * p[k][2];
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
  };
  if (may_flush) {
    Float4 p[3][3];
    for (int k = 0; k < 3; ++k)
      for (int a = 0; a < 3; ++a) p[k][a] = scale_pow2(d[k][a], one_minus_ks, pow2_ks);
    edges(p);
  } else {
    Float4 p[3][3];
    for (int k = 0; k < 3; ++k)
      for (int a = 0; a < 3; ++a) p[k][a] = d[k][a] * pow2_ks;
    edges(p);
  }
}

// The rest of ray_triangle_plane on the `lanes` of a block that block_edges left to finish, four
// at a time with the kernel's operations lane by lane: det = eu + ev + ew, t = dot(n, a) / dot(n, dir)
// summed in x, y, z order, rescaled by 2^(dir_exp - ks).  Returns the lanes the kernel does not
// reject before its weights (det and dot(n, dir) not zero, t in [tmin, tmax]); their t (before
// positive_zero) is in e.t.  The rescale sets the exponent field where the result stays normal; a
// lane where it would not (a denormal quotient, an exponent off the range) takes the kernel's own
// scale_pow2.
LS_ALWAYS_INLINE unsigned block_distances(const TriBlock& block, const BlockRay& r, BlockEdges& e, float tmin, float tmax,
                                          unsigned lanes) {
  const Float4 det = (Float4::load_aligned(e.eu) + Float4::load_aligned(e.ev)) + Float4::load_aligned(e.ew);
  const Float4 nx = Float4::load_aligned(block.n[0]);
  const Float4 ny = Float4::load_aligned(block.n[1]);
  const Float4 nz = Float4::load_aligned(block.n[2]);
  const Float4 tn = (nx * Float4::load_aligned(e.a[r.row_of[0]]) + ny * Float4::load_aligned(e.a[r.row_of[1]])) +
                    nz * Float4::load_aligned(e.a[r.row_of[2]]);
  const Float4 td = (nx * r.dir[0] + ny * r.dir[1]) + nz * r.dir[2];
  const Float4 quotient = tn / td;
  const Int4 shift = Int4(r.tri.dir_exp) - Int4::load_aligned(e.ks);
  const Int4 bits = xsimd::bitwise_cast<Int4>(quotient);
  const Int4 field = (bits >> 23) & Int4(255);
  const Int4 moved = field + shift;
  Float4 t = xsimd::bitwise_cast<Float4>((bits & Int4(int32_t(0x807FFFFFu))) | (moved << 23));
  // Both fields in [1, 254]: field - 1 and moved - 1 in [0, 253], so none of the four below is negative.
  const Int4 f1 = field - Int4(1);
  const Int4 m1 = moved - Int4(1);
  const unsigned slow = lanes & lane_bits((f1 | m1 | (Int4(253) - f1) | (Int4(253) - m1)) < Int4(0));
  t.store_aligned(e.t);
  if (slow != 0u) {
    alignas(16) float q[4];
    alignas(16) int32_t k[4];
    quotient.store_aligned(q);
    shift.store_aligned(k);
    for (unsigned rest = slow; rest != 0u; rest &= rest - 1u) {
      const unsigned l = unsigned(std::countr_zero(rest));
      e.t[l] = lsk::scale_pow2(q[l], k[l]);
    }
    t = Float4::load_aligned(e.t);
  }
  const Float4 zero(0.0f);
  return lanes & lane_bits((det != zero) && (td != zero) && (t >= Float4(tmin)) && (t <= Float4(tmax)));
}

// lsk::TraceContext::trace_leaf over blocks: the `count` triangles from lane index `lane` on, tested
// and offered in that order.  Returns true when any_hit is set and a hit was found (the caller
// stops).  Flattened: the kernel's halves are inlined into it.
[[gnu::flatten]] inline bool trace_blocks(const lsk::TraceContext& c, const TriBlock* blocks, uint32_t lane, uint32_t count,
                                          const BlockRay& block_ray, float tmin, uint32_t instance, bool any_hit,
                                          lsk::Hit& hit, uint32_t& hit_prim) {
  const lsk::TriRay& tri_ray = block_ray.tri;
  BlockEdges e;
  for (uint32_t at = lane, end = lane + count; at < end; at = (at | 3u) + 1u) {
    const TriBlock& blk = blocks[at / 4u];
    block_edges(blk, block_ray, e);
    const unsigned in_leaf = (15u << (at % 4u)) & ((1u << std::min(end - (at & ~3u), 4u)) - 1u);  // no branch
    const unsigned finish = e.finish & in_leaf;
    unsigned lanes = (e.full & in_leaf) | (finish != 0u ? block_distances(blk, block_ray, e, tmin, hit.t, finish) : 0u);
    while (lanes != 0u) {
      const unsigned l = unsigned(std::countr_zero(lanes));
      lanes &= lanes - 1u;
      float t;
      float u;
      float v;
      bool hits;
      if (e.full >> l & 1u) {
        const lsk::vec3 p0(blk.v[0][0][l], blk.v[0][1][l], blk.v[0][2][l]);
        const lsk::vec3 p1(blk.v[1][0][l], blk.v[1][1][l], blk.v[1][2][l]);
        const lsk::vec3 p2(blk.v[2][0][l], blk.v[2][1][l], blk.v[2][2][l]);
        hits = lsk::ray_triangle(tri_ray, tmin, hit.t, p0, p1, p2, t, u, v);
      } else {  // block_distances kept it for the hit at the block's start; the hit may be closer now
        hits = e.t[l] <= hit.t;
        if (hits) {  // the kernel's weights
          const float det = (e.eu[l] + e.ev[l]) + e.ew[l];
          t = lsk::positive_zero(e.t[l]);
          u = e.ev[l] / det;
          v = e.ew[l] / det;
        }
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
