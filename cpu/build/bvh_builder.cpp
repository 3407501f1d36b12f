// The binned SAH builder.  Its trees are bit for bit those of the plain formulation (bin the
// centroids, sweep every boundary, std::partition, recurse; tests/test_bvh.cpp recomputes every
// split by brute force): the speed comes from doing the same work with less memory traffic —
// primitives moved with their boxes, each side's bounds gathered while partitioning, a large range's
// bins initialised up front so that binning has no branch, only occupied bins swept, 4-float SIMD
// for the box arithmetic, small subtrees laid out directly.
#include "cpu/build/bvh_builder.h"

#include "common/base/huge_pages.h"
#include "common/base/interrupt.h"
#include "common/base/parallel.h"
#include "common/structure/accel.h"
#include "cpu/trace/simd.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cmath>
#include <limits>
#include <memory>

namespace ls {
namespace {

constexpr uint32_t kParallelBinning = 4096;  // ranges larger than this are binned in parallel
// Ranges larger than this build their two subtrees as parallel tasks: low enough that a scene of a
// few thousand triangles uses every thread (cornell's 4,026 took 1.0-1.4 ms on one), high enough
// that a task's work dwarfs its scheduling.
constexpr uint32_t kParallelSubtrees = 1024;
constexpr int kMaxBins = 64;
constexpr uint32_t kDenseBinning = 16;  // ranges at least this large initialise all bins (BinSet::make_dense)

// The SAH's half areas are taken in units of a power of two near the range's largest extent (`unit`
// multiplies every coordinate first): scaling by a power of two is exact, so a scene scaled by 2^p
// gets the same costs bit for bit, hence the same tree, and the costs neither overflow (extents
// past 2^63 squared, the count on top) nor fall to subnormals (extents under 2^-63).
float area_unit(const Bounds& b) {
  double extent = 0.0;
  for (int a = 0; a < 3; ++a) extent = std::max(extent, double(b.hi[a]) - double(b.lo[a]));
  if (!(extent > 0.0) || !std::isfinite(extent)) return 1.0f;
  return std::ldexp(1.0f, std::clamp(-std::ilogb(extent), -126, 126));
}

float half_area(const Bounds& b, float unit) {
  if (b.empty()) return 0.0f;
  const glm::vec3 e = b.hi * unit - b.lo * unit;
  return e.x * e.y + e.y * e.z + e.z * e.x;
}

// A node above the serially built subtrees (ranges over kParallelSubtrees), kept until the tree is
// complete and laid out depth first.
struct TempNode {
  Bounds box;
  uint32_t begin = 0, end = 0;
  std::unique_ptr<TempNode> left, right;
  // Or, for a range built serially, its whole subtree already laid out depth first from index 0
  // (inner nodes' `first` relative to that array).
  std::vector<lsk::BvhNode> subtree;
};

// A primitive as the builder moves it: its box and input index side by side, so that binning and
// partitioning read memory in order instead of gathering through an index array.  Its two halves are
// loaded as 4-float batches; `id` sits in lo's fourth lane and is masked off before any arithmetic.
// Plain arrays: an axis chosen at run time is an index, where glm's operator[] is a switch.
struct alignas(16) PrimRef {
  float lo[3];
  uint32_t id;
  float hi[3];
  float zero = 0.0f;
  Float4 lo4() const { return xsimd::bitwise_and(Float4::load_aligned(lo), xyz_mask()); }
  Float4 hi4() const { return Float4::load_aligned(hi); }
  static Float4 xyz_mask() {
    alignas(16) static constexpr int32_t bits[4] = {-1, -1, -1, 0};
    return xsimd::bitwise_cast<Float4>(Int4::load_aligned(bits));
  }
};

// Bounds::centre's arithmetic, 0.5f * (lo + hi), in all lanes at once.
Float4 centre4(const Float4& lo, const Float4& hi) { return Float4(0.5f) * (lo + hi); }

Bounds to_bounds(const Float4& lo, const Float4& hi) {
  alignas(16) float l[4], h[4];
  lo.store_aligned(l);
  hi.store_aligned(h);
  Bounds b;
  b.lo = glm::vec3(l[0], l[1], l[2]);
  b.hi = glm::vec3(h[0], h[1], h[2]);
  return b;
}

// Bounds::grow by a box, lane by lane (glm's min and max, see simd.h).
struct Box4 {
  Float4 lo = Float4(std::numeric_limits<float>::infinity());  // (), not {}: {} is xsimd's lane list
  Float4 hi = Float4(-std::numeric_limits<float>::infinity());
  void grow(const Float4& l, const Float4& h) {
    lo = glm_min(lo, l);
    hi = glm_max(hi, h);
  }
};

// half_area of a box in `unit`s, as the scalar rule: 0 when empty (lo.x > hi.x, which is e.x < 0 of the exact
// difference), else e.x * e.y + e.y * e.z + e.z * e.x of its extent, summed in that order.
float half_area4(const Box4& b, const Float4& unit) {
  const Float4 e = b.hi * unit - b.lo * unit;
  const Float4 products = e * xsimd::swizzle(e, xsimd::batch_constant<xsimd::batch<uint32_t, Simd4Arch>, 1, 2, 0, 3>());
  alignas(16) float ev[4], pv[4];
  e.store_aligned(ev);
  products.store_aligned(pv);
  if (ev[0] < 0.0f) return 0.0f;
  return pv[0] + pv[1] + pv[2];
}

// Per axis and bin, the box and the number of the primitives whose centroid falls in it, for the
// bins set in the axis' `occupied` mask; the others are not initialised (a set is 9 KB, a small range
// touches a few of its bins) until make_dense, after which grow needs no test.
struct BinSet {
  struct alignas(16) Box {
    float lo[4], hi[4];
  };
  std::array<std::array<Box, kMaxBins>, 3> box;
  std::array<std::array<uint32_t, kMaxBins>, 3> count;
  std::array<uint64_t, 3> occupied{};
  bool dense = false;  // every bin below the bin count initialised (make_dense)
  // Grows bin b of axis a, which holds a box (occupied, or initialised empty by make_dense), by a
  // box of n primitives; the caller keeps `occupied`.
  void grow(int a, int b, const Float4& lo, const Float4& hi, uint32_t n) {
    Box& bb = box[a][b];
    glm_min(Float4::load_aligned(bb.lo), lo).store_aligned(bb.lo);
    glm_max(Float4::load_aligned(bb.hi), hi).store_aligned(bb.hi);
    count[a][b] += n;
  }
  void add(int a, int b, const Float4& lo, const Float4& hi, uint32_t n) {
    const uint64_t bit = uint64_t(1) << b;
    if (occupied[a] & bit) return grow(a, b, lo, hi, n);
    // The first: what growing an empty box by it gives (min(+inf, x) is x for every non-NaN x, -0
    // included; scene validation refuses NaN).
    occupied[a] |= bit;
    lo.store_aligned(box[a][b].lo);
    hi.store_aligned(box[a][b].hi);
    count[a][b] = n;
  }
  // Initialises the unoccupied bins below `bins` as empty boxes: the bins of a large range, where a
  // test and branch per axis and primitive costs more than these stores.  Growing an empty box gives
  // the box itself, as add's first store does.
  void make_dense(int bins) {
    const Float4 inf(std::numeric_limits<float>::infinity());
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < bins; ++b)
        if (!(occupied[a] >> b & 1)) {
          inf.store_aligned(box[a][b].lo);
          (-inf).store_aligned(box[a][b].hi);
          count[a][b] = 0;
        }
    dense = true;
  }
  void merge(const BinSet& o) {
    for (int a = 0; a < 3; ++a)
      for (uint64_t m = o.occupied[a]; m; m &= m - 1) {
        const int b = std::countr_zero(m);
        add(a, b, Float4::load_aligned(o.box[a][b].lo), Float4::load_aligned(o.box[a][b].hi), o.count[a][b]);
      }
  }
};

// A range's box and the box of its centroids: what a node needs before it is split.
struct RangeInfo {
  Box4 box4, centroids4;
  void add(const PrimRef& p) {
    const Float4 lo = p.lo4(), hi = p.hi4();
    box4.grow(lo, hi);
    const Float4 c = centre4(lo, hi);
    centroids4.grow(c, c);
  }
  void merge(const RangeInfo& o) {
    box4.grow(o.box4.lo, o.box4.hi);
    centroids4.grow(o.centroids4.lo, o.centroids4.hi);
  }
  Bounds box() const { return to_bounds(box4.lo, box4.hi); }
  Bounds centroids() const { return to_bounds(centroids4.lo, centroids4.hi); }
};

class Builder {
 public:
  Builder(const std::vector<Bounds>& boxes, const BvhBuildOptions& options)
      : options_(options), bins_(std::clamp(options.bins, 2, kMaxBins)) {
    resize_huge(prims_, boxes.size());
    ls::parallel_for(size_t(0), boxes.size(), [&](size_t i) {
      const Bounds& b = boxes[i];
      prims_[i] = PrimRef{{b.lo.x, b.lo.y, b.lo.z}, uint32_t(i), {b.hi.x, b.hi.y, b.hi.z}};
    });
  }

