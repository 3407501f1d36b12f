// 2l-ls:auto: which objects of a two-level structure get a Line Space, and with which integration
// depth D and subdivision N, within a memory budget (--ls-budget MB).
//
// Measured, not modelled.  A pilot of diffuse rays (the rays a Line Space serves: bounces >= 1) and
// of shadow rays from their hits to the lights (as the path tracer casts them) is traced exactly,
// then for every object and every (D, N) of the menu with a Line Space on that object alone.  Only the shafts those rays can look up are searched (a lookup's shaft depends on the ray's
// line and the LS box alone), so one evaluation costs a few thousand searches whatever N and D.  Per
// object and option this gives:
//   error  the pilot rays whose answer moved (another instance, hit and miss swapped, or a hit point
//          more than 1e-3 of the scene's diagonal away; for shadow rays: occluded or not changed),
//          over all pilot rays;
//   work   box tests + 2.3 x triangle tests + 5.7 x Line Space lookups of those rays (the weights
//          are the reference traversal's instruction costs, measured: docs/performance.md,
//          "Per-object Line Space under a memory budget"); the option's saved work is the exact
//          traversal's minus its own.
//   bytes  its LS nodes and candidates, exactly as the builder lays them out.
// Summed over objects, the plan minimises the error subject to
//   bytes_ls <= budget, and saved work >= that of the reference, the uniform 2l-ls:D:N of the menu
//   with the most bytes_ls within the budget (the structure one would have used instead),
// by Lagrangian relaxation of the work constraint (bisection on its multiplier) and the greedy
// multiple-choice knapsack over each object's convex hull of (bytes, error - lambda x saved work),
// then single-object moves that keep both constraints and lower the error.
// "None" is every object's free option, so objects that gain nothing (too few triangles, never
// reached, slower with a Line Space) get none.  When the result would err more than the reference
// in the pilot, the reference itself is the plan.  Finally both are evaluated jointly (every object's
// Line Space at once) on the pilot, and reported.  The menu of (D, N): cpu/build/ls_budget_menu.h.
#pragma once

#include "common/kernels/layouts.h"
#include "common/model/scene.h"
#include "common/structure/accel.h"
#include "cpu/build/line_space_builder.h"
#include "cpu/build/ls_budget_menu.h"

#include <cstddef>
#include <string>
#include <vector>

namespace ls {

// The pilot's pieces, for tests and studies that check the plan against full builds: `count` diffuse
// rays (closest hit) and a shadow ray (any hit) from each one's exact hit to a light, as the path
// tracer casts them (none in a scene without emissive triangles).
struct LsPilot {
  std::vector<lsk::Ray> rays, shadow_rays;
};
LsPilot ls_budget_pilot(const Scene& scene, const Accel& exact, size_t count);
double pilot_tolerance(const Scene& scene);  // 1e-3 of the scene's diagonal
// Closest hit: another instance, hit and miss swapped, or the hit point moved more than tolerance.
bool pilot_answer_moved(const lsk::Ray& ray, const lsk::Hit& got, const lsk::Hit& exact, double tolerance);
// Any hit: occluded or not changed; closest hit: pilot_answer_moved.
bool pilot_answer_wrong(const lsk::Ray& ray, const lsk::Hit& got, const lsk::Hit& exact, bool any_hit, double tolerance);

// The optimiser on its own.  options[o][0] is object o's "none" (0 bytes, no error, no saved work);
// reference[o] indexes the reference's option per object (empty: no reference, every object none).
// Returns, per object, the option of least total error with total bytes <= room and total saved work
// >= the reference's; the reference itself when the search finds nothing better.
struct PlanOption {
  ObjectLs ls;         // n = 0: none
  size_t bytes = 0;
  double error = 0.0;  // fraction of all pilot rays
  double saved = 0.0;  // work saved per pilot ray
  bool offered = true; // false: nothing measurable to buy (no ray moved, almost no work saved); only
                       // a reference may hold it
};
struct PlanChoice {
  std::vector<size_t> choice;
  double lambda = 0.0;
  bool reference_chosen = false;
};
PlanChoice optimise_plan(const std::vector<std::vector<PlanOption>>& options, size_t room, const std::vector<size_t>& reference);

// Plans a budgeted 2L-LS on `accel`, an exact two-level structure without its fast path
// (build_planned_accel, build_structures.h, calls it between the BVHs and the Line Space).  Uses accel's Line Space arrays as scratch and leaves
// them empty.  Throws InputError when the budget cannot hold even the fixed part.
LsPlan plan_line_space_budget(const Scene& scene, Accel& accel, const AccelOptions& options);

}  // namespace ls
