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

// The Line Space of one object of a two-level structure: integration depth D and subdivision N
// (n = 0: no Line Space; the object is traced exactly).
struct ObjectLs {
  int depth = 0;
  int n = 0;
  bool operator==(const ObjectLs&) const = default;
};

struct LsOptions {
  // Defaults chosen by measurement: see README, "Line Space parameters".
  int further_rays = 0;          // search rays after the midpoint ray
  float angle_degrees = 45.0f;   // refusal angle between ray and extrapolated normal; 0 refuses all
  bool reverse_behind = false;   // --ls-behind reverse: a plane hit behind the origin asks the reverse shaft (ls_lookup.h)
  uint32_t min_triangles = 8;    // subtrees with fewer triangles get no LS (0: the paper's behaviour)
  bool paper_candidates = false; // 4-byte candidates instead of the compact 1/2/4-byte local index
  size_t max_memory = 0;         // refuse above this estimate (0: half of physical memory)
  // Per mesh (2L only): each object's own D and N, overriding the structure's; empty: the
  // structure's D and N for every object.  2l-ls:auto fills it from the budget (ls_budget.h).
  std::vector<ObjectLs> objects;
  // 2l-ls:auto (ls_budget.h): bytes of Line Space to spend (bytes_ls), and the pilot's rays.
  size_t budget = 0;
  size_t budget_rays = 1u << 15;
  // Called now and then from the building threads with (LS nodes done, LS nodes): a progress bar.
  std::function<void(size_t done, size_t total)> progress;
};

struct LsBuildInfo {
  size_t ls_nodes = 0;
  size_t shafts_per_ls = 0;          // 30 N^4 when every LS node has the same N, else 0
  size_t shafts = 0;                 // over all LS nodes
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
                                           const LsOptions& options);
size_t placement_bytes(const std::vector<LsPlacement>& placed);  // LS node records + candidates
// What bytes_ls() counts whatever the LS nodes: the per-node LS index and the per-triangle normals.
size_t line_space_fixed_bytes(const Accel& accel);
// The D and N object `mesh` gets: options.objects' entry, else the structure's.
ObjectLs object_line_space(const Accel& accel, const LsOptions& options, size_t mesh);
// The per-triangle vertex normals the lookup's refusal test reads (2L: objects with a Line Space only).
void compute_line_space_normals(const Scene& scene, const BvhSubtrees& subtrees, const LsOptions& options, Accel& accel);
// Chooses the LS nodes, allocates empty candidates and fills ls_info (no normals).
void layout_line_space_nodes(const LsOptions& options, const BvhSubtrees& subtrees, Accel& accel);
// The candidate search of every laid-out LS node on all CPU threads; sets empty_shafts and seconds.
void search_line_space(const LsOptions& options, Accel& accel);

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

size_t physical_memory_bytes();

// How many Line Spaces layout_line_space_nodes() has laid out in this process (every CPU or GPU build,
// and every 2l-ls:auto pilot evaluation, goes through it): the animation tests check that a
// top-level update lays out none.
size_t line_space_layouts();

}  // namespace ls