  BvhBuildResult run() {
    const uint32_t n = uint32_t(prims_.size());
    std::unique_ptr<TempNode> root = build(0, n, 0, range_info(0, n));
    BvhBuildResult result;
    reserve_huge(result.nodes, 2 * prims_.size());
    result.nodes.emplace_back();
    flatten(*root, 0, result.nodes);
    resize_huge(result.order, prims_.size());
    ls::parallel_for(size_t(0), prims_.size(), [&](size_t i) { result.order[i] = prims_[i].id; });
    result.max_depth = max_depth_.load();
    return result;
  }

 private:
  RangeInfo range_info(uint32_t begin, uint32_t end) const {
    auto body = [&](const tbb::blocked_range<uint32_t>& r, RangeInfo info) {
      for (uint32_t i = r.begin(); i != r.end(); ++i) info.add(prims_[i]);
      return info;
    };
    if (end - begin <= kParallelBinning) return body(tbb::blocked_range<uint32_t>(begin, end), RangeInfo{});
    return ls::parallel_reduce(tbb::blocked_range<uint32_t>(begin, end, 1024), RangeInfo{}, body,
                               [](RangeInfo a, const RangeInfo& b) { a.merge(b); return a; });
  }

  // The bin of a centroid along an axis; the same formula bins and partitions.
  int bin_of(float c, float lo, float scale) const {
    return std::clamp(int((c - lo) * scale), 0, bins_ - 1);
  }

