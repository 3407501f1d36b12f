// The reference traversal's work split at the Line Space nodes, and `linespace-validate bound` built on
// it: checked against the exact structures' own counts, against closed forms at D = 0 and D = 1, and
// against the subtrees derived independently from the triangle ranges.
#include "common/structure/accel.h"
#include "cpu/build/build_accel.h"
#include "cpu/trace/ray_generators.h"
#include "cpu/trace/trace_rays.h"
#include "scenes/load_scene.h"
#include "validate/bound_study.h"

#include <catch2/catch.hpp>

using namespace ls;

namespace {

struct Traced {
  TraceWorkTotals work;
  lsk::LsCounters counters{};
};

Traced reference_work(const Accel& accel, const std::vector<lsk::Ray>& rays, bool split = true, const LsLookup& lookup = {}) {
  Traced t;
  std::vector<lsk::Hit> hits(rays.size());
  const std::vector<uint8_t> ls_subtrees = split ? line_space_subtrees(accel) : std::vector<uint8_t>();
  trace_rays(accel, lookup, rays.data(), hits.data(), rays.size(), false, &t.counters, Traversal::Reference, &t.work, &ls_subtrees);
  return t;
}

AccelOptions paper() {
  AccelOptions o;
  o.ls.min_triangles = 0;  // the paper's behaviour: every node at depth D, small ones too
  return o;
}

LsLookup refuse_all() {  // a refusal angle of 0: every lookup refused
  LsLookup l;
  l.angle_degrees = 0.0f;
  return l;
}

// Rays whose line enters the box of nodes[root] within [tmin, tmax], as the kernel's root test decides.
uint64_t rays_entering(const Accel& accel, uint32_t root, const std::vector<lsk::Ray>& rays) {
  uint64_t n = 0;
  for (const lsk::Ray& r : rays) {
    float t_near;
    n += lsk::ray_box(r.origin, lsk::safe_reciprocal(r.dir), r.tmin, r.tmax, accel.nodes[root].lo, accel.nodes[root].hi, t_near);
  }
  return n;
}

}  // namespace

TEST_CASE("every lookup refused, a Line Space structure does its BVH's work and counts its lookups", "[work_bound]") {
  const Scene scene = load_scene("builtin:cornell");
  const Accel bvh = build_accel(scene, parse_structure("bvh"));
  const Accel two_level = build_accel(scene, parse_structure("2l-bvh"));
  const std::vector<lsk::Ray> rays = generate_rays(scene, bvh, RayKind::Diffuse, 4000, 7);
  const Traced flat_exact = reference_work(bvh, rays);
  const Traced two_level_exact = reference_work(two_level, rays);
  REQUIRE(flat_exact.work.box_tests > rays.size());
  for (const char* name : {"f-ls:0:2", "f-ls:3:4", "f-ls:6:2", "2l-ls:0:2", "2l-ls:2:3"}) {
    INFO(name);
    const Accel accel = build_accel(scene, parse_structure(name), paper());
    const Traced t = reference_work(accel, rays, true, refuse_all());
    const Traced& exact = accel.spec.two_level() ? two_level_exact : flat_exact;
    CHECK(t.work.box_tests == exact.work.box_tests);
    CHECK(t.work.triangle_tests == exact.work.triangle_tests);
    CHECK(t.work.lookups == t.counters.lookups);
    CHECK(t.work.lookups > 0);
    CHECK(t.work.box_tests_in_ls < t.work.box_tests);
    CHECK(t.work.triangle_tests_in_ls <= t.work.triangle_tests);
    CHECK(exact.work.box_tests_in_ls == 0);  // no Line Space, nothing below one
    CHECK(exact.work.triangle_tests_in_ls == 0);
    // Not asked for, the split is not made: the same totals, nothing counted apart.
    const Traced unsplit = reference_work(accel, rays, false, refuse_all());
    CHECK(unsplit.work.box_tests == t.work.box_tests);
    CHECK(unsplit.work.triangle_tests == t.work.triangle_tests);
    CHECK(unsplit.work.box_tests_in_ls == 0);
  }
}

TEST_CASE("the split at D = 0 and D = 1 has its closed form", "[work_bound]") {
  const Scene scene = load_scene("builtin:cornell");
  const Accel bvh = build_accel(scene, parse_structure("bvh"));
  std::vector<lsk::Ray> rays = generate_rays(scene, bvh, RayKind::Random, 3000, 11);  // origins in the scene's box
  for (size_t i = 0; i < 1000; ++i) {  // and rays far outside it, half of them towards it
    lsk::Ray r = rays[i];
    r.origin = glm::vec3(1e3f, 1e3f, 1e3f) + r.dir;
    if (i % 2) r.dir = -r.origin;
    rays.push_back(r);
  }
  const uint64_t entering = rays_entering(bvh, 0, rays);
  REQUIRE(entering > 0);
  REQUIRE(entering < rays.size());  // random rays: some miss the scene's box
  REQUIRE(bvh.nodes[0].count == 0);
  {
    // The root is the Line Space node: only the root's own box test is outside it.
    const Traced t = reference_work(build_accel(scene, parse_structure("f-ls:0:2"), paper()), rays, true, refuse_all());
    CHECK(t.work.box_tests - t.work.box_tests_in_ls == rays.size());
    CHECK(t.work.triangle_tests_in_ls == t.work.triangle_tests);
    CHECK(t.work.lookups == entering);
  }
  {
    // The root's two children are: the root's box and, for the rays that enter it, its children's.
    const Traced t = reference_work(build_accel(scene, parse_structure("f-ls:1:2"), paper()), rays, true, refuse_all());
    CHECK(t.work.box_tests - t.work.box_tests_in_ls == rays.size() + 2 * entering);
    CHECK(t.work.triangle_tests_in_ls == t.work.triangle_tests);
  }
}

