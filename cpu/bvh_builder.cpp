#include "bvh_builder.h"

#include "interrupt.h"
#include "parallel.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <memory>

namespace ls {
namespace {

constexpr uint32_t kParallelRange = 4096;  // ranges larger than this are binned and split in parallel
constexpr int kMaxBins = 64;

float half_area(const Bounds& b) {
  if (b.empty()) return 0.0f;
  const glm::vec3 e = b.extent();
  return e.x * e.y + e.y * e.z + e.z * e.x;
}

struct TempNode {
  Bounds box;
  uint32_t begin = 0, end = 0;
  std::unique_ptr<TempNode> left, right;
};

struct BinSet {
  std::array<std::array<Bounds, kMaxBins>, 3> box;
  std::array<std::array<uint32_t, kMaxBins>, 3> count{};
  void merge(const BinSet& o, int bins) {
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < bins; ++b) {
        box[a][b].grow(o.box[a][b]);
        count[a][b] += o.count[a][b];
      }
  }
};

struct RangeInfo {
  Bounds box, centroids;
  void merge(const RangeInfo& o) { box.grow(o.box); centroids.grow(o.centroids); }
};

class Builder {
 public:
  Builder(const std::vector<Bounds>& boxes, const BvhBuildOptions& options)
      : boxes_(boxes), options_(options), bins_(std::clamp(options.bins, 2, kMaxBins)) {
    centroids_.resize(boxes.size());
    order_.resize(boxes.size());
    for (size_t i = 0; i < boxes.size(); ++i) {
      centroids_[i] = boxes[i].centre();
      order_[i] = uint32_t(i);
    }
  }

  BvhBuildResult run() {
    std::unique_ptr<TempNode> root = build(0, uint32_t(boxes_.size()), 0);
    BvhBuildResult result;
    result.nodes.reserve(2 * boxes_.size());
    result.nodes.emplace_back();
    flatten(*root, 0, result.nodes);
    result.order = std::move(order_);
    result.max_depth = max_depth_.load();
    return result;
  }

 private:
  RangeInfo range_info(uint32_t begin, uint32_t end) const {
    auto body = [&](const tbb::blocked_range<uint32_t>& r, RangeInfo info) {
      for (uint32_t i = r.begin(); i != r.end(); ++i) {
        info.box.grow(boxes_[order_[i]]);
        info.centroids.grow(centroids_[order_[i]]);
      }
      return info;
    };
    if (end - begin <= kParallelRange) return body(tbb::blocked_range<uint32_t>(begin, end), RangeInfo{});
    return ls::parallel_reduce(tbb::blocked_range<uint32_t>(begin, end, 1024), RangeInfo{}, body,
                               [](RangeInfo a, const RangeInfo& b) { a.merge(b); return a; });
  }

  // The bin of a centroid along an axis; the same formula bins and partitions.
  int bin_of(float c, float lo, float scale) const {
    return std::clamp(int((c - lo) * scale), 0, bins_ - 1);
  }

  BinSet bin(uint32_t begin, uint32_t end, const Bounds& cb, const glm::vec3& scale) const {
    auto body = [&](const tbb::blocked_range<uint32_t>& r, BinSet set) {
      for (uint32_t i = r.begin(); i != r.end(); ++i) {
        const uint32_t p = order_[i];
        for (int a = 0; a < 3; ++a) {
          const int b = bin_of(centroids_[p][a], cb.lo[a], scale[a]);
          set.box[a][b].grow(boxes_[p]);
          ++set.count[a][b];
        }
      }
      return set;
    };
    if (end - begin <= kParallelRange) return body(tbb::blocked_range<uint32_t>(begin, end), BinSet{});
    return ls::parallel_reduce(tbb::blocked_range<uint32_t>(begin, end, 4096), BinSet{}, body,
                               [this](BinSet a, const BinSet& b) { a.merge(b, bins_); return a; });
  }

  // Splits at the object median along the widest centroid axis (ties by index: deterministic).
  uint32_t median_split(uint32_t begin, uint32_t end, const Bounds& cb) {
    const glm::vec3 e = cb.extent();
    const int axis = (e.x >= e.y && e.x >= e.z) ? 0 : (e.y >= e.z ? 1 : 2);
    const uint32_t mid = begin + (end - begin) / 2;
    std::nth_element(order_.begin() + begin, order_.begin() + mid, order_.begin() + end, [&](uint32_t a, uint32_t b) {
      const float ca = centroids_[a][axis], cb2 = centroids_[b][axis];
      return ca < cb2 || (ca == cb2 && a < b);
    });
    return mid;
  }

