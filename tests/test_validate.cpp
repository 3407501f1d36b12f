// The validator's studies against what they must show by construction: an approximation that refuses
// everything has no error, bounces before the switch are untouched, and the heat-map, the Pareto
// front and the tables agree with independent computations.
#include "common/render/image_metrics.h"
#include "common/render/render_types.h"
#include "common/structure/accel.h"
#include "cpu/app/cpu_backend.h"
#include "scenes/load_scene.h"
#include "validate/bias_estimate.h"
#include "validate/heatmap.h"
#include "validate/policy_study.h"
#include "validate/rmse_study.h"
#include "validate/sweep.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <random>

using namespace ls;

namespace {

ImageSettings tiny_image() {
  ImageSettings s;
  s.width = 24;
  s.height = 24;
  s.spp = 2;
  s.bounces = 3;
  return s;
}

void quiet(const std::string&) {}

// A render of options.spp samples as the studies make it, rendered here directly: half A the first
// ceil(spp / 2) sample indices, half B the rest, and both averaged with their sample counts.
struct Halves {
  RenderResult a, b;
  int n_a = 0, n_b = 0;
  std::vector<glm::vec3> total() const {
    std::vector<glm::vec3> out;
    const double wa = double(n_a) / double(n_a + n_b), wb = 1.0 - wa;
    for (size_t i = 0; i < a.total.size(); ++i) out.push_back(glm::vec3(wa * glm::dvec3(a.total[i]) + wb * glm::dvec3(b.total[i])));
    return out;
  }
};

Halves render_halves(StudyRenderer& renderer, RenderOptions o) {
  Halves h;
  h.n_a = o.spp - o.spp / 2;
  h.n_b = o.spp / 2;
  o.spp = h.n_a;
  h.a = renderer.render(o);
  o.first_sample = uint32_t(h.n_a);
  o.spp = h.n_b;
  h.b = renderer.render(o);
  return h;
}

}  // namespace

TEST_CASE("refusal angle 0: every Line Space gives RMSE 0 on every bounce", "[validate]") {
  const Scene scene = load_scene("builtin:cornell");
  AccelOptions options;
  options.ls.min_triangles = 0;
  StudyRenderer renderer(make_cpu_backend(), scene, options);
  ImageSettings refuse_all = tiny_image();
  refuse_all.lookup.angle_degrees = 0.0f;
  const RmseStudy study = run_rmse_study(renderer, "builtin:cornell", parse_structure_list("f-ls:6:4,2l-ls:2:4"),
                                         refuse_all, "", 0.1f, quiet);
  REQUIRE(study.rows.size() == 6);
  for (const RmseRow& r : study.rows) {
    INFO(r.structure << " from bounce " << r.start_bounce);
    REQUIRE(r.refused.empty());
    REQUIRE(r.rmse == 0.0);
    // The same random numbers make equal images in each half: no noise, no bias, nothing uncertain.
    REQUIRE(r.bias.rmse_bias == 0.0);
    REQUIRE(r.bias.rmse_bias_stderr == 0.0);
    REQUIRE(r.bias.noise_floor == 0.0);
    REQUIRE(r.contribution_rmse.size() == 4);
    for (double c : r.contribution_rmse) REQUIRE(c == 0.0);
  }
}

TEST_CASE("switching to the Line Space at bounce k leaves the bounces before k bit-identical", "[validate]") {
  const Scene scene = load_scene("builtin:cornell");
  AccelOptions options;
  options.ls.min_triangles = 0;
  StudyRenderer renderer(make_cpu_backend(), scene, options);
  const ImageSettings settings = tiny_image();
  Reference reference = render_reference(renderer, settings);
  const StructureSpec ls = parse_structure("f-ls:8:6");
  for (int k = 1; k <= settings.bounces; ++k) {
    INFO("start bounce " << k);
    const Measured m = measure(renderer, schedule_from(ls, k), settings, reference);
    for (int j = 0; j < k; ++j) REQUIRE(m.result.bounce_images[size_t(j)] == reference.result.bounce_images[size_t(j)]);
    // The approximation is really in use from bounce k on, or the check above proves nothing.
    double later = 0.0;
    for (int j = k; j <= settings.bounces; ++j) later += m.contribution_rmse[size_t(j)];
    REQUIRE(later > 0.0);
  }
}