  void bin_into(BinSet& set, uint32_t begin, uint32_t end, const Bounds& cb, const glm::vec3& scale) const {
    alignas(16) const float lo_lanes[4] = {cb.lo.x, cb.lo.y, cb.lo.z, 0.0f}, scale_lanes[4] = {scale.x, scale.y, scale.z, 0.0f};
    const Float4 lo4 = Float4::load_aligned(lo_lanes), scale4 = Float4::load_aligned(scale_lanes);
    const Int4 zero4(0), last4(bins_ - 1);
    auto each = [&](auto add) LS_ALWAYS_LAMBDA {
      for (uint32_t i = begin; i != end; ++i) {
        const PrimRef& p = prims_[i];
        const Float4 lo = p.lo4(), hi = p.hi4();
        // bin_of on three lanes: the truncation is cvttps's, the clamp the scalar one.
        alignas(16) int32_t b[4];
        const Int4 raw = xsimd::to_int((centre4(lo, hi) - lo4) * scale4);
        xsimd::select(raw > last4, last4, xsimd::select(raw < zero4, zero4, raw)).store_aligned(b);
        for (int a = 0; a < 3; ++a) add(a, b[a], lo, hi);
      }
    };
    if (!set.dense && end - begin >= kDenseBinning) set.make_dense(bins_);
    if (set.dense) {
      uint64_t occupied[3] = {set.occupied[0], set.occupied[1], set.occupied[2]};  // in registers, not memory
      each([&](int a, int b, const Float4& lo, const Float4& hi) LS_ALWAYS_LAMBDA {
        occupied[a] |= uint64_t(1) << b;
        set.grow(a, b, lo, hi, 1);
      });
      for (int a = 0; a < 3; ++a) set.occupied[a] = occupied[a];
    } else
      each([&](int a, int b, const Float4& lo, const Float4& hi) LS_ALWAYS_LAMBDA { set.add(a, b, lo, hi, 1); });
  }

  // Fills `set` (serially for small ranges: no copies of the 5 KB set).
  void bin(BinSet& set, uint32_t begin, uint32_t end, const Bounds& cb, const glm::vec3& scale) const {
    if (end - begin <= kParallelBinning) return bin_into(set, begin, end, cb, scale);
    set = ls::parallel_reduce(
        tbb::blocked_range<uint32_t>(begin, end, 4096), BinSet{},
        [&](const tbb::blocked_range<uint32_t>& r, BinSet part) {
          bin_into(part, r.begin(), r.end(), cb, scale);
          return part;
        },
        [](BinSet a, const BinSet& b) { a.merge(b); return a; });
  }