  // The SAH split position, or `end` when no split beats a leaf of an acceptable size.
  uint32_t sah_split(uint32_t begin, uint32_t end, const RangeInfo& info) {
    const uint32_t n = end - begin;
    const Bounds& cb = info.centroids;
    glm::vec3 scale(0.0f);
    for (int a = 0; a < 3; ++a) {
      const float ext = cb.hi[a] - cb.lo[a];
      scale[a] = ext > 0.0f ? float(bins_) * 0.99999f / ext : 0.0f;
    }
    if (scale == glm::vec3(0.0f)) return end;  // all centroids coincide
    const BinSet set = bin(begin, end, cb, scale);

    float best_cost = std::numeric_limits<float>::infinity();
    int best_axis = -1, best_bin = 0;
    for (int a = 0; a < 3; ++a) {
      if (scale[a] == 0.0f) continue;
      std::array<float, kMaxBins> right_cost{};
      Bounds acc;
      uint32_t count = 0;
      for (int b = bins_ - 1; b > 0; --b) {
        acc.grow(set.box[a][b]);
        count += set.count[a][b];
        right_cost[b] = half_area(acc) * float(count);
      }
      acc = Bounds{};
      count = 0;
      for (int b = 0; b < bins_ - 1; ++b) {
        acc.grow(set.box[a][b]);
        count += set.count[a][b];
        if (count == 0 || count == n) continue;
        const float cost = half_area(acc) * float(count) + right_cost[b + 1];
        if (cost < best_cost) { best_cost = cost; best_axis = a; best_bin = b; }
      }
    }
    if (best_axis < 0) return end;
    const float parent_area = half_area(info.box);
    const float split_cost = parent_area > 0.0f ? options_.traversal_cost + best_cost / parent_area : float(n);
    if (n <= uint32_t(options_.max_leaf_size) && float(n) <= split_cost) return begin;  // a leaf is cheaper
    const float lo = cb.lo[best_axis], sc = scale[best_axis];
    auto mid = std::partition(order_.begin() + begin, order_.begin() + end,
                              [&](uint32_t p) { return bin_of(centroids_[p][best_axis], lo, sc) <= best_bin; });
    return uint32_t(mid - order_.begin());
  }

  std::unique_ptr<TempNode> build(uint32_t begin, uint32_t end, int depth) {
    auto node = std::make_unique<TempNode>();
    node->begin = begin;
    node->end = end;
    int seen = max_depth_.load();
    while (depth > seen && !max_depth_.compare_exchange_weak(seen, depth)) {}
    const RangeInfo info = range_info(begin, end);
    node->box = info.box;
    const uint32_t n = end - begin;
    if (n <= 1) return node;

    uint32_t mid;
    if (depth >= options_.sah_depth_limit) {
      if (n <= uint32_t(options_.max_leaf_size)) return node;
      mid = median_split(begin, end, info.centroids);
    } else {
      mid = sah_split(begin, end, info);
      if (mid == begin) return node;  // SAH prefers a leaf
      if (mid == end) {               // inseparable centroids
        if (n <= uint32_t(options_.max_leaf_size)) return node;
        mid = median_split(begin, end, info.centroids);
      }
    }
    if (n > kParallelRange) {
      throw_if_interrupted();  // large subtrees only: the check costs nothing beside their work
      ls::parallel_invoke([&] { node->left = build(begin, mid, depth + 1); },
                          [&] { node->right = build(mid, end, depth + 1); });
    } else {
      node->left = build(begin, mid, depth + 1);
      node->right = build(mid, end, depth + 1);
    }
    return node;
  }

  void flatten(const TempNode& temp, uint32_t index, std::vector<lsk::BvhNode>& nodes) const {
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

  const std::vector<Bounds>& boxes_;
  BvhBuildOptions options_;
  int bins_;
  std::vector<glm::vec3> centroids_;
  std::vector<uint32_t> order_;
  std::atomic<int> max_depth_{0};
};

}  // namespace

BvhBuildResult build_bvh(const std::vector<Bounds>& boxes, const BvhBuildOptions& options) {
  if (boxes.empty()) throw InputError("cannot build a BVH over zero primitives");
  return Builder(boxes, options).run();
}

}  // namespace ls
