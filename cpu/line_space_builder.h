// Builds the Line Space of an F-LS or 2L-LS structure (DESIGN §3, paper §3.1–3.2): an LsNode for every
// BVH node at integration depth D (of the flat BVH, or of every unique object's BVH, stored once per
// mesh however many instances use it), and one candidate per shaft found by the single-source search
// kernel (common/kernels/ls_candidate_search.h), in parallel with TBB.
#pragma once

#include "scene.h"
#include "kernels/layouts.h"

#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

namespace ls {

struct Accel;

struct LsOptions {
  // Defaults chosen by measurement: see README, "Line Space parameters".
  int further_rays = 0;          // search rays after the midpoint ray
  float angle_degrees = 45.0f;   // refusal angle between ray and extrapolated normal; 0 refuses all
  uint32_t min_triangles = 8;    // subtrees with fewer triangles get no LS (0: the paper's behaviour)
  bool paper_candidates = false; // 4-byte candidates instead of the compact 1/2/4-byte local index
  size_t max_memory = 0;         // refuse above this estimate (0: half of physical memory)
  // Called now and then from the building threads with (LS nodes done, LS nodes): a progress bar.
  std::function<void(size_t done, size_t total)> progress;
};

struct LsBuildInfo {
  size_t ls_nodes = 0;
  size_t shafts_per_ls = 0;
  size_t empty_shafts = 0;
  size_t candidate_bytes = 0;        // as stored
  size_t candidate_bytes_paper = 0;  // at 4 bytes per shaft
  size_t candidate_bytes_compact = 0;
  double seconds = 0.0;
};

// Adds the Line Space to an exact structure that build_accel() made: layout_line_space(), then the
// candidate search on all CPU threads, packed by pack_ls_candidates().  Throws InputError when the
// estimated memory exceeds the budget, before allocating anything large.
void build_line_space(const Scene& scene, const LsOptions& options, Accel& accel);

// The part of the build both back ends share: chooses the LS nodes (boxes, subtree ranges, bytes per
// candidate, word offsets), allocates accel.ls_candidates with every shaft empty, computes the vertex
// normals and fills accel.ls_info (sizes; empty_shafts = every shaft until a search packs its result).
void layout_line_space(const Scene& scene, const LsOptions& options, Accel& accel);

// The one packing rule: the search result of every shaft of LS node `ls_index` (an index into tris[],
// or LS_INVALID when empty) stored as an index local to the node's triangle range in ls.bytes bytes,
// all ones = empty.  Returns the number of empty shafts.  Distinct nodes may be packed concurrently.
size_t pack_ls_candidates(Accel& accel, size_t ls_index, const uint32_t* prims);

// The `instance` argument of ls_find_candidate() for this structure (0 for 2L, LS_INVALID for F).
uint32_t ls_search_instance(const Accel& accel);

// Bytes the Line Space of `ls_nodes` nodes at subdivision n would take (candidates at 4 bytes).
size_t estimate_line_space_bytes(size_t ls_nodes, int n);

size_t physical_memory_bytes();

// How many Line Spaces layout_line_space() has laid out in this process (every CPU or GPU build goes
// through it): the animation tests check that a top-level update builds none.
size_t line_space_layouts();

}  // namespace ls