TEST_CASE("the rmse study's figures equal a direct computation from the two renders", "[validate]") {
  const Scene scene = load_scene("builtin:generated:3000:6:2");
  StudyRenderer renderer(make_cpu_backend(), scene, AccelOptions{});
  const ImageSettings settings = tiny_image();
  const RmseStudy study =
      run_rmse_study(renderer, "generated", parse_structure_list("2l-ls:2:4"), settings, "", 0.1f, quiet);
  const Halves reference = render_halves(renderer, settings.options(parse_schedule("bvh")));
  const Halves direct = render_halves(renderer, settings.options(schedule_from(parse_structure("2l-ls:2:4"), 2)));
  const RmseRow* row = study.find("2l-ls:2:4", 2);
  REQUIRE(row);
  const float e = exposure_scale(reference.total());
  REQUIRE(row->rmse == Approx(rmse(reference.total(), direct.total(), e)).epsilon(1e-9));
  REQUIRE(row->spp == settings.spp);
  const BiasEstimate bias = estimate_bias(reference.a.total, direct.a.total, reference.b.total, direct.b.total, e,
                                          direct.n_a, direct.n_b);
  REQUIRE(row->bias.rmse_bias == bias.rmse_bias);
  REQUIRE(row->bias.rmse_bias_stderr == bias.rmse_bias_stderr);
  REQUIRE(row->bytes == renderer.structure(parse_structure("2l-ls:2:4")).bytes_total());
  // The Markdown summary has the reference line and one line per structure.
  REQUIRE(study.summary().rows.size() == 2);
}

TEST_CASE("the heat-map's per-pixel errors give back the RMSE", "[validate]") {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(0.0f, 2.0f);
  Image a{19, 11, {}}, b{19, 11, {}};
  for (int i = 0; i < 19 * 11; ++i) {
    a.pixels.emplace_back(u(rng), u(rng), u(rng));
    b.pixels.emplace_back(u(rng), u(rng), u(rng));
  }
  const float e = exposure_scale(a.pixels);
  const std::vector<float> err = pixel_errors(a, b, e);
  double sum = 0.0;
  for (float x : err) sum += double(x) * double(x);
  REQUIRE(std::sqrt(sum / double(err.size())) == Approx(rmse(a.pixels, b.pixels, e)).epsilon(1e-6));
  // Identical images: a black map.
  const Image same = error_heatmap(a, a, e, 0.1f);
  for (const glm::vec3& p : same.pixels) REQUIRE(glm::all(glm::lessThan(p, glm::vec3(0.002f))));  // the ramp starts at sRGB (0, 0, 4)
  REQUIRE_THROWS_AS(pixel_errors(a, Image{11, 19, b.pixels}, e), InputError);
}

