#include "cpu/build/ls_budget.h"

#include "common/base/interrupt.h"
#include "common/base/parallel.h"
#include "common/kernels/offset_ray.h"
#include "common/kernels/ray_box.h"
#include "common/kernels/rng.h"
#include "common/kernels/sampling.h"
#include "common/render/light_set.h"
#include "common/render/surface.h"
#include "common/structure/accel.h"
#include "cpu/build/build_accel.h"
#include "cpu/build/line_space_builder.h"
#include "cpu/trace/ray_generators.h"
#include "cpu/trace/trace_rays.h"

#include <tbb/enumerable_thread_specific.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>

namespace ls {
namespace {

constexpr uint32_t kPilotSeed = 0x5eed1234u;  // the pilot's rays are the same for every plan of a scene
constexpr double kMoveTolerance = 1e-3;        // of the scene's diagonal: a hit that moved less is right
constexpr double kNegligibleWork = 0.01;  // saved work per pilot ray below which an option buys nothing

struct Traced {
  std::vector<lsk::Hit> hits;
  double work = 0.0;
};

// Hits by the reference traversal (the one that counts its work), on all threads.
Traced trace_counted(const Accel& accel, const LsLookup& lookup, const std::vector<lsk::Ray>& rays, bool any_hit) {
  Traced out;
  out.hits.resize(rays.size());
  TraceWorkTotals w;
  trace_rays(accel, lookup, rays.data(), out.hits.data(), rays.size(), any_hit, nullptr, Traversal::Reference, &w);
  out.work = work_units(w.box_tests, w.triangle_tests, w.lookups);
  return out;
}

// Searches the candidates of the shafts `rays` can look up in accel's laid-out Line Space, and only
// those: a lookup's shaft depends on the ray's line and the LS box alone, and a lookup needs the
// traversal to reach the LS node, i.e. the ray to cross the boxes of the node and its ancestors, so
// the shafts found by walking the BVHs down to their LS nodes are all the rays can read.  Every
// other shaft stays empty and is never read by these rays.  Returns the number of shafts searched.
size_t search_shafts_of(Accel& accel, const std::vector<lsk::Ray>& rays, const BvhSubtrees& subtrees,
                        const std::vector<int>& depth_of_mesh, const LsBuildOptions& options) {
  lsk::TraceContext base = trace_context(accel);
  base.ls_enabled = 0;
  tbb::enumerable_thread_specific<std::vector<uint64_t>> found;  // LS index << 32 | shaft
  ls::parallel_for(tbb::blocked_range<size_t>(0, rays.size(), 64), [&](const tbb::blocked_range<size_t>& r) {
    lsk::TraceContext c = base;
    std::vector<uint64_t>& out = found.local();
    std::vector<uint32_t> stack;
    for (size_t i = r.begin(); i != r.end(); ++i) {
      const lsk::Ray& ray = rays[i];
      for (const lsk::InstanceRecord& rec : accel.instances) {
        const int depth = depth_of_mesh[rec.object];
        if (depth < 0) continue;
        glm::vec3 o, d;
        c.instance_ray(rec, ray.origin, ray.dir, o, d);
        const glm::vec3 inv = lsk::safe_reciprocal(d);
        stack.assign(1, rec.root);
        while (!stack.empty()) {
          const uint32_t n = stack.back();
          stack.pop_back();
          const lsk::BvhNode& node = accel.nodes[n];
          float t_near;
          if (!lsk::ray_box(o, inv, ray.tmin, ray.tmax, node.lo, node.hi, t_near)) continue;
          if (accel.node_ls[n] != lsk::LS_INVALID) {
            const lsk::LsNode& ls = accel.ls_nodes[accel.node_ls[n]];
            uint32_t shaft;
            float t_in, t_out;
            if (lsk::ls_line_shaft(o, d, inv, ls.lo, ls.hi, ls.scale, ls.n, shaft, t_in, t_out))
              out.push_back(uint64_t(accel.node_ls[n]) << 32 | shaft);
            continue;
          }
          if (node.count == 0 && subtrees.depth[n] < depth) {
            stack.push_back(node.first);
            stack.push_back(node.first + 1);
          }
        }
      }
    }
  });
  std::vector<uint64_t> shafts;
  for (const std::vector<uint64_t>& f : found) shafts.insert(shafts.end(), f.begin(), f.end());
  std::sort(shafts.begin(), shafts.end());
  shafts.erase(std::unique(shafts.begin(), shafts.end()), shafts.end());
  std::vector<uint32_t> prims(shafts.size());
  const uint32_t instance = ls_search_instance(accel);
  ls::parallel_for(tbb::blocked_range<size_t>(0, shafts.size(), 16), [&](const tbb::blocked_range<size_t>& r) {
    throw_if_interrupted();
    lsk::TraceContext c = base;
    for (size_t k = r.begin(); k != r.end(); ++k) {
      const lsk::LsNode& ls = accel.ls_nodes[size_t(shafts[k] >> 32)];
      prims[k] = c.ls_find_candidate(ls.node, ls, uint32_t(shafts[k]), uint32_t(options.further_rays), instance);
    }
  });
  for (size_t k = 0; k < shafts.size(); ++k) store_ls_candidate(accel, size_t(shafts[k] >> 32), uint32_t(shafts[k]), prims[k]);
  return shafts.size();
}

// The greedy multiple-choice knapsack for one multiplier: each object moves along the lower convex
// hull of its options' (bytes, error - lambda x saved), best improvement per byte first, while the
// bytes fit.  Returns the chosen option per object.
std::vector<size_t> knapsack(const std::vector<std::vector<PlanOption>>& options, double lambda, size_t room) {
  struct Step {
    size_t object, from, to;
    double bytes, cost;
  };
  std::vector<Step> steps;
  for (size_t o = 0; o < options.size(); ++o) {
    const std::vector<PlanOption>& opts = options[o];
    std::vector<size_t> order(opts.size());
    for (size_t k = 0; k < order.size(); ++k) order[k] = k;
    std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return opts[a].bytes < opts[b].bytes; });
    auto cost = [&](size_t k) { return opts[k].error - lambda * opts[k].saved; };
    std::vector<size_t> hull{0};  // from "none": 0 bytes, cost 0
    for (size_t k : order) {
      if (k == 0 || !opts[k].offered || cost(k) >= cost(hull.back())) continue;  // dearer and no better: never on the hull
      while (hull.size() >= 2) {
        const size_t a = hull[hull.size() - 2], b = hull.back();
        // b lies on or above the segment a -> k: drop it.
        const double lhs = (cost(b) - cost(a)) * double(opts[k].bytes - opts[a].bytes);
        const double rhs = (cost(k) - cost(a)) * double(opts[b].bytes - opts[a].bytes);
        if (lhs >= rhs) hull.pop_back();
        else break;
      }
      if (opts[k].bytes == opts[hull.back()].bytes) hull.pop_back();  // same bytes, lower cost
      hull.push_back(k);
    }
    for (size_t i = 1; i < hull.size(); ++i)
      steps.push_back({o, hull[i - 1], hull[i], double(opts[hull[i]].bytes) - double(opts[hull[i - 1]].bytes),
                       cost(hull[i]) - cost(hull[i - 1])});
  }
  std::stable_sort(steps.begin(), steps.end(), [](const Step& a, const Step& b) {
    const double ea = a.bytes > 0.0 ? a.cost / a.bytes : -std::numeric_limits<double>::infinity();
    const double eb = b.bytes > 0.0 ? b.cost / b.bytes : -std::numeric_limits<double>::infinity();
    return ea < eb;
  });
  std::vector<size_t> choice(options.size(), 0);
  std::vector<bool> blocked(options.size(), false);
  double spent = 0.0;
  for (const Step& s : steps) {
    if (blocked[s.object] || choice[s.object] != s.from) continue;
    if (spent + s.bytes > double(room)) {
      blocked[s.object] = true;
      continue;
    }
    spent += s.bytes;
    choice[s.object] = s.to;
  }
  return choice;
}

