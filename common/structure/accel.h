// A structure's data, apart from what builds and traces it: the flat BVH (F-BVH) over world-space
// triangles or the two-level BVH (2L-BVH: one BVH per unique mesh in object space plus a top level
// over instances), their Line Space, and the options they are built with.  The arrays are the std430
// buffers the GPU port uploads unchanged.  Builders (cpu/build) include this header, never the
// reverse; the CPU's fast path (cpu/trace/fast_tracer.h) hangs off an Accel as an opaque pointer.
#pragma once

#include "common/base/memory_budget.h"
#include "common/kernels/layouts.h"
#include "common/model/scene.h"
#include "common/model/structure_name.h"
#include "common/structure/trace_context.h"

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace ls {

class FastTracer;

// Which traversal trace_rays uses.
enum class Traversal { Reference, Fast };

Traversal parse_traversal(const std::string& text);  // one of traversal_names(); throws InputError
const char* traversal_name(Traversal t);
std::vector<std::string> traversal_names();  // every traversal's name, the default first (the CLI's choices)

struct BvhBuildOptions {
  int bins = 32;                 // SAH bins per axis
  int max_leaf_size = 4;         // a leaf never holds more, unless primitives cannot be separated
  float traversal_cost = 1.0f;   // relative to one primitive test
  int sah_depth_limit = 32;      // deeper, split at the object median: total depth stays < 64
};

// The Line Space of one object of a two-level structure: integration depth D and subdivision N
// (n = 0: no Line Space; the object is traced exactly).
struct ObjectLs {
  int depth = 0;
  int n = 0;
  bool operator==(const ObjectLs&) const = default;
};

// What building a Line Space reads (F-LS, 2L-LS).  Defaults chosen by measurement: see
// docs/performance.md, "Line Space parameters".
struct LsBuildOptions {
  int further_rays = 0;          // search rays after the midpoint ray
  uint32_t min_triangles = 8;    // subtrees with fewer triangles get no LS (0: the paper's behaviour)
  bool paper_candidates = false; // 4-byte candidates instead of the compact 1/2/4-byte local index
  // Per mesh (2L only): each object's own D and N, overriding the structure's; empty: the
  // structure's D and N for every object.  2l-ls:auto's plan fills it (cpu/build/ls_budget.h).
  std::vector<ObjectLs> objects;
  // Called now and then from the building threads with (LS nodes done, LS nodes): a progress bar.
  std::function<void(size_t done, size_t total)> progress;
};

// What linespace-profile --skip leaves out of a Line Space structure's timing on the fast path, so
// that the time of the rest shows: the exact walks of subtrees whose lookup refused, or every
// lookup (each Line Space lane then answers "empty").  The answers are wrong then; nothing else sets it.
enum class LsSkip { Nothing, RefusedWalks, Lookups };

// What a lookup does where its shaft's first candidate lies behind the ray's origin (--ls-behind;
// ls_lookup.h): traverse the subtree, let the reverse shaft answer only "empty", or let its
// candidate answer too.
enum class LsBehind { Exact, Empty, Reverse };

LsBehind parse_ls_behind(const std::string& text);  // one of ls_behind_names(); throws InputError
const char* ls_behind_name(LsBehind behind);
std::vector<std::string> ls_behind_names();  // every mode's name, the default first (the CLI's choices)

// --ls-leave-reach: a number of patches >= 0, or inf; throws InputError otherwise.
float parse_ls_leave_reach(const std::string& text);

// What a Line Space lookup reads besides the structure: it travels with each trace and render call
// (trace_rays, RenderOptions::lookup), so changing it never rebuilds a Line Space.
struct LsLookup {
  float angle_degrees = 30.0f;   // refusal angle between ray and extrapolated normal; 0 refuses all (30: docs/performance.md)
  LsBehind behind = LsBehind::Exact;  // --ls-behind
  // --ls-leave-reach: with --ls-behind empty, how far outside its triangle, in patches, the reverse
  // candidate's plane hit may lie and still be the surface the ray leaves (ls_lookup.h; inf: anywhere
  // in its plane).  0.25: the widest that kept livingroom's error under 45 degrees' exact (docs/performance.md).
  float leave_reach = 0.25f;
  LsSkip skip = LsSkip::Nothing;
};

// 2l-ls:auto's planner inputs (cpu/build/ls_budget.h).
struct LsPlanOptions {
  size_t budget = 0;             // bytes of Line Space to spend (bytes_ls); 0: none given
  size_t rays = 1u << 15;        // the pilot's diffuse rays
  LsLookup lookup;               // the lookup the plan's error and work are measured with
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

// 2l-ls:auto's plan (cpu/build/ls_budget.h): which objects get a Line Space, with which D and N.
struct LsPlanRow {
  uint32_t mesh = 0;
  std::string name;
  size_t triangles = 0;
  size_t instances = 0;
  size_t hits = 0;         // pilot rays whose exact hit lies on this object
  size_t relevant = 0;     // pilot rays that cross one of its instance boxes (the only ones it can change)
  ObjectLs chosen;         // n = 0: none
  ObjectLs reference;      // what the reference uniform structure gives it
  size_t bytes = 0;        // its LS nodes and candidates
  double error = 0.0;      // alone on the pilot: fraction of all pilot rays it gets wrong with `chosen`
  double saved_work = 0.0; // alone on the pilot: work saved per pilot ray with `chosen`
  std::string reason;      // "chosen", "no gain", "not reached", "too small"
};

// A structure's figures on the pilot, every object's Line Space at once.
struct PilotFigures {
  size_t bytes_ls = 0;
  double error = 0.0;       // fraction of pilot rays whose answer moved
  double saved_work = 0.0;  // per pilot ray, against the exact 2L-BVH
};

struct LsPlan {
  size_t budget = 0;           // bytes of Line Space allowed (bytes_ls)
  size_t fixed_bytes = 0;      // bytes_ls without any LS node: per-node index, per-triangle normals
  size_t predicted_bytes = 0;  // fixed + every row's bytes: the structure's bytes_ls, exactly
  std::string reference;       // the uniform structure the plan must be as fast as ("" when none fits)
  bool reference_chosen = false;  // the optimiser did not beat the reference: the plan is the reference
  double lambda = 0.0;         // the work constraint's multiplier
  PilotFigures plan, uniform;  // joint pilot evaluations of the plan and of the reference
  size_t pilot_rays = 0;         // diffuse (closest hit)
  size_t pilot_shadow_rays = 0;  // to the lights (any hit)
  size_t evaluations = 0;      // (object, D, N) options evaluated
  size_t shafts_searched = 0;
  double seconds = 0.0;
  std::vector<LsPlanRow> rows;  // every object the structure holds, by mesh index

  std::vector<ObjectLs> objects(size_t meshes) const;  // LsBuildOptions::objects of the plan
};

struct Accel {
  StructureSpec spec;
  std::vector<lsk::BvhNode> nodes;          // F: the flat BVH; 2L: every object BVH, one after another
  std::vector<lsk::Triangle> tris;          // in BVH order
  std::vector<uint32_t> tri_ids;            // triangle id within its mesh
  std::vector<uint32_t> tri_instances;      // F only: instance id per triangle
  std::vector<lsk::BvhNode> top_nodes;      // 2L only
  std::vector<lsk::InstanceRecord> instances;  // 2L only, in top-level order
  std::vector<uint32_t> object_roots;       // 2L only: root node of each unique mesh's BVH (by mesh index;
                                            // LS_INVALID for meshes no instance uses)
  size_t objects = 0;                       // unique meshes the structure holds
  size_t instance_count = 0;
  size_t world_triangles = 0;
  int max_depth = 0;                        // deepest BVH (object BVHs for 2L)
  double build_seconds = 0.0;               // everything, Line Space included
  BvhBuildOptions bvh_options;              // what the BVHs were built with (the top level is rebuilt with it)
  // Which build this is (unique per build_accel call in a process; 0 for hand-made structures) and
  // how often its top level was updated since (top_level_update.h): device copies check both.
  uint64_t build_id = 0;
  uint32_t top_level_version = 0;

  // Line Space (F-LS, 2L-LS): see line_space_builder.h and common/kernels/ls_lookup.h.
  std::vector<uint32_t> node_ls;            // per BVH node: its LsNode, or LS_INVALID
  std::vector<lsk::LsNode> ls_nodes;
  std::vector<uint32_t> ls_candidates;      // packed per LsNode
  std::vector<lsk::LsRecord> ls_records;    // per triangle (BVH order): what a lookup reads of it
  LsBuildOptions ls_options;              // what its Line Space was built with
  LsBuildInfo ls_info;
  std::shared_ptr<const LsPlan> ls_plan;    // 2l-ls:auto: the per-object choice (ls_budget.h)

  // The fast CPU path (cpu/trace/fast_tracer.h): the wide BVH over the arrays above, and which path trace_rays
  // takes by default.  Both give the same answers; the reference is the GPU's twin.
  std::shared_ptr<const FastTracer> fast;
  Traversal traversal = Traversal::Fast;
  double wide_build_seconds = 0.0;          // part of build_seconds

  size_t bytes_total() const;
  size_t fast_bytes = 0;                    // FastTracer::bytes() of `fast`, set wherever it is made
  size_t bytes_wide() const { return fast_bytes; }  // the fast path's wide nodes (beside bytes_total)
  size_t bytes_ls() const;
};

struct AccelOptions {
  BvhBuildOptions bvh;
  LsBuildOptions ls;
  LsPlanOptions plan;             // 2l-ls:auto only
  Limits limits;                  // --max-memory: builds refuse what would not fit
  bool search_candidates = true;  // false: the Line Space is laid out with every shaft empty (GPU search)
  Traversal traversal = Traversal::Fast;  // what trace_rays uses for this structure
  int exact_width = 8;                    // the order-free walk's nodes: 4 or 8, chosen by measurement
  bool fast_path = true;  // false: no fast path is made, trace_rays takes the reference (the GPU port's builds)
  AccelOptions() = default;
  AccelOptions(const BvhBuildOptions& b) : bvh(b) {}  // NOLINT: implicit on purpose
};

// Sums Line Space lookup counters.
void add_counters(lsk::LsCounters& into, const lsk::LsCounters& from);

// The kernels' view of a built structure's buffers, with the lookup's parameters (the refusal angle's
// cos^2, the behind mode).
lsk::TraceContext trace_context(const Accel& accel, const LsLookup& lookup = {});

// The kernels' ls_cos2 of a lookup: cos^2 of the refusal angle, negative (refuse all) at 0 degrees.
float ls_cos2(const LsLookup& lookup);

// The kernels' ls_behind of a lookup: LS_BEHIND_EXACT, _EMPTY or _REVERSE.
uint32_t ls_behind_code(const LsLookup& lookup);

}  // namespace ls