TEST_CASE("a sweep over the smallest subtree and the behind mode measures each point as its own run would", "[validate]") {
  const Scene scene = load_scene("builtin:cornell");
  const ImageSettings settings = tiny_image();
  SweepGrid grid;
  grid.families = {StructureKind::FlatLs, StructureKind::TwoLevelLs};
  grid.depths = {2};
  grid.subdivisions = {4};
  grid.behinds = {LsBehind::Exact, LsBehind::Reverse};
  grid.min_triangles = {0, 1u << 30};  // every subtree, then none: no Line Space at all
  StudyRenderer sweeping(make_cpu_backend(), scene, AccelOptions{});
  const Sweep sweep = run_sweep(sweeping, "builtin:cornell", grid, settings, quiet);
  REQUIRE(sweep.points.size() == 8);
  size_t i = 0;
  for (uint32_t min_triangles : grid.min_triangles)
    for (LsBehind behind : grid.behinds)
      for (const char* structure : {"f-ls:2:4", "2l-ls:2:4"}) {
        const SweepPoint& p = sweep.points[i++];
        INFO(structure << " " << ls_behind_name(behind) << " min-triangles " << min_triangles);
        REQUIRE(p.structure == structure);
        REQUIRE(p.behind == behind);
        REQUIRE(p.min_triangles == min_triangles);
        REQUIRE(p.refused.empty());
        // A renderer of its own, built with this smallest subtree and traced with this mode.
        AccelOptions options;
        options.ls.min_triangles = min_triangles;
        StudyRenderer alone(make_cpu_backend(), scene, options);
        ImageSettings lookup = settings;
        lookup.lookup.behind = behind;
        Reference reference = render_reference(alone, lookup);
        const Measured m = measure(alone, schedule_from(parse_structure(structure), 1), lookup, reference);
        REQUIRE(p.ls_nodes == alone.structure(parse_structure(structure)).ls_info.ls_nodes);
        REQUIRE(p.rmse == m.rmse);
        REQUIRE(p.bias.rmse_bias == m.bias.rmse_bias);
        if (min_triangles == 0) {
          REQUIRE(p.ls_nodes > 0);
          REQUIRE(p.rmse > 0.0);  // the Line Space is in use, or the equalities above prove little
        } else {
          REQUIRE(p.ls_nodes == 0);
          REQUIRE(p.rmse == 0.0);  // no Line Space: the exact BVH's image
        }
      }
  REQUIRE(i == sweep.points.size());
  // The modes answer differently somewhere, or the behind axis would not be tested.
  REQUIRE(sweep.points[0].rmse != sweep.points[2].rmse);
}

TEST_CASE("the Pareto front is exactly the points no other point dominates", "[validate]") {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<SweepPoint> points(40);
  for (SweepPoint& p : points) {
    p.bias.rmse_bias = std::round(u(rng) * 20.0) / 20.0;  // ties on purpose
    p.rmse = 1.0 - p.bias.rmse_bias;                      // the front is drawn on rmse_bias, not on the RMSE
    p.speedup = std::round(u(rng) * 40.0) / 20.0;  // each beside its own timing of the exact F-BVH
    p.mrays_per_s = 2.0 - p.speedup;                // the front is drawn on the speed-up, not on MRays/s
  }
  points[5].refused = "over budget";
  const double reference = 1.0;  // the exact F-BVH: RMSE 0 at speed-up 1
  mark_pareto(points);
  int front = 0;
  for (size_t i = 0; i < points.size(); ++i) {
    bool dominated = !points[i].refused.empty();
    const double ei = points[i].bias.rmse_bias;
    if (reference >= points[i].speedup && (reference > points[i].speedup || ei > 0.0)) dominated = true;
    for (size_t j = 0; j < points.size(); ++j) {
      const double ej = points[j].bias.rmse_bias;
      if (j != i && points[j].refused.empty() && ej <= ei && points[j].speedup >= points[i].speedup &&
          (ej < ei || points[j].speedup > points[i].speedup))
        dominated = true;
    }
    REQUIRE(points[i].pareto == !dominated);
    front += points[i].pareto;
  }
  REQUIRE(front >= 1);
  // Every point faster than the reference that no one dominates is on the front, so the front is not empty.
}