// One kind of pilot ray (closest hit or any hit) with its exact answers and work.
struct PilotSet {
  std::vector<lsk::Ray> rays;
  bool any_hit = false;
  Traced exact;
};

// What a structure does on `subset` of a pilot set: wrong answers (pilot_answer_wrong) and work.
struct Outcome {
  size_t wrong = 0;
  double work = 0.0;
};

std::vector<lsk::Ray> gather(const PilotSet& set, const std::vector<uint32_t>& subset) {
  std::vector<lsk::Ray> rays(subset.size());
  for (size_t i = 0; i < subset.size(); ++i) rays[i] = set.rays[subset[i]];
  return rays;
}

Outcome run_on(const Accel& accel, const LsLookup& lookup, const PilotSet& set, const std::vector<uint32_t>& subset, double tolerance) {
  const std::vector<lsk::Ray> rays = gather(set, subset);
  const Traced got = trace_counted(accel, lookup, rays, set.any_hit);
  Outcome o;
  o.work = got.work;
  for (size_t i = 0; i < rays.size(); ++i)
    o.wrong += pilot_answer_wrong(rays[i], got.hits[i], set.exact.hits[subset[i]], set.any_hit, tolerance);
  return o;
}

}  // namespace

LsPilot ls_budget_pilot(const Scene& scene, const Accel& exact, size_t count) {
  LsPilot pilot;
  try {
    pilot.rays = generate_rays(scene, exact, RayKind::Diffuse, std::max<size_t>(1, count), kPilotSeed);
  } catch (const InputError& e) {  // name the rays: the user asked for none
    throw InputError(std::string("2l-ls:auto's pilot (diffuse rays from the camera's view, which measure each object's "
                                 "error): ") + e.what());
  }
  // Shadow rays as the path tracer casts them: from each exact hit, offset, to a point on a light
  // picked by power, both ends offset; none where the light lies behind the surface.
  const SurfaceLookup surfaces(scene);
  const LightSet lights(scene, surfaces);
  if (lights.lights.empty()) return pilot;
  for (uint32_t i = 0; i < pilot.rays.size(); ++i) {
    const lsk::Hit h = trace_ray(trace_context(exact), exact, pilot.rays[i], false);
    if (h.triangle == lsk::LS_INVALID) continue;
    const SurfacePoint sp = surfaces.at(h, pilot.rays[i].dir);
    const float pick = lsk::random01(kPilotSeed, i, 0, 1, 0);
    const size_t l = std::min(size_t(std::upper_bound(lights.cdf.begin(), lights.cdf.end(), pick) - lights.cdf.begin()),
                              lights.lights.size() - 1);
    const lsk::ShadeLight& light = lights.lights[l];
    const glm::vec3 q = lsk::sample_triangle(light.a, light.b, light.c, lsk::random01(kPilotSeed, i, 0, 1, 1),
                                             lsk::random01(kPilotSeed, i, 0, 1, 2));
    const glm::vec3 origin = lsk::offset_ray_origin(sp.position, sp.geometric_normal, surfaces.scene_scale());
    const glm::vec3 nl = glm::dot(light.normal, origin - q) < 0.0f ? -light.normal : light.normal;
    const glm::vec3 target = lsk::offset_ray_origin(q, nl, surfaces.scene_scale());
    lsk::Ray r;
    r.origin = origin;
    r.tmin = 0.0f;
    r.dir = target - origin;
    r.tmax = 1.0f;
    if (glm::dot(sp.geometric_normal, r.dir) > 0.0f) pilot.shadow_rays.push_back(r);
  }
  return pilot;
}