  // Splits at the object median along the widest centroid axis (ties by index: deterministic).
  uint32_t median_split(uint32_t begin, uint32_t end, const Bounds& cb) {
    const glm::vec3 e = cb.extent();
    const int axis = (e.x >= e.y && e.x >= e.z) ? 0 : (e.y >= e.z ? 1 : 2);
    const uint32_t mid = begin + (end - begin) / 2;
    std::nth_element(prims_.begin() + begin, prims_.begin() + mid, prims_.begin() + end,
                     [&](const PrimRef& a, const PrimRef& b) {
                       const float ca = 0.5f * (a.lo[axis] + a.hi[axis]), cb2 = 0.5f * (b.lo[axis] + b.hi[axis]);
                       return ca < cb2 || (ca == cb2 && a.id < b.id);
                     });
    return mid;
  }

  // Moves the primitives `in_left` accepts before the others, in std::partition's order (the
  // bidirectional swap loop of libstdc++, which the trees documented so far were built with), and
  // gathers each side's RangeInfo on the way: no second pass over the range.
  template <class InLeft>
  uint32_t partition(uint32_t begin, uint32_t end, InLeft in_left, RangeInfo& left, RangeInfo& right) {
    PrimRef* first = prims_.data() + begin;
    PrimRef* last = prims_.data() + end;
    while (true) {
      while (true) {
        if (first == last) return uint32_t(first - prims_.data());
        if (!in_left(*first)) break;
        left.add(*first++);
      }
      --last;
      while (true) {
        if (first == last) {
          right.add(*first);
          return uint32_t(first - prims_.data());
        }
        if (in_left(*last)) break;
        right.add(*last--);
      }
      std::swap(*first, *last);
      left.add(*first++);
      right.add(*last);
    }
  }

  // The SAH split position, or `end` when no split beats a leaf of an acceptable size; `left` and
  // `right` receive the sides' RangeInfo when it splits.
  uint32_t sah_split(uint32_t begin, uint32_t end, const RangeInfo& info, RangeInfo& left, RangeInfo& right) {
    const uint32_t n = end - begin;
    const Bounds cb = info.centroids();
    glm::vec3 scale(0.0f);
    for (int a = 0; a < 3; ++a) {
      const float ext = cb.hi[a] - cb.lo[a];
      scale[a] = ext > 0.0f ? float(bins_) * 0.99999f / ext : 0.0f;
    }
    if (scale == glm::vec3(0.0f)) return end;  // all centroids coincide
    BinSet set;
    bin(set, begin, end, cb, scale);

    const float unit = area_unit(info.box());
    const Float4 unit4(unit);
    float best_cost = std::numeric_limits<float>::infinity();
    int best_axis = -1, best_bin = 0;
    for (int a = 0; a < 3; ++a) {
      if (scale[a] == 0.0f) continue;
      // Boundaries right after an occupied bin, in bin order.  The boundary after an empty bin moves
      // nothing across: it costs what the one before it costs, and the earlier wins the tie, so
      // only occupied bins are swept; the right side of bin[j]'s boundary is bins[j+1..].
      std::array<int, kMaxBins> bins;
      int k = 0;
      for (uint64_t m = set.occupied[a]; m; m &= m - 1) bins[k++] = std::countr_zero(m);
      std::array<float, kMaxBins> right_cost;  // [1, k) written before read
      auto grow = [&](Box4& acc, int bin) {
        acc.grow(Float4::load_aligned(set.box[a][bin].lo), Float4::load_aligned(set.box[a][bin].hi));
      };
      Box4 acc;
      uint32_t count = 0;
      for (int j = k - 1; j > 0; --j) {
        grow(acc, bins[j]);
        count += set.count[a][bins[j]];
        right_cost[j] = half_area4(acc, unit4) * float(count);
      }
      acc = Box4{};
      count = 0;
      for (int j = 0; j + 1 < k; ++j) {
        grow(acc, bins[j]);
        count += set.count[a][bins[j]];
        const float cost = half_area4(acc, unit4) * float(count) + right_cost[j + 1];
        if (cost < best_cost) { best_cost = cost; best_axis = a; best_bin = bins[j]; }
      }
    }
    if (best_axis < 0) return end;
    const float parent_area = half_area(info.box(), unit);
    const float split_cost = parent_area > 0.0f ? options_.traversal_cost + best_cost / parent_area : float(n);
    if (n <= uint32_t(options_.max_leaf_size) && float(n) <= split_cost) return begin;  // a leaf is cheaper
    const float lo = cb.lo[best_axis], sc = scale[best_axis];
    auto in_left = [&](const PrimRef& p) { return bin_of(0.5f * (p.lo[best_axis] + p.hi[best_axis]), lo, sc) <= best_bin; };
    return partition(begin, end, in_left, left, right);
  }

