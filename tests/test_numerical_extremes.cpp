// Numerical extremes end to end: builtin:cornell scaled by 1e-20 .. 1e20 and moved 1e6 away renders
// with finite pixels, and (where float can still represent the scene) the same picture as at scale 1.
#include "common/render/render_types.h"
#include "cpu/build/build_accel.h"
#include "cpu/build/build_structures.h"
#include "cpu/render/path_tracer.h"
#include "scenes/load_scene.h"

#include <catch2/catch.hpp>

#include <cmath>

using namespace ls;

namespace {

RenderResult render_small(const Scene& scene) {
  RenderOptions o;
  o.schedule = parse_schedule("bvh");
  o.bounces = 2;
  o.spp = 4;
  o.width = o.height = 24;
  auto built = build_schedule_structures(scene, o.schedule);
  return render(scene, built, o);
}

double mean_luminance(const RenderResult& r) {
  double sum = 0.0;
  for (const glm::vec3& p : r.total) sum += 0.2126 * p.x + 0.7152 * p.y + 0.0722 * p.z;
  return sum / double(r.total.size());
}

bool all_finite(const RenderResult& r) {
  for (const auto& img : r.bounce_images)
    for (const glm::vec3& p : img)
      if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) return false;
  for (const glm::vec3& p : r.total)
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) return false;
  return true;
}

}  // namespace

TEST_CASE("scaled scenes from 1e-20 to 1e20 render the picture of scale 1 with finite pixels", "[extremes]") {
  const RenderResult reference = render_small(builtin_scene("cornell"));
  const double expected = mean_luminance(reference);
  REQUIRE(expected > 0.0);
  for (const float scale : {1e-20f, 0x1p-60f, 1e-10f, 1e10f, 0x1p60f, 1e20f}) {
    Scene scene = builtin_scene("cornell");
    scale_and_offset(scene, scale, glm::vec3(0.0f));
    const RenderResult r = render_small(scene);
    INFO("scale " << scale << ": mean luminance " << mean_luminance(r) << ", at scale 1 " << expected);
    CHECK(all_finite(r));
    CHECK(r.dropped_samples == 0);
    // Same random numbers, same paths up to rounding: the mean brightness agrees closely.
    CHECK(mean_luminance(r) == Approx(expected).epsilon(0.02));
  }
}

TEST_CASE("a power-of-two scale changes no decision: the image is the scale-1 image", "[extremes]") {
  const RenderResult reference = render_small(builtin_scene("cornell"));
  for (const float scale : {0x1p-64f, 0x1p64f}) {
    Scene scene = builtin_scene("cornell");
    scale_and_offset(scene, scale, glm::vec3(0.0f));
    const RenderResult r = render_small(scene);
    INFO("scale " << scale);
    double worst = 0.0;
    for (size_t i = 0; i < r.total.size(); ++i)
      worst = std::max(worst, double(glm::length(r.total[i] - reference.total[i]) / (glm::length(reference.total[i]) + 1e-3f)));
    CHECK(worst < 1e-4);
  }
}