bool pilot_answer_wrong(const lsk::Ray& ray, const lsk::Hit& got, const lsk::Hit& exact, bool any_hit, double tolerance) {
  if (any_hit) return (got.triangle != lsk::LS_INVALID) != (exact.triangle != lsk::LS_INVALID);
  return pilot_answer_moved(ray, got, exact, tolerance);
}

double pilot_tolerance(const Scene& scene) { return kMoveTolerance * double(glm::length(world_bounds(scene).extent())); }

bool pilot_answer_moved(const lsk::Ray& ray, const lsk::Hit& got, const lsk::Hit& exact, double tolerance) {
  const bool hit = got.triangle != lsk::LS_INVALID, hit_exact = exact.triangle != lsk::LS_INVALID;
  if (hit != hit_exact) return true;
  if (!hit || (got.instance == exact.instance && got.triangle == exact.triangle)) return false;
  if (got.instance != exact.instance) return true;
  return double(std::fabs(got.t - exact.t)) * double(glm::length(ray.dir)) > tolerance;
}

PlanChoice optimise_plan(const std::vector<std::vector<PlanOption>>& options, size_t room, const std::vector<size_t>& reference) {
  const size_t objects = options.size();
  PlanChoice out;
  out.choice.assign(objects, 0);
  if (reference.empty()) return out;  // nothing to be as fast as: no Line Space errs least
  auto totals = [&](const std::vector<size_t>& ch, double& error, double& saved) {
    error = saved = 0.0;
    for (size_t o = 0; o < objects; ++o) error += options[o][ch[o]].error, saved += options[o][ch[o]].saved;
  };
  double ref_error, ref_saved;
  totals(reference, ref_error, ref_saved);
  std::vector<size_t> best;
  double best_error = std::numeric_limits<double>::infinity(), best_lambda = 0.0;
  auto consider = [&](double lambda) {
    const std::vector<size_t> ch = knapsack(options, lambda, room);
    double error, saved;
    totals(ch, error, saved);
    const bool feasible = saved >= ref_saved;
    if (feasible && error < best_error) best = ch, best_error = error, best_lambda = lambda;
    return feasible;
  };
  if (!consider(0.0)) {
    double lo = 0.0, hi = 1e-6;
    while (!consider(hi) && hi < 1e9) lo = hi, hi *= 4.0;
    for (int i = 0; i < 60 && hi < 1e9; ++i) {
      const double mid = 0.5 * (lo + hi);
      (consider(mid) ? hi : lo) = mid;
    }
  }
  if (best.empty() || best_error >= ref_error) {
    out.choice = reference;
    out.reference_chosen = true;
    best_error = ref_error;
  } else {
    out.choice = best;
    out.lambda = best_lambda;
  }
  // Then single-object moves that keep both constraints and lower the error, best first, until none.
  std::vector<size_t>& ch = out.choice;
  size_t bytes = 0;
  double saved = 0.0;
  for (size_t o = 0; o < objects; ++o) bytes += options[o][ch[o]].bytes, saved += options[o][ch[o]].saved;
  while (true) {
    size_t move_o = objects, move_k = 0;
    double gain = 0.0;
    for (size_t o = 0; o < objects; ++o)
      for (size_t k = 0; k < options[o].size(); ++k) {
        const PlanOption &now = options[o][ch[o]], &next = options[o][k];
        if (!next.offered || bytes - now.bytes + next.bytes > room || saved - now.saved + next.saved < ref_saved) continue;
        if (now.error - next.error > gain) gain = now.error - next.error, move_o = o, move_k = k;
      }
    if (move_o == objects) break;
    bytes += options[move_o][move_k].bytes - options[move_o][ch[move_o]].bytes;
    saved += options[move_o][move_k].saved - options[move_o][ch[move_o]].saved;
    ch[move_o] = move_k;
    out.reference_chosen = false;
  }
  return out;
}