TEST_CASE("the Line Space subtrees are the nodes whose triangles lie within a Line Space node's", "[work_bound]") {
  const Scene scene = load_scene("builtin:generated:3000:6:2");
  for (const char* name : {"f-ls:0:2", "f-ls:4:2", "f-ls:9:2", "2l-ls:0:2", "2l-ls:3:2", "f-ls:60:2", "bvh"}) {
    INFO(name);
    const Accel accel = build_accel(scene, parse_structure(name), paper());
    const std::vector<uint8_t> in_ls = line_space_subtrees(accel);
    if (!accel.spec.line_space()) {
      CHECK(in_ls.empty());
      continue;
    }
    REQUIRE(in_ls.size() == accel.nodes.size());
    // Every node covers one contiguous triangle range and children split their parent's, so a node
    // lies in an LS node's subtree exactly when its range lies within that node's.  (Objects' BVHs
    // sit one after another in nodes[] and tris[], so ranges never cross objects.)
    // An inner node's first is its children's index: its range is the union of its leaves'.
    std::vector<uint32_t> lo(accel.nodes.size(), UINT32_MAX), hi(accel.nodes.size(), 0);
    for (size_t k = 0; k < accel.nodes.size(); ++k) {
      const lsk::BvhNode& n = accel.nodes[k];
      if (n.count) {
        lo[k] = n.first;
        hi[k] = n.first + n.count;
      }
    }
    bool changed = true;
    while (changed) {  // to a fixed point: no assumption on the order of nodes[]
      changed = false;
      for (size_t k = 0; k < accel.nodes.size(); ++k) {
        const lsk::BvhNode& n = accel.nodes[k];
        if (n.count) continue;
        const uint32_t l = std::min(lo[n.first], lo[n.first + 1]), h = std::max(hi[n.first], hi[n.first + 1]);
        if (l != lo[k] || h != hi[k]) {
          lo[k] = l;
          hi[k] = h;
          changed = true;
        }
      }
    }
    std::vector<std::pair<uint32_t, uint32_t>> ls_ranges;
    for (size_t k = 0; k < accel.nodes.size(); ++k)
      if (accel.node_ls[k] != lsk::LS_INVALID) ls_ranges.emplace_back(lo[k], hi[k]);
    CHECK(ls_ranges.size() == accel.ls_info.ls_nodes);
    size_t marked = 0;
    for (size_t k = 0; k < accel.nodes.size(); ++k) {
      bool inside = false;
      for (const auto& [l, h] : ls_ranges) inside = inside || (lo[k] >= l && hi[k] <= h);
      if (in_ls[k] != uint8_t(inside)) FAIL("node " << k << ": marked " << int(in_ls[k]) << ", by its range " << inside);
      marked += in_ls[k];
    }
    if (accel.ls_info.ls_nodes == 0)
      CHECK(marked == 0);  // D past every leaf: no Line Space node, nothing below one
    else
      CHECK(marked >= accel.ls_info.ls_nodes);
  }
}

TEST_CASE("bound: the oracle is the exact work outside the Line Space nodes plus their lookups", "[work_bound]") {
  const Scene scene = load_scene("builtin:cornell");
  const Accel bvh = build_accel(scene, parse_structure("bvh"));
  const std::vector<lsk::Ray> rays = generate_rays(scene, bvh, RayKind::Diffuse, 3000, 5);
  const std::vector<StructureSpec> specs = parse_structure_list("f-ls:3:4,2l-ls:1:3,f-ls:60:2");
  const BoundStudy study = run_bound_study(scene, "builtin:cornell", rays, "diffuse", specs, paper(), LsLookup{}, [](const std::string&) {});
  REQUIRE(study.rows.size() == 3);
  const Traced flat_exact = reference_work(bvh, rays);
  for (const BoundRow& row : study.rows) {
    INFO(row.structure);
    const Accel accel = build_accel(scene, parse_structure(row.structure), paper());
    const Traced traced = reference_work(accel, rays);
    CHECK(row.traced_work.box_tests == traced.work.box_tests);
    CHECK(row.traced_work.lookups == traced.work.lookups);
    CHECK(row.traced.accepted == traced.counters.accepted);
    CHECK(row.exact_work_units() == Approx(work_units(row.exact_work.box_tests, row.exact_work.triangle_tests, 0)));
    const double outside = work_units(row.exact_work.box_tests - row.exact_work.box_tests_in_ls,
                                      row.exact_work.triangle_tests - row.exact_work.triangle_tests_in_ls, 0);
    CHECK(row.oracle_work_units() == Approx(outside + kLookupWork * double(row.exact_work.lookups)));
  }
  // The flat rows are measured against the bvh's own walk.
  CHECK(study.rows[0].exact == "bvh");
  CHECK(study.rows[0].exact_work.box_tests == flat_exact.work.box_tests);
  CHECK(study.rows[1].exact == "2l-bvh");
  // D past the leaves: no Line Space node, so no lookup, the oracle is the exact structure: bound 1.
  CHECK(study.rows[2].ls_nodes == 0);
  CHECK(study.rows[2].bound() == 1.0);
  CHECK(study.rows[2].achieved() == 1.0);
  CHECK_THROWS_AS(run_bound_study(scene, "s", rays, "r", parse_structure_list("bvh"), AccelOptions{}, LsLookup{}, [](const std::string&) {}),
                  InputError);
  CHECK_THROWS_AS(run_bound_study(scene, "s", {}, "r", specs, AccelOptions{}, LsLookup{}, [](const std::string&) {}), InputError);
}