TEST_CASE("list flags of the validator reject nonsense", "[validate]") {
  REQUIRE(parse_int_list("0,4,8", "--depths", 0, 60) == std::vector<int>{0, 4, 8});
  REQUIRE_THROWS_AS(parse_int_list("4,", "--depths", 0, 60), InputError);
  REQUIRE_THROWS_AS(parse_int_list("4,x", "--depths", 0, 60), InputError);
  REQUIRE_THROWS_AS(parse_int_list("61", "--depths", 0, 60), InputError);
  REQUIRE_THROWS_AS(parse_int_list("", "--depths", 0, 60), InputError);
  REQUIRE_THROWS_AS(parse_angle_list("91"), InputError);
  REQUIRE_THROWS_AS(parse_angle_list("nan"), InputError);
  REQUIRE_THROWS_AS(parse_families("f-ls,bvh"), InputError);
  REQUIRE(parse_behind_list("reverse,exact") == std::vector<LsBehind>{LsBehind::Reverse, LsBehind::Exact});
  REQUIRE_THROWS_AS(parse_behind_list("exact,ahead"), InputError);
  REQUIRE(parse_min_triangles_list("0,512") == std::vector<uint32_t>{0, 512});
  REQUIRE_THROWS_AS(parse_min_triangles_list("-1"), InputError);
  // Repeats are dropped, each item at its first place (they rendered the same configuration twice).
  REQUIRE(parse_int_list("8,2,8,2,4", "--depths", 0, 60) == std::vector<int>{8, 2, 4});
  REQUIRE(parse_angle_list("30,45,30") == std::vector<float>{30.0f, 45.0f});
  REQUIRE(parse_families("2l-ls,f-ls,2l-ls") == std::vector<StructureKind>{StructureKind::TwoLevelLs, StructureKind::FlatLs});
  REQUIRE(parse_behind_list("exact,exact") == std::vector<LsBehind>{LsBehind::Exact});
  REQUIRE(parse_min_triangles_list("512,0,512") == std::vector<uint32_t>{512, 0});
}

TEST_CASE("interpolation on the policy curves: linear between neighbours, none outside", "[validate]") {
  const std::vector<std::pair<double, double>> points = {{1.0, 3.0}, {0.0, 0.0}, {0.5, 1.0}};  // unsorted on purpose
  REQUIRE(interpolate(points, 0.25) == Approx(0.5));
  REQUIRE(interpolate(points, 0.75) == Approx(2.0));
  REQUIRE(interpolate(points, 0.5) == 1.0);
  REQUIRE(interpolate(points, 1.0) == 3.0);
  REQUIRE(interpolate(points, 0.0) == 0.0);
  REQUIRE(std::isnan(interpolate(points, 1.01)));
  REQUIRE(std::isnan(interpolate(points, -0.01)));
  REQUIRE(std::isnan(interpolate({}, 0.0)));
  REQUIRE(interpolate({{0.0, 1.0}, {0.0, 5.0}, {1.0, 2.0}}, 0.0) == 1.0);  // equal x: the first given
  REQUIRE(parse_threshold_list("0.3,0.1,0.3") == std::vector<float>{0.1f, 0.3f});
  for (const char* bad : {"0", "-1", "nan", "inf", "0.1,", ",0.1", "x", ""}) REQUIRE_THROWS_AS(parse_threshold_list(bad), InputError);
}

