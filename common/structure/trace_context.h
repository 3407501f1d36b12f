// The C++ stand-in for a shader's bound buffers: the single-source traversal kernels are included
// inside this struct, so `nodes[i]` in the kernel reads the pointer member here and the buffer there.
#pragma once

#include "common/kernels/hit.h"
#include "common/kernels/layouts.h"
#include "common/kernels/line_space.h"
#include "common/kernels/ray_box.h"
#include "common/kernels/ray_triangle.h"

#include <cstdint>

namespace lsk {

struct TraceContext {
  const BvhNode* nodes = nullptr;
  const Triangle* tris = nullptr;
  const uint* tri_ids = nullptr;
  const uint* tri_instances = nullptr;
  const BvhNode* top_nodes = nullptr;
  const InstanceRecord* instances = nullptr;
  // Line Space (LS structures only)
  const uint* node_ls = nullptr;
  const LsNode* ls_nodes = nullptr;
  const uint* ls_candidates = nullptr;
  const LsRecord* ls_records = nullptr;
  uint ls_enabled = 0;
  float ls_cos2 = -1.0f;
  uint ls_behind = 0;  // --ls-behind: LS_BEHIND_* (ls_lookup.h)
  float ls_leave_reach = 0.0f;  // --ls-leave-reach: patches (ls_lookup.h)
  uint walk_far_first = 0;  // tests: the farther child first (traverse_bvh.h)
  uint ls_skip = 0;  // linespace-profile --skip, read by the fast path only (LsSkip, accel.h)
  static constexpr uint LS_SKIP_REFUSED_WALKS = 1u;
  static constexpr uint LS_SKIP_LOOKUPS = 2u;
  LsCounters ls_counters{};  // the shader keeps these in a private variable too
  TraceWork trace_work{};    // box and triangle tests of the reference traversal (shaders count nothing)
  // Per node of nodes[], non-zero in a Line Space node's subtree (line_space_subtrees(), accel.h):
  // where the work is also counted as *_in_ls.  Null: nothing is.
  const uint8_t* node_in_ls = nullptr;

  void count_work(uint node, uint boxes, uint triangles) {
    trace_work.box_tests += boxes;
    trace_work.triangle_tests += triangles;
    if (node_in_ls && node != LS_INVALID && node_in_ls[node]) {
      trace_work.box_tests_in_ls += boxes;
      trace_work.triangle_tests_in_ls += triangles;
    }
  }

#include "common/kernels/ls_lookup.h"
#include "common/kernels/traverse_bvh.h"
#include "common/kernels/ls_candidate_search.h"
};

}  // namespace lsk