  // Where the range splits: a position in (begin, end), with the sides' RangeInfo, or `begin` when
  // the range stays a leaf.
  uint32_t split(uint32_t begin, uint32_t end, int depth, const RangeInfo& info, RangeInfo& left, RangeInfo& right) {
    int seen = max_depth_.load(std::memory_order_relaxed);
    while (depth > seen && !max_depth_.compare_exchange_weak(seen, depth)) {}
    const uint32_t n = end - begin;
    if (n <= 1) return begin;
    uint32_t mid;
    if (depth >= options_.sah_depth_limit) {
      if (n <= uint32_t(options_.max_leaf_size)) return begin;
      mid = median_split(begin, end, info.centroids());
    } else {
      mid = sah_split(begin, end, info, left, right);
      if (mid == begin) return begin;  // SAH prefers a leaf
      if (mid != end) return mid;      // sides gathered by the partition
      if (n <= uint32_t(options_.max_leaf_size)) return begin;  // inseparable centroids
      mid = median_split(begin, end, info.centroids());
    }
    left = range_info(begin, mid);
    right = range_info(mid, end);
    return mid;
  }

  std::unique_ptr<TempNode> build(uint32_t begin, uint32_t end, int depth, const RangeInfo& info) {
    auto node = std::make_unique<TempNode>();
    node->begin = begin;
    node->end = end;
    node->box = info.box();
    if (end - begin <= kParallelSubtrees) {
      node->subtree.emplace_back();
      build_serial(begin, end, depth, info, 0, node->subtree);
      return node;
    }
    RangeInfo left, right;
    const uint32_t mid = split(begin, end, depth, info, left, right);
    if (mid == begin) return node;
    throw_if_interrupted();  // large subtrees only: the check costs nothing beside their work
    ls::parallel_invoke([&] { node->left = build(begin, mid, depth + 1, left); },
                        [&] { node->right = build(mid, end, depth + 1, right); });
    return node;
  }

  // Builds the range's subtree into `nodes` at `index`, children appended in pairs, depth first.
  void build_serial(uint32_t begin, uint32_t end, int depth, const RangeInfo& info, uint32_t index,
                    std::vector<lsk::BvhNode>& nodes) {
    RangeInfo left, right;
    const uint32_t mid = split(begin, end, depth, info, left, right);
    lsk::BvhNode& out = nodes[index];
    const Bounds box = info.box();
    out.lo = box.lo;
    out.hi = box.hi;
    if (mid == begin) {
      out.first = begin;
      out.count = end - begin;
      return;
    }
    const uint32_t child = uint32_t(nodes.size());
    out.first = child;
    out.count = 0;
    nodes.emplace_back();
    nodes.emplace_back();  // may reallocate: `out` is not used below
    build_serial(begin, mid, depth + 1, left, child, nodes);
    build_serial(mid, end, depth + 1, right, child + 1, nodes);
  }

  // Lays the tree out depth first, children in adjacent pairs: a serially built subtree is copied
  // with its inner nodes' child indices moved to where it lands.
  void flatten(const TempNode& temp, uint32_t index, std::vector<lsk::BvhNode>& nodes) const {
    if (!temp.subtree.empty()) {
      const uint32_t base = uint32_t(nodes.size()) - 1;  // local index k >= 1 lands at base + k
      auto moved = [base](lsk::BvhNode node) {
        if (node.count == 0) node.first += base;
        return node;
      };
      nodes[index] = moved(temp.subtree[0]);
      for (size_t k = 1; k < temp.subtree.size(); ++k) nodes.push_back(moved(temp.subtree[k]));
      return;
    }
    lsk::BvhNode& out = nodes[index];
    out.lo = temp.box.lo;
    out.hi = temp.box.hi;
    if (!temp.left) {
      out.first = temp.begin;
      out.count = temp.end - temp.begin;
      return;
    }
    const uint32_t left = uint32_t(nodes.size());
    out.first = left;
    out.count = 0;
    nodes.emplace_back();
    nodes.emplace_back();  // may reallocate: `out` is not used below
    flatten(*temp.left, left, nodes);
    flatten(*temp.right, left + 1, nodes);
  }

  BvhBuildOptions options_;
  int bins_;
  std::vector<PrimRef> prims_;
  std::atomic<int> max_depth_{0};
};

}  // namespace

BvhBuildResult build_bvh(const std::vector<Bounds>& boxes, const BvhBuildOptions& options) {
  if (boxes.empty()) throw InputError("cannot build a BVH over zero primitives");
  return Builder(boxes, options).run();
}

}  // namespace ls