TEST_CASE("the policy study's RMSE and rays on X equal a direct computation from the renders", "[validate]") {
  const Scene scene = load_scene("builtin:cornell");
  AccelOptions options;
  options.ls.min_triangles = 0;
  StudyRenderer renderer(make_cpu_backend(), scene, options);
  const ImageSettings settings = tiny_image();
  const StructureSpec x = parse_structure("f-ls:3:6");
  const PolicyStudy study = run_policy_study(renderer, "builtin:cornell", x, {1, 3}, {0.3f, 0.6f}, settings, quiet);
  REQUIRE(study.points.size() == 4);
  const Halves reference_halves = render_halves(renderer, settings.options(parse_schedule("bvh")));
  const float e_halves = exposure_scale(reference_halves.total());
  auto indirect = [](const RenderResult& r, int from) {
    uint64_t n = 0;
    for (size_t k = size_t(from); k < r.bounces.size(); ++k) n += r.bounces[k].extension_rays + r.bounces[k].shadow_rays;
    return n;
  };
  for (const PolicyPoint& p : study.points) {
    INFO(p.policy << " " << p.label());
    RenderOptions o = settings.options(p.policy == "bounce" ? schedule_from(x, p.start_bounce) : parse_schedule("bvh"));
    if (p.policy == "throughput") o.throughput_switch = ThroughputSwitch{p.threshold, x};
    const RenderResult r = renderer.render(o);
    const Halves h = render_halves(renderer, o);
    REQUIRE(p.rmse == Approx(rmse(reference_halves.total(), h.total(), e_halves)).epsilon(1e-9));
    REQUIRE(p.rmse > 0.0);
    const double direct = estimate_bias(reference_halves.a.total, h.a.total, reference_halves.b.total, h.b.total, e_halves,
                                        h.n_a, h.n_b).rmse_bias;
    if (std::isnan(direct))  // undetermined on this tiny image (bias_estimate.h): so must the study's be
      REQUIRE(std::isnan(p.bias.rmse_bias));
    else
      REQUIRE(p.bias.rmse_bias == direct);
    REQUIRE(p.indirect_rays == indirect(r, 1));
    if (p.policy == "bounce") {
      REQUIRE(p.rays_on_x == indirect(r, p.start_bounce));  // every ray from the start bounce on
    } else {
      uint64_t switched = 0;
      for (size_t k = 1; k < r.bounces.size(); ++k) switched += r.bounces[k].switched_extension_rays + r.bounces[k].switched_shadow_rays;
      REQUIRE(p.rays_on_x == switched);
      REQUIRE(r.bounces[0].switched_extension_rays == 0);  // T <= 1: camera rays stay exact
    }
  }
  // Each comparison interpolates the throughput points (and the reference at 0) at the bounce point's fraction.
  REQUIRE(study.comparisons.size() == 2);
  for (const PolicyComparison& c : study.comparisons) {
    std::vector<std::pair<double, double>> curve = {{0.0, 0.0}};
    for (const PolicyPoint& p : study.points)
      if (p.policy == "throughput") curve.push_back({p.fraction_on_x(), p.rmse});
    std::sort(curve.begin(), curve.end());
    double expected = std::nan("");
    for (size_t i = 0; i + 1 < curve.size(); ++i)
      if (curve[i].first <= c.fraction_on_x && c.fraction_on_x <= curve[i + 1].first)
        expected = curve[i].second + (curve[i + 1].second - curve[i].second) * (c.fraction_on_x - curve[i].first) /
                                         (curve[i + 1].first - curve[i].first);
    INFO("from bounce " << c.start_bounce << " at " << c.fraction_on_x);
    if (std::isnan(expected)) REQUIRE(std::isnan(c.throughput_rmse_at_fraction));
    else REQUIRE(c.throughput_rmse_at_fraction == Approx(expected));
  }
}

TEST_CASE("the two halves are the plain render's samples, split: first_sample 0 changes nothing", "[validate]") {
  const Scene scene = load_scene("builtin:cornell");
  StudyRenderer renderer(make_cpu_backend(), scene, AccelOptions{});
  RenderOptions o = tiny_image().options(parse_schedule("bvh"));
  o.spp = 5;
  const RenderResult plain = renderer.render(o);
  RenderOptions explicit_zero = o;
  explicit_zero.first_sample = 0;
  REQUIRE(renderer.render(explicit_zero).total == plain.total);
  const Halves h = render_halves(renderer, o);
  REQUIRE(h.n_a == 3);
  REQUIRE(h.n_b == 2);
  REQUIRE(h.a.total != h.b.total);  // other sample indices, other random numbers
  const std::vector<glm::vec3> combined = h.total();
  for (size_t i = 0; i < plain.total.size(); ++i)
    for (int c = 0; c < 3; ++c) REQUIRE(combined[i][c] == Approx(plain.total[i][c]).epsilon(1e-5).margin(1e-6));
  // What the studies render is exactly that.
  const SplitRender split = render_split(renderer, o);
  REQUIRE(split.spp == std::array<int, 2>{3, 2});
  REQUIRE(split.half[0].total == h.a.total);
  REQUIRE(split.half[1].total == h.b.total);
  REQUIRE(split.combined.bounces[1].extension_rays == plain.bounces[1].extension_rays);
}