// The SAH's costs are areas: squared, times a triangle count, in float. At 2^64 they overflowed and
// at 2^-64 they fell to subnormals, so the tree (and every Line Space answer with it) changed with
// the scale. Every box must be the scale-1 box times the scale, every other field equal.
TEST_CASE("a power-of-two scale builds the scale-1 BVH and Line Space, every box scaled", "[extremes]") {
  AccelOptions options;
  options.ls.min_triangles = 0;
  for (const char* name : {"f-ls:4:4", "2l-ls:2:4"}) {
    const Accel reference = build_accel(builtin_scene("cornell"), parse_structure(name), options);
    REQUIRE(!reference.ls_nodes.empty());
    for (const float scale : {0x1p-100f, 0x1p-64f, 0x1p64f, 0x1p100f}) {
      Scene scene = builtin_scene("cornell");
      scale_and_offset(scene, scale, glm::vec3(0.0f));
      const Accel scaled = build_accel(scene, parse_structure(name), options);
      INFO(name << " at scale " << scale);
      // The scale is the instances' (scale_and_offset): a flat BVH's boxes scale, a two-level
      // structure's object BVHs do not and its top level's do.
      auto differing = [](const std::vector<lsk::BvhNode>& got, const std::vector<lsk::BvhNode>& want, float s) {
        if (got.size() != want.size()) return std::max(got.size(), want.size());
        size_t differ = 0;
        for (size_t i = 0; i < got.size(); ++i)
          differ += got[i].lo != want[i].lo * s || got[i].hi != want[i].hi * s || got[i].first != want[i].first ||
                    got[i].count != want[i].count;
        return differ;
      };
      const bool flat = reference.top_nodes.size() <= 1;
      CHECK(differing(scaled.nodes, reference.nodes, flat ? scale : 1.0f) == 0);
      CHECK(differing(scaled.top_nodes, reference.top_nodes, flat ? 1.0f : scale) == 0);
      CHECK(scaled.tri_ids == reference.tri_ids);
      CHECK(scaled.node_ls == reference.node_ls);
      CHECK(scaled.ls_candidates == reference.ls_candidates);
    }
  }
}

// Mesh files have no camera: framing_camera puts one before the scene's bounds. In float their squared
// extent overflowed past 1.8e19 (a camera at infinity: a blank image, exit 0) and underflowed below
// 1e-19 (a camera 1 away from a scene 1e-25 across).
TEST_CASE("the framing camera of a scene scaled by a power of two is the scale-1 camera scaled", "[extremes]") {
  const Camera reference = framing_camera(builtin_scene("cornell"));
  for (const float scale : {0x1p-90f, 0x1p-64f, 0x1p64f, 0x1p70f, 0x1p100f}) {
    Scene scene = builtin_scene("cornell");
    scale_and_offset(scene, scale, glm::vec3(0.0f));
    const Camera cam = framing_camera(scene);
    INFO("scale " << scale);
    CHECK(cam.position == reference.position * scale);
    CHECK(cam.target == reference.target * scale);
    CHECK(cam.yfov == reference.yfov);
  }
  // 1e38 across: the camera would stand past float's range.
  Scene huge = builtin_scene("cornell");
  scale_and_offset(huge, 1e38f, glm::vec3(0.0f));
  CHECK_THROWS_WITH(framing_camera(huge), Catch::Contains("cannot be placed in float"));
}

TEST_CASE("scenes moved 1e6 away render finite pixels, and so do scenes float cannot resolve", "[extremes]") {
  const RenderResult reference = render_small(builtin_scene("cornell"));
  {
    // A room 2000 wide, 1e6 from the origin: a float step there (1/16) is far below its detail.
    Scene scene = builtin_scene("cornell");
    scale_and_offset(scene, 1e3f, glm::vec3(1e6f, -1e6f, 1e6f));
    const RenderResult r = render_small(scene);
    INFO("mean luminance " << mean_luminance(r) << ", at the origin " << mean_luminance(reference));
    CHECK(all_finite(r));
    CHECK(r.dropped_samples == 0);
    CHECK(mean_luminance(r) == Approx(mean_luminance(reference)).epsilon(0.05));
  }
  // A room 2 wide 1e6 away is 32 float steps across, coarser than the 256-ulp self-intersection
  // offset (kernels/offset_ray.h, 16 units there); 1e-20 of it collapses onto one point; 1e20 with an
  // offset of 1e6 is the 1e20 scene.  None is a faithful picture; each must stay finite.
  for (const float scale : {1.0f, 1e-20f, 1e20f}) {
    Scene scene = builtin_scene("cornell");
    scale_and_offset(scene, scale, glm::vec3(1e6f));
    INFO("scale " << scale << " offset 1e6");
    const RenderResult r = render_small(scene);
    CHECK(all_finite(r));
  }
}
