// Builds the Line Space of an F-LS or 2L-LS structure (docs/design.md §3, paper §3.1–3.2): an LsNode for every
// BVH node at integration depth D (of the flat BVH, or of every unique object's BVH, stored once per
// mesh however many instances use it), and one candidate per shaft found by the single-source search
// kernel (common/kernels/ls_candidate_search.h), in parallel with TBB.
#pragma once

#include "common/base/memory_budget.h"
#include "common/kernels/layouts.h"
#include "common/model/scene.h"
#include "common/structure/accel.h"

#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

namespace ls {

struct Accel;

// Adds the Line Space to an exact structure that build_accel() made: layout_line_space(), then the
// candidate search on all CPU threads, packed by pack_ls_candidates().  Throws InputError when the
// estimated memory exceeds the budget, before allocating anything large.
void build_line_space(const Scene& scene, const LsBuildOptions& options, const Limits& limits, Accel& accel);

// The part of the build both back ends share: chooses the LS nodes (boxes, subtree ranges, bytes per
// candidate, word offsets), allocates accel.ls_candidates with every shaft empty, computes the
// candidate records and fills accel.ls_info (sizes; empty_shafts = every shaft until a search packs its result).
void layout_line_space(const Scene& scene, const LsBuildOptions& options, const Limits& limits, Accel& accel);

// The pieces of layout_line_space(), for callers that lay out many Line Spaces over one BVH (the
// budget's pilot, ls_budget.h).  Per BVH node: its subtree's triangle range and its depth below the
// root of its BVH (-1 for nodes of no BVH the Line Space uses).
struct BvhSubtrees {
  std::vector<uint32_t> first, count;
  std::vector<int> depth;
};
BvhSubtrees bvh_subtrees(const Accel& accel);
std::vector<uint32_t> ls_roots(const Accel& accel);  // the flat BVH's root, or every object's
// The LS nodes a BVH rooted at `root` gets at (depth, n), in node order: subtrees at that depth with
// at least min_triangles triangles and a usable box; `words` of candidates each.  n <= 0: none.
struct LsPlacement {
  lsk::LsNode ls;
  uint32_t words = 0;
};
std::vector<LsPlacement> place_line_spaces(const Accel& accel, const BvhSubtrees& subtrees, uint32_t root, int depth, int n,
                                           const LsBuildOptions& options);
size_t placement_bytes(const std::vector<LsPlacement>& placed);  // LS node records + candidates
// What bytes_ls() counts whatever the LS nodes: the per-node LS index and the per-triangle records.
size_t line_space_fixed_bytes(const Accel& accel);
// The D and N object `mesh` gets: options.objects' entry, else the structure's.
ObjectLs object_line_space(const Accel& accel, const LsBuildOptions& options, size_t mesh);
// The per-triangle records the lookup reads (2L: objects with a Line Space only; the rest stay zero).
void compute_line_space_records(const Scene& scene, const BvhSubtrees& subtrees, const LsBuildOptions& options, Accel& accel);
// One triangle's record: normals are its three vertex normals, octahedral (packSnorm2x16); id its
// tri_ids[] entry.
lsk::LsRecord make_ls_record(const lsk::Triangle& tri, const glm::uvec3& normals, uint32_t id);
// Chooses the LS nodes, allocates empty candidates and fills ls_info (no records).
void layout_line_space_nodes(const LsBuildOptions& options, const Limits& limits, const BvhSubtrees& subtrees, Accel& accel);
// The candidate search of every laid-out LS node on all CPU threads; sets empty_shafts and seconds.
void search_line_space(const LsBuildOptions& options, Accel& accel);

// The one packing rule: the search result of every shaft of LS node `ls_index` (an index into tris[],
// or LS_INVALID when empty) stored as an index local to the node's triangle range in ls.bytes bytes,
// all ones = empty.  Returns the number of empty shafts.  Distinct nodes may be packed concurrently.
size_t pack_ls_candidates(Accel& accel, size_t ls_index, const uint32_t* prims);

// The packing rule for one shaft (pack_ls_candidates applies it to every shaft of a node).  Shafts of
// one node share words: not concurrently within a node.
void store_ls_candidate(Accel& accel, size_t ls_index, uint32_t shaft, uint32_t prim);

// The centres of an LS node's 6 N^2 patches (lsk::ls_patch_point at ls_search_offsets(0)), indexed by
// patch: the ends of every shaft's first search ray, made once a node for the fast path's search.
std::vector<lsk::vec3> ls_patch_centres(const lsk::LsNode& ls);

// The `instance` argument of ls_find_candidate() for this structure (0 for 2L, LS_INVALID for F).
uint32_t ls_search_instance(const Accel& accel);

// Bytes the Line Space of `ls_nodes` nodes at subdivision n would take (candidates at 4 bytes).
size_t estimate_line_space_bytes(size_t ls_nodes, int n);

// How many Line Spaces layout_line_space_nodes() has laid out in this process (every CPU or GPU build,
// and every 2l-ls:auto pilot evaluation, goes through it): the animation tests check that a
// top-level update lays out none.
size_t line_space_layouts();

}  // namespace ls