TEST_CASE("rmse_bias of a real Line Space stays put from 4 to 16 spp while the RMSE falls", "[validate]") {
  // From inside the box, close to the blocks, where f-ls:4:2's error stands well above the noise that
  // 4 spp leave in the estimate (from the classic view, 48 x 48 pixels, the noise dominates).
  Scene scene = load_scene("builtin:cornell");
  scene.camera.position = {0.0f, 0.0f, 0.97f};
  scene.camera.target = {0.0f, 0.0f, -1.0f};
  scene.camera.yfov = 0.96f;
  AccelOptions options;
  options.ls.min_triangles = 0;
  StudyRenderer renderer(make_cpu_backend(), scene, options);
  ImageSettings settings = tiny_image();
  settings.width = settings.height = 48;
  std::vector<RmseRow> rows;
  for (int spp : {4, 16}) {
    settings.spp = spp;
    rows.push_back(*run_rmse_study(renderer, "builtin:cornell", parse_structure_list("f-ls:4:2"), settings, "", 0.1f, quiet)
                        .find("f-ls:4:2", 1));
  }
  const BiasEstimate &b4 = rows[0].bias, &b16 = rows[1].bias;
  INFO("4 spp: RMSE " << rows[0].rmse << ", rmse_bias " << b4.rmse_bias << " ± " << b4.rmse_bias_stderr);
  INFO("16 spp: RMSE " << rows[1].rmse << ", rmse_bias " << b16.rmse_bias << " ± " << b16.rmse_bias_stderr);
  REQUIRE(b16.rmse_bias > 3.0 * b16.rmse_bias_stderr);  // a real bias, seen
  REQUIRE(std::abs(b4.rmse_bias - b16.rmse_bias) <=
          3.0 * std::sqrt(b4.rmse_bias_stderr * b4.rmse_bias_stderr + b16.rmse_bias_stderr * b16.rmse_bias_stderr));
  REQUIRE(rows[0].rmse > rows[1].rmse);
}

TEST_CASE("spp auto: each configuration doubles its samples until rmse_bias is known, or the time is up", "[validate]") {
  const Scene scene = load_scene("builtin:cornell");
  AccelOptions options;
  options.ls.min_triangles = 0;
  StudyRenderer renderer(make_cpu_backend(), scene, options);
  ImageSettings settings = tiny_image();
  settings.spp = 4;
  settings.auto_spp.enabled = true;
  settings.auto_spp.rel_stderr = 0.3;
  settings.auto_spp.seconds = 60.0;
  settings.auto_spp.max_spp = 256;
  const RmseStudy study = run_rmse_study(renderer, "builtin:cornell", parse_structure_list("f-ls:4:2"), settings, "", 0.1f, quiet);
  for (const RmseRow& r : study.rows) {
    INFO("from bounce " << r.start_bounce << ": " << r.spp << " spp, " << r.spp_stop << ", rmse_bias " << r.bias.rmse_bias
                        << " ± " << r.bias.rmse_bias_stderr);
    REQUIRE((r.spp == 4 || r.spp == 8 || r.spp == 16 || r.spp == 32 || r.spp == 64 || r.spp == 128 || r.spp == 256));
    if (r.spp_stop == "converged") REQUIRE(r.bias.rmse_bias_stderr <= 0.3 * r.bias.rmse_bias);
    else REQUIRE((r.spp_stop == "max spp" || r.spp_stop == "time budget"));
    if (r.spp_stop == "max spp") REQUIRE(r.spp == 256);
  }
  REQUIRE(study.json()["spp_auto"]["rel_stderr"] == 0.3);
  // An exact approximation converges at once: its rmse_bias is 0 with no uncertainty.
  settings.lookup.angle_degrees = 0.0f;
  settings.auto_spp.seconds = 1e6;
  for (const RmseRow& r : run_rmse_study(renderer, "builtin:cornell", parse_structure_list("f-ls:4:2"), settings, "", 0.1f, quiet).rows) {
    REQUIRE(r.spp == 4);
    REQUIRE(r.spp_stop == "converged");
  }
  // A budget too short for any doubling stops at the start.
  settings.lookup.angle_degrees = 45.0f;
  settings.auto_spp.seconds = 1e-9;
  settings.auto_spp.rel_stderr = 1e-6;
  for (const RmseRow& r : run_rmse_study(renderer, "builtin:cornell", parse_structure_list("f-ls:4:2"), settings, "", 0.1f, quiet).rows) {
    REQUIRE(r.spp == 4);
    REQUIRE(r.spp_stop == "time budget");
  }
}