LsPlan plan_line_space_budget(const Scene& scene, Accel& accel, const AccelOptions& accel_options) {
  const LsBuildOptions& options = accel_options.ls;
  const LsLookup& lookup = accel_options.plan.lookup;
  const auto start = std::chrono::steady_clock::now();
  if (!accel.spec.two_level()) throw InputError("--ls-budget plans two-level structures only (2l-ls:auto)");
  LsPlan plan;
  plan.budget = accel_options.plan.budget;
  plan.fixed_bytes = line_space_fixed_bytes(accel);
  if (plan.fixed_bytes > plan.budget)
    throw InputError("--ls-budget " + std::to_string(double(plan.budget) / 1e6) + " MB is below what any Line Space of this scene takes (" +
                     std::to_string(double(plan.fixed_bytes) / 1e6) + " MB of per-triangle candidate records and per-node indices): raise --ls-budget");
  const size_t room = plan.budget - plan.fixed_bytes;
  const size_t meshes = scene.meshes.size();
  const BvhSubtrees subtrees = bvh_subtrees(accel);

  // The pilot: diffuse and shadow rays, their exact answers and the exact traversal's work (no Line
  // Space yet).
  LsPilot pilot = ls_budget_pilot(scene, accel, accel_options.plan.rays);
  std::array<PilotSet, 2> sets;
  sets[0].rays = std::move(pilot.rays);
  sets[1].rays = std::move(pilot.shadow_rays);
  sets[1].any_hit = true;
  for (PilotSet& set : sets) set.exact = trace_counted(accel, lookup, set.rays, set.any_hit);
  plan.pilot_rays = sets[0].rays.size();
  plan.pilot_shadow_rays = sets[1].rays.size();
  const double per_ray = 1.0 / double(plan.pilot_rays + plan.pilot_shadow_rays);
  const double tolerance = pilot_tolerance(scene);

  // Per object: the pilot rays whose exact segment (any-hit: the whole segment) crosses one of its
  // instance boxes (the only rays its Line Space can change), and the diffuse pilot rays that hit it.
  std::vector<std::vector<Bounds>> boxes(meshes);
  std::vector<size_t> instances(meshes, 0), hits(meshes, 0);
  for (const Instance& inst : scene.instances) {
    ++instances[inst.mesh];
    const uint32_t root = accel.object_roots[inst.mesh];
    const Bounds b = transform_bounds(inst.object_to_world, Bounds{accel.nodes[root].lo, accel.nodes[root].hi});
    const glm::vec3 slack = 1e-5f * (b.extent() + glm::abs(b.lo) + glm::abs(b.hi));  // the transform's rounding
    boxes[inst.mesh].push_back(Bounds{b.lo - slack, b.hi + slack});
  }
  for (const lsk::Hit& h : sets[0].exact.hits)
    if (h.triangle != lsk::LS_INVALID) ++hits[scene.instances[h.instance].mesh];
  std::array<std::vector<std::vector<uint32_t>>, 2> relevant;  // [set][mesh]: ray indices
  for (size_t k = 0; k < sets.size(); ++k) {
    const PilotSet& set = sets[k];
    std::vector<std::vector<uint32_t>> crossing(set.rays.size());
    ls::parallel_for(size_t(0), set.rays.size(), [&](size_t i) {
      const lsk::Ray& r = set.rays[i];
      const glm::vec3 inv = lsk::safe_reciprocal(r.dir);
      const bool closest = !set.any_hit && set.exact.hits[i].triangle != lsk::LS_INVALID;
      const float t_end = closest ? set.exact.hits[i].t : r.tmax;
      for (uint32_t m = 0; m < meshes; ++m)
        for (const Bounds& b : boxes[m]) {
          float t_near;
          if (lsk::ray_box(r.origin, inv, r.tmin, t_end, b.lo, b.hi, t_near)) {
            crossing[i].push_back(m);
            break;
          }
        }
    });
    relevant[k].resize(meshes);
    for (uint32_t i = 0; i < set.rays.size(); ++i)
      for (uint32_t m : crossing[i]) relevant[k][m].push_back(i);
  }

  // The vertex normals of every object, once for all evaluations.
  LsBuildOptions scratch = options;
  scratch.progress = {};
  scratch.objects.assign(meshes, ObjectLs{0, 1});
  compute_line_space_records(scene, subtrees, scratch, accel);

  // Every object's options, each evaluated with a Line Space on that object alone.
  const std::vector<ObjectLs> menu = ls_budget_menu();
  std::vector<std::vector<PlanOption>> options_of(meshes, std::vector<PlanOption>(1));  // [0]: none
  std::vector<std::vector<size_t>> index_of(meshes, std::vector<size_t>(menu.size(), 0));  // menu entry -> option
  std::vector<std::vector<size_t>> menu_bytes(meshes, std::vector<size_t>(menu.size(), 0));
  std::vector<bool> placeable(meshes, false);
  for (uint32_t m = 0; m < meshes; ++m) {
    const uint32_t root = accel.object_roots[m];
    if (root == lsk::LS_INVALID) continue;
    const bool reached = !relevant[0][m].empty() || !relevant[1][m].empty();
    std::vector<lsk::Ray> batch = gather(sets[0], relevant[0][m]), shadow_batch = gather(sets[1], relevant[1][m]);
    batch.insert(batch.end(), shadow_batch.begin(), shadow_batch.end());  // every ray that can look it up
    double exact_work = -1.0;
    for (size_t e = 0; e < menu.size(); ++e) {
      const ObjectLs c = menu[e];
      const size_t bytes = placement_bytes(place_line_spaces(accel, subtrees, root, c.depth, c.n, options));
      if (bytes == 0) continue;  // no subtree of this object qualifies at this depth
      placeable[m] = true;
      menu_bytes[m][e] = bytes;
      if (bytes > room) continue;
      PlanOption opt{c, bytes, 0.0, 0.0};
      if (reached) {
        if (exact_work < 0.0) {
          accel.node_ls.clear();
          exact_work = run_on(accel, lookup, sets[0], relevant[0][m], tolerance).work + run_on(accel, lookup, sets[1], relevant[1][m], tolerance).work;
        }
        LsBuildOptions single = scratch;
        single.objects.assign(meshes, ObjectLs{});
        single.objects[m] = c;
        layout_line_space_nodes(single, accel_options.limits, subtrees, accel);
        std::vector<int> depth_of_mesh(meshes, -1);
        depth_of_mesh[m] = c.depth;
        plan.shafts_searched += search_shafts_of(accel, batch, subtrees, depth_of_mesh, options);
        const Outcome a = run_on(accel, lookup, sets[0], relevant[0][m], tolerance), b = run_on(accel, lookup, sets[1], relevant[1][m], tolerance);
        opt.error = double(a.wrong + b.wrong) * per_ray;
        opt.saved = (exact_work - a.work - b.work) * per_ray;
        ++plan.evaluations;
      }
      // No ray moved and under a hundredth of a box test saved per ray: nothing measurable to buy
      // (the reference may still hold it).
      opt.offered = !(opt.error == 0.0 && opt.saved < kNegligibleWork);
      index_of[m][e] = options_of[m].size();
      options_of[m].push_back(opt);
    }
  }

  // The reference: the uniform structure of the menu with the most bytes that fit.
  size_t ref = menu.size();
  size_t ref_bytes = 0;
  double ref_error = 0.0;
  for (size_t e = 0; e < menu.size(); ++e) {
    size_t bytes = 0;
    double error = 0.0;
    bool fits = true;
    for (size_t m = 0; m < meshes && fits; ++m) {
      if (menu_bytes[m][e] == 0) continue;
      if (index_of[m][e] == 0) fits = false;  // this object's part alone is over the budget
      else {
        const PlanOption& o = options_of[m][index_of[m][e]];
        bytes += o.bytes, error += o.error;
      }
    }
    if (!fits || bytes > room) continue;
    if (ref == menu.size() || bytes > ref_bytes || (bytes == ref_bytes && error < ref_error))
      ref = e, ref_bytes = bytes, ref_error = error;
  }

  // Least error at no less saved work than the reference (ls_budget.h).
  std::vector<size_t> reference;
  if (ref < menu.size()) {
    plan.reference = "2l-ls:" + std::to_string(menu[ref].depth) + ":" + std::to_string(menu[ref].n);
    for (size_t m = 0; m < meshes; ++m) reference.push_back(index_of[m][ref]);
  }
  const PlanChoice optimised = optimise_plan(options_of, room, reference);
  const std::vector<size_t>& choice = optimised.choice;
  plan.lambda = optimised.lambda;
  plan.reference_chosen = optimised.reference_chosen;

  for (uint32_t m = 0; m < meshes; ++m) {
    if (accel.object_roots[m] == lsk::LS_INVALID) continue;
    LsPlanRow row;
    row.mesh = m;
    row.name = scene.meshes[m].name;
    row.triangles = scene.meshes[m].triangles.size();
    row.instances = instances[m];
    row.hits = hits[m];
    row.relevant = relevant[0][m].size() + relevant[1][m].size();
    const PlanOption& o = options_of[m][choice[m]];
    row.chosen = o.ls;
    row.bytes = o.bytes;
    row.error = o.error;
    row.saved_work = o.saved;
    if (ref < menu.size() && menu_bytes[m][ref] > 0) row.reference = menu[ref];
    row.reason = o.ls.n > 0 ? "chosen" : !placeable[m] ? "too small" : row.relevant == 0 ? "not reached" : "no gain";
    plan.predicted_bytes += row.bytes;
    plan.rows.push_back(row);
  }
  plan.predicted_bytes += plan.fixed_bytes;

  // The plan and the reference on the pilot, every object's Line Space at once.
  auto joint = [&](const std::vector<ObjectLs>& objects) {
    PilotFigures f;
    LsBuildOptions all = scratch;
    all.objects = objects;
    layout_line_space_nodes(all, accel_options.limits, subtrees, accel);
    f.bytes_ls = accel.bytes_ls();
    std::vector<int> depth_of_mesh(meshes, -1);
    for (size_t m = 0; m < meshes; ++m)
      if (objects[m].n > 0) depth_of_mesh[m] = objects[m].depth;
    std::vector<lsk::Ray> all_rays = sets[0].rays;
    all_rays.insert(all_rays.end(), sets[1].rays.begin(), sets[1].rays.end());
    plan.shafts_searched += search_shafts_of(accel, all_rays, subtrees, depth_of_mesh, options);
    for (const PilotSet& set : sets) {
      std::vector<uint32_t> every(set.rays.size());
      for (uint32_t i = 0; i < every.size(); ++i) every[i] = i;
      const Outcome o = run_on(accel, lookup, set, every, tolerance);
      f.error += double(o.wrong) * per_ray;
      f.saved_work += (set.exact.work - o.work) * per_ray;
    }
    return f;
  };
  plan.plan = joint(plan.objects(meshes));
  if (ref < menu.size()) {
    std::vector<ObjectLs> uniform(meshes);
    for (size_t m = 0; m < meshes; ++m)
      if (menu_bytes[m][ref] > 0) uniform[m] = menu[ref];
    plan.uniform = joint(uniform);
  }

  // Leave no Line Space behind: build_accel lays out the plan's.
  accel.node_ls.clear();
  accel.ls_nodes.clear();
  accel.ls_candidates.clear();
  accel.ls_records.clear();
  accel.ls_info = LsBuildInfo{};
  plan.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return plan;
}

}  // namespace ls
