// `linespace-validate bound`: how much traversal work a Line Space can save at most, against what it
// saves, on the same rays (CPU reference kernels, whose work is counted: TraceWork, common/kernels/layouts.h).
//
// A lookup stops the walk at a Line Space node; what it can save is the exact work *below* that node.
// Tracing the structure with every lookup refused (--ls-angle 0) walks exactly as its BVH does, and
// counts the work done in the Line Space nodes' subtrees apart (TraceWork::*_in_ls).  Without that
// part, plus one lookup per Line Space node the walk reached, it is the work of an *oracle*: a Line
// Space whose every lookup gave the exact answer at a lookup's cost.  exact / oracle bounds the
// speed-up of any Line Space at those nodes that answers as the exact structure does; a real one
// saves less where lookups are refused, and can prune more only by answering differently (its
// image error).  Work is in box tests: boxes + 2.3 x triangles + 5.7 x lookups (cpu/trace/trace_rays.h).
#pragma once

#include "common/structure/accel.h"
#include "cpu/trace/trace_rays.h"
#include "validate/table.h"

#include <nlohmann/json.hpp>

#include <functional>
#include <string>
#include <vector>

namespace ls {

struct BoundRow {
  std::string structure, exact;  // "f-ls:8:6" and its exact structure, "bvh"
  size_t ls_nodes = 0;
  TraceWorkTotals exact_work;    // every lookup refused: the BVH's own walk, split at the LS nodes
  TraceWorkTotals traced_work;   // as the structure traces with the study's Line Space options
  lsk::LsCounters traced{};      // its lookups' outcomes

  double exact_work_units() const;   // boxes + 2.3 triangles (the lookups of the refused walk excluded)
  double oracle_work_units() const;  // exact work outside the LS subtrees + 5.7 x the walk's lookups
  double traced_work_units() const;  // boxes + 2.3 triangles + 5.7 lookups, as traced
  double share_below_ls() const;     // of the exact work, the part in LS subtrees
  double bound() const { return exact_work_units() / oracle_work_units(); }
  double achieved() const { return exact_work_units() / traced_work_units(); }
};

struct BoundStudy {
  std::string scene, rays;  // rays: "diffuse, 200000, seed 1" or the ray file
  size_t ray_count = 0;
  std::vector<BoundRow> rows;

  Table table() const;  // per ray
  nlohmann::json json() const;
};

// Builds each Line Space structure of `specs` (an exact one is an InputError) and traces `rays` twice
// on the reference kernels, on all threads.  log: one line per structure.
BoundStudy run_bound_study(const Scene& scene, const std::string& scene_name, const std::vector<lsk::Ray>& rays,
                           const std::string& rays_name, const std::vector<StructureSpec>& specs, const AccelOptions& options,
                           const LsLookup& lookup, const std::function<void(const std::string&)>& log);

// bound.md, bound.csv, bound.json into dir.
void write_bound_study(const std::string& dir, const BoundStudy& study);

}  // namespace ls
