// Exact traversal of F-BVH and 2L-BVH (common/kernels/traverse_bvh.h through cpu/accel) against a
// brute-force loop over every world triangle, against each other, and against the promises of the
// kernels: watertightness, closed boxes, in-plane rays, degenerate triangles, [tmin, tmax], numerical
// extremes, and ray offsets that never re-hit their own triangle.
//
// The brute force uses the very same triangle kernel (lsk::ray_triangle) on the world-space triangles
// the flat structure stores, each triangle tested independently over the ray's whole [tmin, tmax],
// closest t winning and ties going to the lower (instance, triangle).  So the flat BVH must match it
// exactly (ids and the bits of t, u, v).  The two-level BVH works in object space on a transformed
// ray, so it must match up to ties (another triangle at the same distance), rays that graze an edge
// (where the world-to-object rounding decides) and hits at an interval end, with t within 1e-5
// relative to (t + |origin| / |dir|), divided by the cosine of incidence (a rounded origin moves a
// grazing hit further: see t_error and t_tolerance).
//
// Everything is deterministic: std::mt19937 with fixed seeds, floats from the top 24 bits of a draw.
// Reports carry the bits of the rays and triangles involved, enough to reproduce a failure alone.
#include <catch2/catch.hpp>

#include "common/base/parallel.h"
#include "common/kernels/offset_ray.h"
#include "common/kernels/ray_triangle.h"
#include "common/model/scene.h"
#include "common/model/structure_name.h"
#include "common/render/surface.h"
#include "common/structure/accel.h"
#include "cpu/build/build_accel.h"
#include "cpu/trace/trace_rays.h"
#include "tests/test_helpers.h"

#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>
#include <map>
#include <random>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

using namespace test_support;  // Rng: floats from the top 24 bits of a draw

namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr uint32_t kNone = lsk::LS_INVALID;
constexpr double kRelT = 1e-5;     // t tolerance between structures that round differently
constexpr double kEdgeBary = 1e-4;  // a hit this close (in barycentrics) to an edge may flip between structures

// ---------------------------------------------------------------------------------------------------
// Reporting.

std::string fbits(float x) {
  char buf[64];
  uint32_t u;
  std::memcpy(&u, &x, 4);
  std::snprintf(buf, sizeof buf, "%a (0x%08x)", double(x), u);
  return buf;
}

std::string describe(const lsk::Ray& r) {
  std::ostringstream s;
  s << "ray o=(" << fbits(r.origin.x) << ", " << fbits(r.origin.y) << ", " << fbits(r.origin.z) << ") d=("
    << fbits(r.dir.x) << ", " << fbits(r.dir.y) << ", " << fbits(r.dir.z) << ") tmin=" << fbits(r.tmin)
    << " tmax=" << fbits(r.tmax);
  return s.str();
}

std::string describe(const lsk::Hit& h) {
  std::ostringstream s;
  if (h.triangle == kNone) {
    s << "miss (t=" << fbits(h.t) << ")";
  } else {
    s << "hit inst=" << h.instance << " tri=" << h.triangle << " t=" << fbits(h.t) << " u=" << h.u << " v=" << h.v;
  }
  return s.str();
}

bool is_hit(const lsk::Hit& h) { return h.triangle != kNone; }
bool same_ids(const lsk::Hit& a, const lsk::Hit& b) { return a.instance == b.instance && a.triangle == b.triangle; }
bool same_bits(float a, float b) { return std::memcmp(&a, &b, 4) == 0; }

// ---------------------------------------------------------------------------------------------------
// Scenes.

// A closed, consistently oriented sphere: the icosahedron subdivided `levels` times, on the unit sphere.
ls::Mesh icosphere(int levels) {
  const float g = 1.61803398875f;
  std::vector<glm::vec3> p = {{-1, g, 0}, {1, g, 0}, {-1, -g, 0}, {1, -g, 0}, {0, -1, g}, {0, 1, g},
                              {0, -1, -g}, {0, 1, -g}, {g, 0, -1}, {g, 0, 1}, {-g, 0, -1}, {-g, 0, 1}};
  for (glm::vec3& v : p) v = glm::normalize(v);
  std::vector<glm::uvec3> t = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                               {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
                               {3, 8, 9},  {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (int l = 0; l < levels; ++l) {
    std::map<std::pair<uint32_t, uint32_t>, uint32_t> mid;
    const auto midpoint = [&](uint32_t a, uint32_t b) {
      const auto key = std::make_pair(std::min(a, b), std::max(a, b));
      const auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      p.push_back(glm::normalize(p[a] + p[b]));
      mid[key] = uint32_t(p.size() - 1);
      return uint32_t(p.size() - 1);
    };
    std::vector<glm::uvec3> next;
    for (const glm::uvec3& f : t) {
      const uint32_t a = midpoint(f.x, f.y), b = midpoint(f.y, f.z), c = midpoint(f.z, f.x);
      next.push_back({f.x, a, c});
      next.push_back({f.y, b, a});
      next.push_back({f.z, c, b});
      next.push_back({a, b, c});
    }
    t = next;
  }
  return make_mesh(p, t);
}

// The cube [-1, 1]^3, two triangles per face sharing the face diagonal.
ls::Mesh cube() {
  std::vector<glm::vec3> p;
  for (int i = 0; i < 8; ++i) p.push_back(glm::vec3((i & 1) ? 1.0f : -1.0f, (i & 2) ? 1.0f : -1.0f, (i & 4) ? 1.0f : -1.0f));
  // Faces as quads (outward counter-clockwise), split along the a-c diagonal.
  const uint32_t q[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  std::vector<glm::uvec3> t;
  for (const auto& f : q) {
    t.push_back({f[0], f[1], f[2]});
    t.push_back({f[0], f[2], f[3]});
  }
  return make_mesh(p, t);
}

glm::mat4 transform(const glm::vec3& translate, float angle, const glm::vec3& axis, const glm::vec3& scale) {
  glm::mat4 m = glm::translate(glm::mat4(1.0f), translate);
  m = glm::rotate(m, angle, axis);
  return glm::scale(m, scale);
}

ls::Scene scene_of(std::vector<ls::Mesh> meshes, const std::vector<std::pair<uint32_t, glm::mat4>>& placed) {
  ls::Scene s;
  s.name = "test";
  s.materials.push_back(ls::Material{});
  s.meshes = std::move(meshes);
  for (const auto& [mesh, m] : placed) {
    ls::Instance inst;
    inst.mesh = mesh;
    inst.object_to_world = m;
    s.instances.push_back(inst);
  }
  ls::validate_scene(s);
  return s;
}

// Soup, sphere and grid placed several times with rotations, non-uniform and mirroring scales.
ls::Scene instanced_scene(uint32_t seed) {
  std::vector<ls::Mesh> meshes;
  meshes.push_back(random_soup(300, seed, 1.0f, 0.2f));
  meshes.push_back(icosphere(2));
  meshes.push_back(square_grid(8));
  meshes.push_back(cube());
  Rng rng(seed + 1);
  std::vector<std::pair<uint32_t, glm::mat4>> placed;
  for (uint32_t i = 0; i < 14; ++i) {
    glm::vec3 scale = rng.vec(0.4f, 1.6f);
    if (i % 3 == 1) scale.x = -scale.x;                // mirror: negative determinant
    if (i % 5 == 2) scale = -scale;                     // point reflection
    if (i % 4 == 3) scale = glm::vec3(0.8f);            // uniform
    const glm::vec3 axis = glm::normalize(rng.vec(-1.0f, 1.0f) + glm::vec3(0.01f));
    const float angle = i % 6 == 0 ? 0.0f : rng.range(0.0f, 6.28f);
    placed.push_back({i % 4, transform(rng.vec(-3.0f, 3.0f), angle, axis, scale)});
  }
  return scene_of(std::move(meshes), placed);
}

// ---------------------------------------------------------------------------------------------------
// Brute force over the world triangles, in (instance, triangle) order, with the flat builder's vertices.

struct WorldTris {
  std::vector<glm::vec3> v;  // 3 per triangle
  std::vector<uint32_t> inst, tri;
  size_t size() const { return inst.size(); }
};

WorldTris world_tris(const ls::Scene& scene) {
  WorldTris w;
  for (size_t i = 0; i < scene.instances.size(); ++i) {
    const ls::Instance& in = scene.instances[i];
    const ls::Mesh& m = scene.meshes[in.mesh];
    for (size_t t = 0; t < m.triangles.size(); ++t) {
      for (int k = 0; k < 3; ++k) w.v.push_back(ls::transform_point(in.object_to_world, m.positions[m.triangles[t][k]]));
      w.inst.push_back(uint32_t(i));
      w.tri.push_back(uint32_t(t));
    }
  }
  return w;
}

lsk::Hit brute(const WorldTris& w, const lsk::Ray& ray) {
  lsk::Hit best;
  best.t = kInf;
  best.instance = best.triangle = kNone;
  best.u = best.v = 0.0f;
  const lsk::TriRay tr = lsk::make_tri_ray(ray.origin, ray.dir);
  for (size_t k = 0; k < w.size(); ++k) {
    float t, u, v;
    if (!lsk::ray_triangle(tr, ray.tmin, ray.tmax, w.v[3 * k], w.v[3 * k + 1], w.v[3 * k + 2], t, u, v)) continue;
    // Triangles come in increasing (instance, triangle) order: on equal t the earlier one stays.
    if (best.triangle == kNone || t < best.t) {
      best.t = t;
      best.u = u;
      best.v = v;
      best.instance = w.inst[k];
      best.triangle = w.tri[k];
    }
  }
  return best;
}

std::vector<lsk::Hit> brute_all(const WorldTris& w, const std::vector<lsk::Ray>& rays) {
  std::vector<lsk::Hit> hits(rays.size());
  ls::parallel_for(size_t(0), rays.size(), [&](size_t i) { hits[i] = brute(w, rays[i]); });
  return hits;
}

std::vector<lsk::Hit> trace_all(const ls::Accel& a, const std::vector<lsk::Ray>& rays, bool any_hit = false) {
  std::vector<lsk::Hit> hits(rays.size());
  ls::trace_rays(a, ls::LsLookup{}, rays.data(), hits.data(), rays.size(), any_hit);
  return hits;
}

// The world-space triangle a hit names.
void world_triangle(const ls::Scene& s, uint32_t inst, uint32_t tri, glm::vec3& a, glm::vec3& b, glm::vec3& c) {
  const ls::Instance& in = s.instances[inst];
  const ls::Mesh& m = s.meshes[in.mesh];
  a = ls::transform_point(in.object_to_world, m.positions[m.triangles[tri].x]);
  b = ls::transform_point(in.object_to_world, m.positions[m.triangles[tri].y]);
  c = ls::transform_point(in.object_to_world, m.positions[m.triangles[tri].z]);
}

// ---------------------------------------------------------------------------------------------------
// Comparisons.

std::string describe_triangle(const ls::Scene& s, const lsk::Hit& h) {
  if (!is_hit(h)) return "";
  glm::vec3 p[3];
  world_triangle(s, h.instance, h.triangle, p[0], p[1], p[2]);
  std::ostringstream out;
  out << "    world triangle (" << h.instance << ", " << h.triangle << "):";
  for (const glm::vec3& v : p) out << " (" << fbits(v.x) << ", " << fbits(v.y) << ", " << fbits(v.z) << ")";
  return out.str();
}

// Exact agreement: ids and the bits of t, u, v.
size_t count_exact_mismatches(const ls::Scene& scene, const std::vector<lsk::Ray>& rays, const std::vector<lsk::Hit>& ref,
                              const std::vector<lsk::Hit>& got, const char* what) {
  size_t bad = 0, missed = 0, extra = 0, farther = 0, nearer = 0, tie = 0, other = 0;
  for (size_t i = 0; i < rays.size(); ++i) {
    const bool ok = same_ids(ref[i], got[i]) && same_bits(ref[i].t, got[i].t) &&
                    (!is_hit(ref[i]) || (same_bits(ref[i].u, got[i].u) && same_bits(ref[i].v, got[i].v)));
    if (ok) continue;
    ++bad;
    // Count by kind; show the first example of each kind.
    size_t* counter = &other;
    if (is_hit(ref[i]) && !is_hit(got[i])) counter = &missed;
    else if (!is_hit(ref[i]) && is_hit(got[i])) counter = &extra;
    else if (got[i].t > ref[i].t) counter = &farther;
    else if (got[i].t < ref[i].t) counter = &nearer;
    else if (!same_ids(ref[i], got[i])) counter = &tie;
    if (++*counter == 1)
      UNSCOPED_INFO(what << " ray " << i << ": " << describe(rays[i]) << "\n  reference " << describe(ref[i]) << "\n"
                         << describe_triangle(scene, ref[i]) << "\n  got       " << describe(got[i]) << "\n"
                         << describe_triangle(scene, got[i]));
  }
  if (bad)
    UNSCOPED_INFO(what << ": " << bad << " of " << rays.size() << " rays differ: " << missed << " hits missed, " << extra
                       << " extra hits, " << farther << " farther hits, " << nearer << " nearer hits, " << tie
                       << " other triangle at the same t, " << other << " same triangle with other u, v");
  return bad;
}

double rel(double a, double b) { return a == b ? 0.0 : std::fabs(a - b) / std::max(std::fabs(a), std::fabs(b)); }

float min_bary(const lsk::Hit& h) { return std::min({h.u, h.v, 1.0f - h.u - h.v}); }

// |cos| of the angle between a ray direction and the normal of the world triangle a hit names.
double incidence(const ls::Scene& s, const lsk::Hit& h, const glm::vec3& dir) {
  glm::vec3 a, b, c;
  world_triangle(s, h.instance, h.triangle, a, b, c);
  const glm::dvec3 n = glm::cross(glm::dvec3(b) - glm::dvec3(a), glm::dvec3(c) - glm::dvec3(a));
  const double ln = glm::length(n), ld = glm::length(glm::dvec3(dir));
  return ln > 0.0 && ld > 0.0 ? std::fabs(glm::dot(n, glm::dvec3(dir))) / (ln * ld) : 0.0;
}

// A relative tolerance on t for structures whose inputs differ by a few ulps (a transformed ray, scaled
// vertices): t moves by (input error) / cos(incidence), so the tolerance grows the same way at
// grazing incidence.
double t_tolerance(double base, double cos_incidence) { return base / std::max(cos_incidence, 1e-6); }

// The difference of two t of one ray relative to t plus the origin's magnitude (in units of the
// direction): rounding the ray's origin (a world-to-object transform, a translated scene) moves the hit
// by a few ulps of |origin|, which is large against t for hits close to an origin far from 0.
double t_error(double a, double b, const lsk::Ray& r) {
  if (a == b) return 0.0;
  const double scale = std::max(std::fabs(a), std::fabs(b)) +
                       glm::length(glm::dvec3(r.origin)) / std::max(glm::length(glm::dvec3(r.dir)), 1e-300);
  return std::fabs(a - b) / scale;
}

struct Agreement {
  size_t rays = 0, hits = 0, same = 0, ties = 0, edges = 0, boundary = 0, bad_ids = 0, bad_t = 0, nan_t = 0;
  size_t t_within_base = 0, common_hits = 0;  // common hits with t within the base tolerance (no angle factor)
  double max_rel_t = 0.0, max_rel_t_cos = 0.0;
  std::string examples;  // the first few disagreements, with the bits to reproduce them
};

// Agreement of two structures that round differently.  Same ids: t within t_tolerance.  Different ids:
// a tie (both hit, t within t_tolerance), an edge graze (the nearer hit lies within kEdgeBary / cos of
// an edge of its triangle), or an interval boundary (the nearer hit's t is within t_tolerance of tmin or
// tmax); anything else is a mismatch.  `scale` multiplies the reference t before comparing.
Agreement compare_approx(const ls::Scene& scene, const std::vector<lsk::Ray>& rays, const std::vector<lsk::Hit>& ref,
                         const std::vector<lsk::Hit>& got, const char* what, double scale = 1.0, double base = kRelT) {
  Agreement a;
  a.rays = rays.size();
  size_t reported = 0;
  for (size_t i = 0; i < rays.size(); ++i) {
    const lsk::Hit& r = ref[i];
    const lsk::Hit& g = got[i];
    if (std::isnan(g.t) || std::isnan(r.t)) ++a.nan_t;
    if (is_hit(r)) ++a.hits;
    const double rt = double(r.t) * scale, gt = double(g.t);
    if (same_ids(r, g)) {
      ++a.same;
      if (!is_hit(r)) continue;
      ++a.common_hits;
      const double e = rel(rt, gt), cs = incidence(scene, r, rays[i].dir), eo = t_error(rt, gt, rays[i]);
      a.max_rel_t = std::max(a.max_rel_t, e);
      a.max_rel_t_cos = std::max(a.max_rel_t_cos, eo * cs);
      if (e <= base) ++a.t_within_base;
      if (!(eo <= t_tolerance(base, cs))) {
        ++a.bad_t;
        if (++reported <= 4) {
          std::ostringstream m;
          m << "\n" << what << " ray " << i << " t differs (rel " << e << ", cos " << cs << "): " << describe(rays[i])
            << "\n  reference " << describe(r) << "\n  got       " << describe(g) << "\n" << describe_triangle(scene, g);
          a.examples += m.str();
        }
      }
      continue;
    }
    const bool r_nearer = !is_hit(g) || (is_hit(r) && rt <= gt);
    const lsk::Hit& nearer = r_nearer ? r : g;
    const double tn = r_nearer ? rt : gt;
    const double cs = incidence(scene, nearer, rays[i].dir);
    const double tol = t_tolerance(base, cs);
    if (is_hit(r) && is_hit(g) && t_error(rt, gt, rays[i]) <= tol) {
      ++a.ties;
      continue;
    }
    if (min_bary(nearer) <= kEdgeBary / std::max(cs, 1e-6)) {
      ++a.edges;
      continue;
    }
    const double tmin = double(rays[i].tmin) * (r_nearer ? scale : 1.0), tmax = double(rays[i].tmax) * (r_nearer ? scale : 1.0);
    if ((tmin > 0.0 && t_error(tn, tmin, rays[i]) <= tol) || (std::isfinite(tmax) && t_error(tn, tmax, rays[i]) <= tol)) {
      ++a.boundary;
      continue;
    }
    ++a.bad_ids;
    if (++reported <= 4) {
      std::ostringstream m;
      m << "\n" << what << " ray " << i << " ids differ: " << describe(rays[i]) << "\n  reference " << describe(r) << "\n"
        << describe_triangle(scene, r) << "\n  got       " << describe(g) << "\n" << describe_triangle(scene, g);
      a.examples += m.str();
    }
  }
  return a;
}

std::string summary(const Agreement& a) {
  std::ostringstream s;
  s << a.rays << " rays, " << a.hits << " reference hits, " << a.same << " same ids, " << a.ties << " ties, " << a.edges
    << " edge grazes, " << a.boundary << " interval boundaries, " << a.bad_ids << " id mismatches, " << a.bad_t
    << " t mismatches; t within " << kRelT << " on " << a.t_within_base << " of " << a.common_hits
    << " common hits; max rel t error " << a.max_rel_t << ", max t_error x cos " << a.max_rel_t_cos << a.examples;
  return s.str();
}

std::vector<lsk::Ray> random_rays(Rng& rng, size_t n, float origin_extent, float target_extent) {
  std::vector<lsk::Ray> rays;
  rays.reserve(n);
  for (size_t i = 0; i < n; ++i) {
    const glm::vec3 o = rng.vec(-origin_extent, origin_extent);
    glm::vec3 d;
    switch (i % 4) {
      case 0: d = rng.unit(); break;                                              // any direction
      case 1: d = rng.vec(-target_extent, target_extent) - o; break;              // aimed into the scene
      case 2: d = (rng.vec(-target_extent, target_extent) - o) * 37.5f; break;    // not normalised
      default: d = rng.unit() * rng.range(1e-3f, 1e3f); break;                    // odd lengths
    }
    rays.push_back(make_ray(o, d));
  }
  return rays;
}

struct Built {
  ls::Accel flat, two;
};

Built build_both(const ls::Scene& s) {
  return {ls::build_accel(s, ls::parse_structure("bvh")), ls::build_accel(s, ls::parse_structure("2l-bvh"))};
}

size_t count_nan(const std::vector<lsk::Hit>& hits) {
  return size_t(std::count_if(hits.begin(), hits.end(), [](const lsk::Hit& h) { return std::isnan(h.t); }));
}

// Brute force, F-BVH and 2L-BVH on the same rays: F exact, 2L up to ties / edge grazes, any-hit
// consistent.  random_set: the rays are random (not aimed at edges), so ties and grazes must be rare.
void check_against_brute(const ls::Scene& scene, const std::vector<lsk::Ray>& rays, const char* what, bool random_set = true) {
  const WorldTris w = world_tris(scene);
  const Built b = build_both(scene);
  const std::vector<lsk::Hit> ref = brute_all(w, rays);
  const std::vector<lsk::Hit> flat = trace_all(b.flat, rays);
  const std::vector<lsk::Hit> two = trace_all(b.two, rays);
  CHECK(count_nan(ref) == 0);
  CHECK(count_nan(flat) == 0);
  CHECK(count_nan(two) == 0);
  {
    INFO(what << ": F-BVH vs brute force");
    CHECK(count_exact_mismatches(scene, rays, ref, flat, "F-BVH") == 0);
  }
  {
    const Agreement a = compare_approx(scene, rays, ref, two, "2L-BVH");
    INFO(what << ": 2L-BVH vs brute force: " << summary(a));
    CHECK(a.bad_ids == 0);
    CHECK(a.bad_t == 0);
    CHECK(a.nan_t == 0);
    if (random_set) CHECK(a.ties + a.edges + a.boundary <= rays.size() / 1000);
  }
  // Any-hit: a hit exactly when closest-hit finds one, and the triangle it names is really hit.
  const std::vector<lsk::Hit> flat_any = trace_all(b.flat, rays, true);
  const std::vector<lsk::Hit> two_any = trace_all(b.two, rays, true);
  size_t any_bad = 0, any_unverified = 0;
  for (size_t i = 0; i < rays.size(); ++i) {
    if (is_hit(flat_any[i]) != is_hit(flat[i]) || is_hit(two_any[i]) != is_hit(two[i])) {
      if (++any_bad <= 4)
        UNSCOPED_INFO("any-hit ray " << i << ": " << describe(rays[i]) << "\n  F closest " << describe(flat[i]) << " any "
                                     << describe(flat_any[i]) << "\n  2L closest " << describe(two[i]) << " any "
                                     << describe(two_any[i]));
    }
    if (is_hit(flat_any[i])) {
      glm::vec3 p0, p1, p2;
      world_triangle(scene, flat_any[i].instance, flat_any[i].triangle, p0, p1, p2);
      float t, u, v;
      const lsk::TriRay tr = lsk::make_tri_ray(rays[i].origin, rays[i].dir);
      if (!lsk::ray_triangle(tr, rays[i].tmin, rays[i].tmax, p0, p1, p2, t, u, v) || !same_bits(t, flat_any[i].t))
        ++any_unverified;
    }
  }
  INFO(what << ": any-hit");
  CHECK(any_bad == 0);
  CHECK(any_unverified == 0);
}

}  // namespace

// ===================================================================================================

TEST_CASE("traversal: random soup against brute force", "[traversal]") {
  const ls::Scene scene = single_mesh_scene(random_soup(2000, 101));
  Rng rng(102);
  const std::vector<lsk::Ray> rays = random_rays(rng, 8000, 2.5f, 1.0f);
  check_against_brute(scene, rays, "soup");
}

TEST_CASE("traversal: instanced scene against brute force and F-BVH vs 2L-BVH", "[traversal]") {
  for (uint32_t seed : {201u, 202u}) {
    INFO("seed " << seed);
    const ls::Scene scene = instanced_scene(seed);
    Rng rng(seed * 7);
    const std::vector<lsk::Ray> rays = random_rays(rng, 5000, 5.0f, 3.5f);
    check_against_brute(scene, rays, "instanced");

    // F-BVH vs 2L-BVH directly.
    const Built b = build_both(scene);
    const Agreement a = compare_approx(scene, rays, trace_all(b.flat, rays), trace_all(b.two, rays), "F vs 2L");
    INFO("F-BVH vs 2L-BVH: " << summary(a));
    CHECK(a.bad_ids == 0);
    CHECK(a.bad_t == 0);
    CHECK(a.nan_t == 0);
    CHECK(a.ties + a.edges + a.boundary <= rays.size() / 1000);
    CHECK(a.hits > rays.size() / 4);
  }
}

TEST_CASE("traversal: N = 1 triangle scenes", "[traversal]") {
  const ls::Mesh one = make_mesh({glm::vec3(-0.5f, -0.3f, 0.1f), glm::vec3(0.7f, -0.2f, -0.2f), glm::vec3(0.1f, 0.6f, 0.3f)},
                                 {glm::uvec3(0, 1, 2)});
  Rng rng(301);
  std::vector<lsk::Ray> rays = random_rays(rng, 4000, 2.0f, 0.6f);
  // Rays aimed at interior points of the triangle must hit it.
  std::vector<lsk::Ray> aimed;
  for (int i = 0; i < 2000; ++i) {
    float u = rng.range(0.01f, 0.98f), v = rng.range(0.01f, 0.98f);
    if (u + v > 0.99f) {
      u = 0.99f - u;
      v = 0.99f - v;
    }
    const glm::vec3 target = one.positions[0] * (1.0f - u - v) + one.positions[1] * u + one.positions[2] * v;
    const glm::vec3 o = rng.unit() * 3.0f;
    aimed.push_back(make_ray(o, target - o));
  }
  for (const glm::mat4& m : {glm::mat4(1.0f), transform(glm::vec3(1, 2, 3), 1.0f, glm::vec3(0, 1, 0), glm::vec3(2.0f, -1.0f, 0.5f))}) {
    const ls::Scene scene = single_mesh_scene(one, {m});
    check_against_brute(scene, rays, "one triangle");
    const Built b = build_both(scene);
    std::vector<lsk::Ray> world_aimed = aimed;
    for (lsk::Ray& r : world_aimed) {
      const glm::vec3 target = ls::transform_point(m, r.origin + r.dir);
      r.origin = ls::transform_point(m, r.origin);
      r.dir = target - r.origin;
    }
    glm::vec3 p0, p1, p2;
    world_triangle(scene, 0, 0, p0, p1, p2);
    const glm::dvec3 n = glm::cross(glm::dvec3(p1) - glm::dvec3(p0), glm::dvec3(p2) - glm::dvec3(p0));
    for (const ls::Accel* a : {&b.flat, &b.two}) {
      const std::vector<lsk::Hit> hits = trace_all(*a, world_aimed);
      size_t missed = 0;
      double worst = 0.0;
      for (size_t i = 0; i < hits.size(); ++i) {
        // The exact t of this float ray against this float triangle, and the incidence.
        const lsk::Ray& r = world_aimed[i];
        const double exact = glm::dot(glm::dvec3(p0) - glm::dvec3(r.origin), n) / glm::dot(glm::dvec3(r.dir), n);
        const double cs = std::fabs(glm::dot(glm::normalize(n), glm::normalize(glm::dvec3(r.dir))));
        const double e = is_hit(hits[i]) ? rel(hits[i].t, exact) : 1.0;
        worst = std::max(worst, e * cs);
        if (!is_hit(hits[i]) || hits[i].triangle != 0 || e > t_tolerance(kRelT, cs)) {
          if (++missed <= 3)
            UNSCOPED_INFO(a->spec.name() << ": " << describe(r) << " -> " << describe(hits[i]) << " exact t " << exact
                                         << " cos " << cs);
        }
      }
      INFO(a->spec.name() << ": rays aimed at the inside of the triangle; worst relative t error x cos = " << worst);
      CHECK(missed == 0);
    }
  }
}

TEST_CASE("traversal: watertight closed meshes", "[traversal][watertight]") {
  struct Case {
    const char* name;
    ls::Mesh mesh;
    bool closed;  // closed and convex; else the grid (an open surface in z = 0)
  };
  std::vector<Case> cases;
  cases.push_back({"icosphere", icosphere(2), true});
  cases.push_back({"cube", cube(), true});
  cases.push_back({"grid", square_grid(12), false});
  enum Kind { kVertex, kMidpoint, kAlongEdge, kInside, kAxisParallel, kKinds };
  const char* kind_names[kKinds] = {"vertex", "edge midpoint", "point along an edge", "interior point", "axis-parallel onto grid"};

  Rng rng(401);
  for (const Case& c : cases) {
    for (int placement = 0; placement < 2; ++placement) {
      const glm::mat4 m = placement == 0 ? glm::mat4(1.0f)
                                         : transform(glm::vec3(0.3f, -0.2f, 0.1f), 0.8f, glm::vec3(1, 2, 3), glm::vec3(1.3f, 0.7f, -1.1f));
      const std::string where = std::string(c.name) + (placement == 0 ? " (identity)" : " (rotated, scaled, mirrored)");
      INFO(where);
      const ls::Scene scene = single_mesh_scene(c.mesh, {m});
      const WorldTris w = world_tris(scene);
      const Built b = build_both(scene);
      const ls::Mesh& mesh = c.mesh;

      // Targets in object space: vertices, edge midpoints, points along edges, interior points.
      std::vector<std::pair<glm::vec3, Kind>> targets;
      std::vector<std::pair<uint32_t, uint32_t>> edges;
      for (const glm::uvec3& t : mesh.triangles)
        for (int k = 0; k < 3; ++k) {
          const uint32_t a = t[k], e = t[(k + 1) % 3];
          if (a < e) edges.push_back({a, e});
        }
      const auto inner = [&](const glm::vec3& p) {  // the grid's border is no shared edge
        return c.closed || (std::fabs(p.x) < 0.999f && std::fabs(p.y) < 0.999f);
      };
      for (const glm::vec3& p : mesh.positions)
        if (inner(p)) targets.push_back({p, kVertex});
      for (const auto& [a, e] : edges) {
        const glm::vec3 pa = mesh.positions[a], pe = mesh.positions[e];
        if (inner(pa) && inner(pe)) targets.push_back({0.5f * (pa + pe), kMidpoint});
        for (float s : {1.0f / 3.0f, 0.1f, rng.uniform()}) {
          const glm::vec3 p = pa + s * (pe - pa);
          if (inner(p)) targets.push_back({p, kAlongEdge});
        }
      }
      for (int i = 0; i < 300; ++i)
        targets.push_back({c.closed ? rng.unit() * rng.range(0.0f, 0.55f) : glm::vec3(rng.range(-0.99f, 0.99f), rng.range(-0.99f, 0.99f), 0.0f),
                           kInside});

      // Origins outside: on the axes and diagonals (rays along faces and through edges and corners of
      // the cube) and random.
      std::vector<glm::vec3> origins = {{3, 0, 0}, {0, -3, 0}, {0, 0, 3}, {-3, 0, 0}, {0, 3, 0}, {0, 0, -3}, {3, 3, 3}, {-3, 2, -3}};
      for (int i = 0; i < 6; ++i) origins.push_back(rng.unit() * 3.5f);

      // World-space face planes (outward) of the closed convex mesh, to keep only rays that really enter
      // it: the line's chord through the solid must be longer than 1e-2 (rays that only graze a
      // silhouette edge or vertex may go either way).
      glm::dvec3 centre(0.0);
      for (const glm::vec3& v : w.v) centre += glm::dvec3(v);
      centre /= double(w.v.size());
      const auto enters = [&](const glm::vec3& o, const glm::vec3& d) {
        if (!c.closed) {  // the grid: crossing its plane at a non-grazing angle
          const glm::dvec3 n = glm::cross(glm::dvec3(w.v[1]) - glm::dvec3(w.v[0]), glm::dvec3(w.v[2]) - glm::dvec3(w.v[0]));
          return std::fabs(glm::dot(glm::normalize(n), glm::normalize(glm::dvec3(d)))) > 1e-3;
        }
        double s0 = -1e300, s1 = 1e300;
        for (size_t k = 0; k < w.size(); ++k) {
          const glm::dvec3 a(w.v[3 * k]), bb(w.v[3 * k + 1]), cc(w.v[3 * k + 2]);
          glm::dvec3 n = glm::cross(bb - a, cc - a);
          if (glm::dot(n, a - centre) < 0.0) n = -n;
          const double num = glm::dot(n, a - glm::dvec3(o)), den = glm::dot(n, glm::dvec3(d));
          if (den == 0.0) {
            if (num < 0.0) return false;
            continue;
          }
          if (den < 0.0) s0 = std::max(s0, num / den);
          else s1 = std::min(s1, num / den);
        }
        return (s1 - s0) * glm::length(glm::dvec3(d)) > 1e-2;
      };

      std::vector<lsk::Ray> candidates;
      std::vector<Kind> candidate_kinds;
      for (const glm::vec3& o : origins) {
        const glm::vec3 wo = ls::transform_point(m, o);
        for (const auto& [p, kind] : targets) {
          const glm::vec3 wp = ls::transform_point(m, p);
          candidates.push_back(make_ray(wo, wp - wo));
          candidate_kinds.push_back(kind);
        }
      }
      std::vector<char> entering(candidates.size());
      ls::parallel_for(size_t(0), candidates.size(),
                       [&](size_t i) { entering[i] = enters(candidates[i].origin, candidates[i].dir) ? 1 : 0; });
      std::vector<lsk::Ray> rays;
      std::vector<Kind> kinds;
      size_t grazing = 0;
      for (size_t i = 0; i < candidates.size(); ++i) {
        if (!entering[i]) {
          ++grazing;
          continue;
        }
        rays.push_back(candidates[i]);
        kinds.push_back(candidate_kinds[i]);
      }
      if (!c.closed)  // straight down and up onto every grid target (exactly axis-parallel in object space)
        for (const auto& [p, kind] : targets)
          for (float z : {2.0f, -2.0f}) {
            const glm::vec3 wo = ls::transform_point(m, glm::vec3(p.x, p.y, z));
            rays.push_back(make_ray(wo, ls::transform_point(m, p) - wo));
            kinds.push_back(kAxisParallel);
          }
      // Every target is on (or, interior points, beyond) the surface, so the first hit is at t <= 1 up to
      // the kernel's t error; a ray that slips through the surface there hits the far side (t > 1.002
      // given the chord above; interior points lie >= 0.4 inside) or nothing.
      const float limit = 1.0f + 1e-3f;
      const std::vector<lsk::Hit> brute = brute_all(w, rays);
      const std::vector<lsk::Hit> flat = trace_all(b.flat, rays);
      for (const auto& [name, hits] : std::vector<std::pair<const char*, const std::vector<lsk::Hit>*>>{
               {"brute force", &brute}, {"F-BVH", &flat}}) {
        size_t slipped[kKinds] = {}, total[kKinds] = {};
        std::string examples[kKinds];
        for (size_t i = 0; i < rays.size(); ++i) {
          ++total[kinds[i]];
          const lsk::Hit& h = (*hits)[i];
          // std::string("\n") first: GCC 12's -Wrestrict misfires on "\n" + std::string here.
          if ((!is_hit(h) || !(h.t <= limit)) && ++slipped[kinds[i]] <= 2)
            examples[kinds[i]] += std::string("\n") + describe(rays[i]) + " -> " + describe(h);
        }
        for (int k = 0; k < kKinds; ++k) {
          if (total[k] == 0) continue;
          INFO(where << ", " << name << ", rays aimed at a " << kind_names[k] << ": " << slipped[k] << " of " << total[k]
                     << " entering rays slipped through (" << grazing << " grazing rays left out)" << examples[k]);
          CHECK(slipped[k] == 0);
        }
      }
      // 2L-BVH: the same, and identical ids on shared edges (ties go to the lower triangle).
      const std::vector<lsk::Hit> two = trace_all(b.two, rays);
      size_t slipped = 0;
      for (size_t i = 0; i < rays.size(); ++i)
        if (!is_hit(two[i]) || !(two[i].t <= limit))
          if (++slipped <= 3) UNSCOPED_INFO("2L-BVH slip (" << kind_names[kinds[i]] << "): " << describe(rays[i]) << " -> " << describe(two[i]));
      INFO(where << ", 2L-BVH: " << slipped << " of " << rays.size() << " entering rays slipped through");
      CHECK(slipped == 0);
      // Rays through shared edges and vertices are ties: the flat BVH must pick what the brute force picks.
      INFO(where << ": F-BVH vs brute force on edge and vertex rays (ties to the lower triangle)");
      CHECK(count_exact_mismatches(scene, rays, brute, flat, "F-BVH") == 0);
    }
  }
}

TEST_CASE("traversal: axis-parallel rays, box faces, edges and corners", "[traversal]") {
  // Boxes whose faces the rays run along: the cube [-1, 1]^3, a grid in z = 5 (a flat box), and a soup
  // at x = 3 for inner nodes.
  std::vector<ls::Mesh> meshes;
  meshes.push_back(cube());
  meshes.push_back(square_grid(4));
  meshes.push_back(random_soup(400, 501, 1.0f, 0.2f));
  const ls::Scene scene = scene_of(std::move(meshes), {{0u, glm::mat4(1.0f)},
                                                      {1u, transform(glm::vec3(0, 0, 5), 0.0f, glm::vec3(0, 0, 1), glm::vec3(1.0f))},
                                                      {2u, transform(glm::vec3(3, 0, 0), 0.0f, glm::vec3(0, 0, 1), glm::vec3(1.0f))}});
  const Built b = build_both(scene);
  Rng rng(502);
  std::vector<lsk::Ray> rays;
  const float nz = -0.0f;
  const std::vector<glm::vec3> dirs = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1},
                                       {nz, 0, -1}, {0, nz, 1}, {1, nz, nz}, {nz, nz, 1}, {0.6f, 0.8f, 0}, {0.6f, nz, -0.8f},
                                       {nz, -0.6f, 0.8f}, {1, 1, 0}, {1, 0, 1}, {0, 1, 1}, {-1, -1, nz}};
  // Origins on box planes of every node (exact face, edge and corner coordinates) and random ones.
  std::vector<float> planes = {-1.0f, 0.0f, 1.0f, 3.0f, 2.0f, 4.0f, 5.0f, -0.5f, 0.5f};
  for (const lsk::BvhNode& n : b.flat.nodes)
    for (int k = 0; k < 3; ++k) {
      planes.push_back(n.lo[k]);
      planes.push_back(n.hi[k]);
    }
  for (const glm::vec3& d : dirs)
    for (int i = 0; i < 600; ++i) {
      glm::vec3 o = rng.vec(-4.0f, 5.0f);
      for (int k = 0; k < 3; ++k)
        if (rng.uniform() < 0.5f) o[k] = planes[size_t(rng.uniform() * float(planes.size()))];
      rays.push_back(make_ray(o, d));
    }
  check_against_brute(scene, rays, "axis-parallel", false);

  // Rays running exactly along a face of the cube hit the edge of the perpendicular face they meet
  // (boxes are closed, edges are hit).  Along the face x = 1, starting at y = -3, moving +y: the
  // face y = -1 is met at its edge x = 1, at t = 2.
  std::vector<lsk::Ray> along;
  for (float s : {-0.5f, 0.0f, 0.25f, 0.9f}) {
    for (float face : {1.0f, -1.0f}) {
      along.push_back(make_ray(glm::vec3(face, -3.0f, s), glm::vec3(0, 1, 0)));
      along.push_back(make_ray(glm::vec3(face, -3.0f, s), glm::vec3(nz, 1, 0)));
      along.push_back(make_ray(glm::vec3(-3.0f, s, face), glm::vec3(1, 0, nz)));
      along.push_back(make_ray(glm::vec3(s, face, 3.0f), glm::vec3(0, 0, -1)));
      along.push_back(make_ray(glm::vec3(s, face, 3.0f), glm::vec3(nz, nz, -1)));
    }
  }
  // Through cube edges and corners.
  along.push_back(make_ray(glm::vec3(3, 3, 0.5f), glm::vec3(-1, -1, 0)));
  along.push_back(make_ray(glm::vec3(3, 3, 3), glm::vec3(-1, -1, -1)));
  along.push_back(make_ray(glm::vec3(-3, 3, -3), glm::vec3(1, -1, 1)));
  along.push_back(make_ray(glm::vec3(3, 0.25f, 3), glm::vec3(-1, nz, -1)));
  const WorldTris w = world_tris(scene);
  for (const auto& [name, hits] : std::vector<std::pair<const char*, std::vector<lsk::Hit>>>{
           {"brute force", brute_all(w, along)}, {"F-BVH", trace_all(b.flat, along)}, {"2L-BVH", trace_all(b.two, along)}}) {
    size_t bad = 0;
    for (size_t i = 0; i < along.size(); ++i)
      if (!is_hit(hits[i]) || hits[i].instance != 0 || rel(hits[i].t, 2.0) > 1e-6) {
        if (++bad <= 6) UNSCOPED_INFO(name << ": " << describe(along[i]) << " -> " << describe(hits[i]));
      }
    INFO(name << ": rays along cube faces / through edges and corners must hit the cube at t = 2");
    CHECK(bad == 0);
  }
}

TEST_CASE("traversal: flat boxes, in-plane and grazing rays", "[traversal]") {
  // One quad in z = 0: every BVH box is flat.
  const ls::Scene quad = single_mesh_scene(
      make_mesh({glm::vec3(-1, -1, 0), glm::vec3(1, -1, 0), glm::vec3(1, 1, 0), glm::vec3(-1, 1, 0)}, {{0, 1, 2}, {0, 2, 3}}));
  const Built qb = build_both(quad);
  REQUIRE(qb.flat.nodes[0].lo.z == 0.0f);
  REQUIRE(qb.flat.nodes[0].hi.z == 0.0f);
  Rng rng(601);
  const float nz = -0.0f;

  SECTION("rays from above and below hit inside and miss outside") {
    std::vector<lsk::Ray> rays;
    std::vector<int> expect;  // 1 hit, 0 miss, -1 too close to the border to say
    for (int i = 0; i < 4000; ++i) {
      const glm::vec3 o(rng.range(-2, 2), rng.range(-2, 2), (i % 2 ? 1.0f : -1.0f) * rng.range(0.1f, 3.0f));
      glm::vec3 d;
      if (i % 3 == 0)
        d = glm::vec3(i % 6 == 0 ? 0.0f : nz, i % 4 == 0 ? 0.0f : nz, -o.z);  // axis-parallel
      else
        d = glm::vec3(rng.range(-1, 1), rng.range(-1, 1), -o.z * rng.range(0.2f, 2.0f));
      rays.push_back(make_ray(o, d));
      const double t = -double(o.z) / double(d.z);
      const double x = double(o.x) + t * double(d.x), y = double(o.y) + t * double(d.y);
      const double m = std::max(std::fabs(x), std::fabs(y));
      expect.push_back(m < 1.0 - 1e-5 ? 1 : (m > 1.0 + 1e-5 ? 0 : -1));
    }
    check_against_brute(quad, rays, "quad");
    for (const ls::Accel* a : {&qb.flat, &qb.two}) {
      const std::vector<lsk::Hit> hits = trace_all(*a, rays);
      size_t bad = 0;
      for (size_t i = 0; i < rays.size(); ++i) {
        if (expect[i] < 0) continue;
        const double t = -double(rays[i].origin.z) / double(rays[i].dir.z);
        if (is_hit(hits[i]) != (expect[i] == 1) || (is_hit(hits[i]) && rel(hits[i].t, t) > 1e-6))
          if (++bad <= 5) UNSCOPED_INFO(a->spec.name() << ": " << describe(rays[i]) << " -> " << describe(hits[i]));
      }
      CHECK(bad == 0);
    }
  }

  SECTION("rays in the plane of the quad miss (decided: in-plane rays never hit)") {
    std::vector<lsk::Ray> rays;
    for (int i = 0; i < 2000; ++i) {
      const float z = i % 3 == 0 ? nz : 0.0f;
      const glm::vec3 o(rng.range(-3, 3), rng.range(-3, 3), z);
      glm::vec3 d(rng.range(-1, 1), rng.range(-1, 1), i % 2 ? nz : 0.0f);
      if (i % 5 == 0) d = glm::vec3(0.0f, 1.0f, 0.0f);
      if (i % 7 == 0) d = glm::vec3(-1.0f, nz, nz);
      rays.push_back(make_ray(o, d));
      // Parallel to the plane just above and below it: no intersection at all.
      rays.push_back(make_ray(glm::vec3(o.x, o.y, i % 2 ? 1e-30f : -1e-30f), d));
    }
    // Through the shared diagonal and the corners, in the plane.
    rays.push_back(make_ray(glm::vec3(-2, -2, 0), glm::vec3(1, 1, 0)));
    rays.push_back(make_ray(glm::vec3(-3, -1, 0), glm::vec3(1, 0, 0)));
    rays.push_back(make_ray(glm::vec3(1, -3, 0), glm::vec3(0, 1, 0)));
    const WorldTris w = world_tris(quad);
    for (const auto& [name, hits] : std::vector<std::pair<const char*, std::vector<lsk::Hit>>>{
             {"brute force", brute_all(w, rays)}, {"F-BVH", trace_all(qb.flat, rays)}, {"2L-BVH", trace_all(qb.two, rays)}}) {
      size_t hit = 0;
      for (size_t i = 0; i < rays.size(); ++i)
        if (is_hit(hits[i]) || !std::isinf(hits[i].t)) {
          if (++hit <= 5) UNSCOPED_INFO(name << ": " << describe(rays[i]) << " -> " << describe(hits[i]));
        }
      INFO(name);
      CHECK(hit == 0);
    }
  }

  SECTION("grazing rays nearly parallel to a large triangle") {
    const ls::Scene big = single_mesh_scene(make_mesh({glm::vec3(-10, -10, 0), glm::vec3(10, -10, 0), glm::vec3(0, 10, 0)}, {{0, 1, 2}}));
    const Built bb = build_both(big);
    std::vector<lsk::Ray> rays;
    std::vector<int> expect;
    std::vector<double> expect_t, sin_angle;
    for (float slope : {1e-1f, 1e-2f, 1e-3f, 1e-4f, 1e-5f, 1e-6f}) {
      for (int i = 0; i < 500; ++i) {
        const float phi = rng.range(0.0f, 6.2831853f);
        const glm::vec3 d(std::cos(phi), std::sin(phi), (i % 2 ? -1.0f : 1.0f) * slope);
        const float travel = rng.range(0.5f, 15.0f);
        const glm::vec3 o(rng.range(-12, 12), rng.range(-12, 12), -d.z * travel);
        rays.push_back(make_ray(o, d));
        const double t = -double(o.z) / double(d.z);
        const double x = double(o.x) + t * double(d.x), y = double(o.y) + t * double(d.y);
        // Edge functions of the triangle (-10,-10) (10,-10) (0,10), positive inside.
        const auto edge = [](double ax, double ay, double bx, double by, double px, double py) {
          return ((bx - ax) * (py - ay) - (by - ay) * (px - ax)) / std::hypot(bx - ax, by - ay);
        };
        const double d0 = edge(-10, -10, 10, -10, x, y), d1 = edge(10, -10, 0, 10, x, y), d2 = edge(0, 10, -10, -10, x, y);
        const double inside = std::min({d0, d1, d2});
        expect.push_back(inside > 1e-3 ? 1 : (inside < -1e-3 ? 0 : -1));
        expect_t.push_back(t);
        sin_angle.push_back(double(slope) / std::sqrt(1.0 + double(slope) * double(slope)));
      }
    }
    check_against_brute(big, rays, "grazing");
    for (const ls::Accel* a : {&bb.flat, &bb.two}) {
      const std::vector<lsk::Hit> hits = trace_all(*a, rays);
      size_t bad = 0;
      double worst = 0.0;
      for (size_t i = 0; i < rays.size(); ++i) {
        if (expect[i] < 0) continue;
        const double e = is_hit(hits[i]) ? rel(hits[i].t, expect_t[i]) : 0.0;
        worst = std::max(worst, e * sin_angle[i]);
        // t: a few ulps of the distance, amplified by 1 / sin(angle) at grazing incidence.
        if (is_hit(hits[i]) != (expect[i] == 1) || e * sin_angle[i] > 1e-6)
          if (++bad <= 5)
            UNSCOPED_INFO(a->spec.name() << ": " << describe(rays[i]) << " -> " << describe(hits[i]) << " expected "
                                         << (expect[i] ? "hit" : "miss") << " t=" << expect_t[i]);
      }
      INFO(a->spec.name() << ": worst relative t error x sin(angle) = " << worst);
      CHECK(bad == 0);
    }
  }
}

TEST_CASE("traversal: degenerate triangles are never hit", "[traversal]") {
  // Zero-area triangles: a repeated vertex, all three equal, exactly collinear; among normal ones.
  std::vector<glm::vec3> p = {{0, 0, 0}, {1, 1, 1}, {2, 2, 2}, {0.5f, 0.25f, 0}, {0.5f, 0.25f, 0}, {1, -1, 0.5f},
                              {-1, 0, 0}, {1, 0, 0}, {3, 0, 0}, {0, 0, 1}, {0, 0, 1}, {0, 0, 1}};
  std::vector<glm::uvec3> t = {{0, 1, 2}, {3, 4, 5}, {6, 7, 8}, {9, 10, 11}, {0, 0, 1}, {7, 6, 8}, {5, 5, 3}};
  const size_t degenerate = t.size();
  ls::Mesh normal = random_soup(50, 701, 1.5f, 0.3f);
  for (const glm::uvec3& tri : normal.triangles) t.push_back(tri + glm::uvec3(uint32_t(p.size())));
  p.insert(p.end(), normal.positions.begin(), normal.positions.end());
  const ls::Mesh mesh = make_mesh(p, t);

  Rng rng(702);
  std::vector<lsk::Ray> rays = random_rays(rng, 3000, 4.0f, 2.0f);
  // Aimed exactly at the degenerate triangles' vertices, along their lines, and at points on them.
  for (size_t k = 0; k < degenerate; ++k)
    for (int i = 0; i < 200; ++i) {
      const glm::vec3 a = p[t[k].x], b = p[t[k].y], c = p[t[k].z];
      const glm::vec3 target = i % 4 == 0 ? a : (i % 4 == 1 ? b : (i % 4 == 2 ? 0.5f * (a + c) : a + rng.uniform() * (c - a)));
      const glm::vec3 o = rng.unit() * 4.0f;
      rays.push_back(make_ray(o, target - o));
      if (i % 10 == 0) rays.push_back(make_ray(a - 2.0f * (c - a), c - a));  // along the line
    }
  for (const glm::mat4& m : {glm::mat4(1.0f), transform(glm::vec3(0.5f, 0, 0), 0.5f, glm::vec3(1, 1, 0), glm::vec3(1, 2, 1))}) {
    const ls::Scene scene = single_mesh_scene(mesh, {m});
    const WorldTris w = world_tris(scene);
    const Built b = build_both(scene);
    // Zero-area in the space the structure tests in: world space for the brute force and F-BVH (a
    // transform may round collinear points apart), object space for 2L-BVH.
    std::vector<bool> world_zero(degenerate), object_zero(degenerate);
    for (size_t k = 0; k < degenerate; ++k) {
      glm::vec3 a, bb, c;
      world_triangle(scene, 0, uint32_t(k), a, bb, c);
      world_zero[k] = glm::cross(glm::dvec3(bb) - glm::dvec3(a), glm::dvec3(c) - glm::dvec3(a)) == glm::dvec3(0.0);
      object_zero[k] = glm::cross(glm::dvec3(p[t[k].y]) - glm::dvec3(p[t[k].x]), glm::dvec3(p[t[k].z]) - glm::dvec3(p[t[k].x])) ==
                       glm::dvec3(0.0);
      CHECK(object_zero[k]);
    }
    for (const auto& [name, hits] : std::vector<std::pair<const char*, std::vector<lsk::Hit>>>{
             {"brute force", brute_all(w, rays)}, {"F-BVH", trace_all(b.flat, rays)}, {"2L-BVH", trace_all(b.two, rays)}}) {
      const std::vector<bool>& zero_area = std::string(name) == "2L-BVH" ? object_zero : world_zero;
      size_t bad = 0;
      std::vector<size_t> per_triangle(degenerate, 0);
      for (size_t i = 0; i < rays.size(); ++i)
        if (is_hit(hits[i]) && hits[i].triangle < degenerate && zero_area[hits[i].triangle]) {
          ++per_triangle[hits[i].triangle];
          if (++bad <= 3)
            UNSCOPED_INFO(name << ": " << describe(rays[i]) << " -> " << describe(hits[i]) << "\n"
                               << describe_triangle(scene, hits[i]));
        }
      std::ostringstream counts;
      for (size_t k = 0; k < degenerate; ++k) counts << " " << per_triangle[k];
      INFO(name << (m == glm::mat4(1.0f) ? " (identity)" : " (transformed)") << ": " << bad << " hits on zero-area triangles of "
                << rays.size() << " rays; per degenerate triangle:" << counts.str());
      CHECK(bad == 0);
    }
    check_against_brute(scene, rays, "degenerate", false);
  }
}

TEST_CASE("traversal: tmin and tmax are respected", "[traversal]") {
  const ls::Scene scene = instanced_scene(801);
  const WorldTris w = world_tris(scene);
  const Built b = build_both(scene);
  Rng rng(802);
  const std::vector<lsk::Ray> base = random_rays(rng, 4000, 5.0f, 3.5f);
  const std::vector<lsk::Hit> first = trace_all(b.flat, base);

  // From each hit at t*: tmax = t* (must still hit at t*), tmax just below t* (that triangle not at t*),
  // tmin = t* (the hit counts), tmin just above t* (not that hit), and random intervals.
  std::vector<lsk::Ray> rays;
  std::vector<int> kind;
  std::vector<size_t> from;
  for (size_t i = 0; i < base.size(); ++i) {
    if (!is_hit(first[i])) continue;
    const float ts = first[i].t;
    lsk::Ray r = base[i];
    r.tmax = ts;
    rays.push_back(r), kind.push_back(0), from.push_back(i);
    r.tmax = std::nextafter(ts, 0.0f);
    rays.push_back(r), kind.push_back(1), from.push_back(i);
    r = base[i];
    r.tmin = ts;
    rays.push_back(r), kind.push_back(2), from.push_back(i);
    r.tmin = std::nextafter(ts, kInf);
    rays.push_back(r), kind.push_back(3), from.push_back(i);
    r = base[i];
    r.tmin = ts * rng.range(0.0f, 1.5f);
    r.tmax = r.tmin + ts * rng.range(0.0f, 2.0f);
    rays.push_back(r), kind.push_back(4), from.push_back(i);
  }
  REQUIRE(rays.size() > 4000);
  const std::vector<lsk::Hit> ref = brute_all(w, rays);
  const std::vector<lsk::Hit> flat = trace_all(b.flat, rays);
  const std::vector<lsk::Hit> two = trace_all(b.two, rays);
  CHECK(count_exact_mismatches(scene, rays, ref, flat, "F-BVH interval") == 0);
  {
    const Agreement a = compare_approx(scene, rays, ref, two, "2L-BVH interval");
    INFO("2L-BVH vs brute force with intervals: " << summary(a));
    CHECK(a.bad_ids == 0);
    CHECK(a.bad_t == 0);
  }
  size_t bad[5] = {0, 0, 0, 0, 0}, total[5] = {0, 0, 0, 0, 0}, in_interval = 0;
  std::string examples[5];
  for (size_t k = 0; k < rays.size(); ++k) {
    const lsk::Hit& h0 = first[from[k]];
    const lsk::Hit& h = flat[k];
    bool ok = true;
    switch (kind[k]) {
      case 0: ok = is_hit(h) && same_bits(h.t, h0.t) && same_ids(h, h0); break;  // a hit exactly at tmax counts
      case 1: ok = !same_ids(h, h0); break;                                     // that hit lies beyond tmax
      case 2: ok = is_hit(h) && same_bits(h.t, h0.t) && same_ids(h, h0); break;  // a hit exactly at tmin counts
      case 3: ok = !same_ids(h, h0); break;                                     // that hit lies before tmin
      default: break;
    }
    ++total[kind[k]];
    if (!ok && ++bad[kind[k]] <= 2) {
      std::ostringstream m;
      m << "\n" << describe(rays[k]) << "\n  unrestricted " << describe(h0) << "\n  restricted   " << describe(h) << "\n"
        << describe_triangle(scene, h0);
      examples[kind[k]] += m.str();
    }
    if (is_hit(h) && !(h.t >= rays[k].tmin && h.t <= rays[k].tmax)) ++in_interval;
    if (is_hit(two[k]) && !(two[k].t >= rays[k].tmin && two[k].t <= rays[k].tmax)) ++in_interval;
  }
  const char* rule[4] = {"tmax = t*: the hit at t* counts", "tmax = t* - 1 ulp: the hit at t* lies beyond",
                         "tmin = t*: the hit at t* counts", "tmin = t* + 1 ulp: the hit at t* lies before"};
  for (int k = 0; k < 4; ++k) {
    INFO("F-BVH, " << rule[k] << ": violated on " << bad[k] << " of " << total[k] << " rays" << examples[k]);
    CHECK(bad[k] == 0);
  }
  CHECK(in_interval == 0);
  // Any-hit with intervals: a hit exactly when closest-hit finds one.
  const std::vector<lsk::Hit> flat_any = trace_all(b.flat, rays, true);
  const std::vector<lsk::Hit> two_any = trace_all(b.two, rays, true);
  size_t any_bad = 0;
  for (size_t k = 0; k < rays.size(); ++k)
    if (is_hit(flat_any[k]) != is_hit(flat[k]) || is_hit(two_any[k]) != is_hit(two[k])) ++any_bad;
  CHECK(any_bad == 0);
  // An empty interval (tmin > tmax) finds nothing.
  std::vector<lsk::Ray> empty = base;
  for (lsk::Ray& r : empty) {
    r.tmin = 2.0f;
    r.tmax = 1.0f;
  }
  for (const ls::Accel* a : {&b.flat, &b.two})
    for (bool any : {false, true}) {
      const std::vector<lsk::Hit> hits = trace_all(*a, empty, any);
      CHECK(std::count_if(hits.begin(), hits.end(), is_hit) == 0);
    }
}

// ---------------------------------------------------------------------------------------------------
// Numerical extremes.

namespace {

enum class ScaleMode { Vertices, Transforms };

// The scene scaled about the origin, then translated.  Vertices: every mesh's positions and every
// instance's translation are scaled (the linear parts stay as they are).  Transforms: every instance
// transform is premultiplied by translate * scale (not validated: see the validate_scene test below).
ls::Scene transformed_scene(const ls::Scene& base, float scale, float translate, ScaleMode mode = ScaleMode::Vertices) {
  ls::Scene s = base;
  if (mode == ScaleMode::Vertices) {
    for (ls::Mesh& m : s.meshes)
      for (glm::vec3& p : m.positions) p *= scale;
    for (ls::Instance& in : s.instances)
      in.object_to_world[3] = glm::vec4(glm::vec3(in.object_to_world[3]) * scale + glm::vec3(translate), 1.0f);
    ls::validate_scene(s);
  } else {
    const glm::mat4 m = glm::translate(glm::mat4(1.0f), glm::vec3(translate)) * glm::scale(glm::mat4(1.0f), glm::vec3(scale));
    for (ls::Instance& in : s.instances) in.object_to_world = m * in.object_to_world;
  }
  return s;
}

std::vector<lsk::Ray> transformed_rays(const std::vector<lsk::Ray>& rays, float scale, float translate) {
  std::vector<lsk::Ray> out = rays;
  for (lsk::Ray& r : out) r.origin = r.origin * scale + glm::vec3(translate);
  return out;
}

}  // namespace

TEST_CASE("traversal: numerical extremes: scales 1e-20, 1e20, 2^-60, 2^60 and a translation by 1e6", "[traversal][extremes]") {
  // A unit-scale scene: a soup at identity plus instanced meshes.
  std::vector<ls::Mesh> meshes;
  meshes.push_back(random_soup(1500, 901, 1.0f, 0.15f));
  meshes.push_back(icosphere(2));
  meshes.push_back(square_grid(6));
  const ls::Scene unit = scene_of(std::move(meshes),
                                  {{0u, glm::mat4(1.0f)},
                                   {1u, transform(glm::vec3(1.5f, 0, 0), 0.4f, glm::vec3(0, 1, 0), glm::vec3(0.5f, 0.3f, 0.4f))},
                                   {2u, transform(glm::vec3(0, -1.2f, 0), 1.2f, glm::vec3(1, 0, 0), glm::vec3(1.0f, -1.5f, 1.0f))},
                                   {1u, transform(glm::vec3(-1.4f, 0.5f, 0.2f), 0.0f, glm::vec3(0, 0, 1), glm::vec3(-0.3f))}});
  Rng rng(902);
  const std::vector<lsk::Ray> rays = random_rays(rng, 20000, 2.5f, 1.5f);
  const Built ub = build_both(unit);
  const std::vector<lsk::Hit> unit_hits[2] = {trace_all(ub.flat, rays), trace_all(ub.two, rays)};
  for (const auto& hits : unit_hits) CHECK(count_nan(hits) == 0);

  struct Variant {
    const char* name;
    float scale, translate;
    ScaleMode mode;
    bool exact;  // powers of two change no decision: identical ids, t scaled exactly
  };
  const Variant variants[] = {
      {"vertices x 1e-20", 1e-20f, 0.0f, ScaleMode::Vertices, false},
      {"vertices x 1e20", 1e20f, 0.0f, ScaleMode::Vertices, false},
      {"vertices x 2^-60", 0x1.0p-60f, 0.0f, ScaleMode::Vertices, true},
      {"vertices x 2^60", 0x1.0p60f, 0.0f, ScaleMode::Vertices, true},
      {"transforms x 1e-20", 1e-20f, 0.0f, ScaleMode::Transforms, false},
      {"transforms x 1e20", 1e20f, 0.0f, ScaleMode::Transforms, false},
      {"transforms x 2^-60", 0x1.0p-60f, 0.0f, ScaleMode::Transforms, true},
      {"transforms x 2^60", 0x1.0p60f, 0.0f, ScaleMode::Transforms, true},
      // A unit-size scene moved to 1e6 would sit on a 1/16 grid (the float spacing there) and stop being
      // the same geometry; the translated scene is the unit scene scaled by 2^16 (exact: same hits as the
      // unit scene), then moved by 1e6.
      {"vertices x 2^16, translated by 1e6", 0x1.0p16f, 1e6f, ScaleMode::Vertices, false},
      {"transforms x 2^16, translated by 1e6", 0x1.0p16f, 1e6f, ScaleMode::Transforms, false},
  };
  for (const Variant& v : variants) {
    const ls::Scene scene = transformed_scene(unit, v.scale, v.translate, v.mode);
    const std::vector<lsk::Ray> scaled = transformed_rays(rays, v.scale, v.translate);
    const Built b = build_both(scene);
    const ls::Accel* accels[2] = {&b.flat, &b.two};
    for (int s = 0; s < 2; ++s) {
      const std::vector<lsk::Hit> hits = trace_all(*accels[s], scaled);
      size_t same = 0, t_ok = 0, t_ok_angle = 0, both_hit = 0, nan = 0, exact_t = 0;
      double worst = 0.0, worst_cos = 0.0;
      for (size_t i = 0; i < rays.size(); ++i) {
        const lsk::Hit& r = unit_hits[s][i];
        const lsk::Hit& h = hits[i];
        if (std::isnan(h.t)) ++nan;
        if (!same_ids(r, h)) continue;
        ++same;
        if (!is_hit(r)) continue;
        ++both_hit;
        const double expected = double(r.t) * double(v.scale);
        const double e = rel(expected, double(h.t)), cs = incidence(unit, r, rays[i].dir);
        const double eo = t_error(expected, double(h.t), scaled[i]);
        if (expected == double(h.t)) ++exact_t;
        worst = std::max(worst, e);
        worst_cos = std::max(worst_cos, eo * cs);
        if (e <= 1e-4) ++t_ok;
        if (eo <= t_tolerance(1e-4, cs)) ++t_ok_angle;
      }
      std::ostringstream out;
      out << v.name << ", " << accels[s]->spec.name() << ": ids agree on " << same << "/" << rays.size()
          << " rays; t within 1e-4 relative on " << t_ok << "/" << both_hit << " common hits (t_error within 1e-4/cos on "
          << t_ok_angle << "), worst rel t " << worst << " (worst t_error x cos " << worst_cos << "), bit-exact t "
          << exact_t << ", NaN " << nan;
      const std::string line = out.str();
      INFO(line);
      std::printf("extremes: %s\n", line.c_str());
      CHECK(nan == 0);
      CHECK(double(same) >= 0.999 * double(rays.size()));
      if (v.translate == 0.0f) CHECK(double(t_ok) >= 0.999 * double(both_hit));
      CHECK(t_ok_angle == both_hit);
      if (v.exact) {
        CHECK(same == rays.size());
        CHECK(exact_t == both_hit);
      }
    }
  }
}

TEST_CASE("traversal: small triangles far from the ray origin", "[traversal][extremes]") {
  // A triangle of size ~1 seen from distance L.  The exact crossing point of each float ray with the
  // float triangle (computed in double) lies well inside it (all barycentrics >= 0.1), so the ray must
  // hit, and the barycentrics reported must be those of the crossing point up to 32 ulps of L (any test
  // that translates the vertices to the ray origin in float loses ~1 ulp of L; this allows 32).
  Rng rng(1101);
  const ls::Mesh tri = make_mesh({glm::vec3(0.6f, -0.2f, 0.1f), glm::vec3(-0.3f, 0.5f, -0.2f), glm::vec3(-0.25f, -0.45f, 0.15f)},
                                 {glm::uvec3(0, 1, 2)});
  const ls::Scene scene = single_mesh_scene(tri);
  const Built b = build_both(scene);
  const glm::dvec3 A(tri.positions[0]), B(tri.positions[1]), C(tri.positions[2]);
  for (float distance : {10.0f, 100.0f, 1000.0f, 10000.0f}) {
    std::vector<lsk::Ray> rays;
    std::vector<glm::dvec2> exact;  // barycentrics of vertices 1 and 2 at the exact crossing
    while (rays.size() < 4000) {
      const float u = rng.range(0.15f, 0.7f), v = rng.range(0.15f, 0.85f - u);
      const glm::vec3 target = tri.positions[0] * (1.0f - u - v) + tri.positions[1] * u + tri.positions[2] * v;
      glm::vec3 dir = rng.unit();
      if (dir.z < 0.0f) dir = -dir;
      dir = glm::normalize(dir + glm::vec3(0.0f, 0.0f, 0.5f));  // away from grazing
      const glm::vec3 o = target + dir * distance;
      const glm::vec3 d = target - o;
      // Exact crossing of the float ray with the float triangle's plane (Moller-Trumbore in double).
      const glm::dvec3 e1 = B - A, e2 = C - A, pv = glm::cross(glm::dvec3(d), e2);
      const double det = glm::dot(e1, pv);
      const glm::dvec3 tv = glm::dvec3(o) - A, q = glm::cross(tv, e1);
      const double eu = glm::dot(tv, pv) / det, ev = glm::dot(glm::dvec3(d), q) / det;
      if (std::min({eu, ev, 1.0 - eu - ev}) < 0.1) continue;
      rays.push_back(make_ray(o, d));
      exact.push_back(glm::dvec2(eu, ev));
    }
    for (const ls::Accel* a : {&b.flat, &b.two}) {
      const std::vector<lsk::Hit> hits = trace_all(*a, rays);
      size_t missed = 0, inaccurate = 0;
      double worst = 0.0;
      const double allowed = 1e-5 + 32.0 * 0x1.0p-24 * double(distance);
      for (size_t i = 0; i < rays.size(); ++i) {
        if (!is_hit(hits[i])) {
          if (++missed <= 2)
            UNSCOPED_INFO("missed: " << describe(rays[i]) << " exact barycentrics " << exact[i].x << ", " << exact[i].y);
          continue;
        }
        const double e = std::max(std::fabs(hits[i].u - exact[i].x), std::fabs(hits[i].v - exact[i].y));
        worst = std::max(worst, e);
        if (e > allowed && ++inaccurate <= 2)
          UNSCOPED_INFO("inaccurate: " << describe(rays[i]) << " -> " << describe(hits[i]) << " exact barycentrics "
                                       << exact[i].x << ", " << exact[i].y);
      }
      std::ostringstream line;
      line << "distance/size " << distance << ", " << a->spec.name() << ": " << missed << " of " << rays.size()
           << " rays through the inside missed, worst barycentric error " << worst << " (allowed " << allowed << ")";
      std::printf("far triangle: %s\n", line.str().c_str());
      INFO(line.str());
      CHECK(missed == 0);
      CHECK(worst <= allowed);
    }
  }
}

TEST_CASE("scene validation accepts instance transforms scaled by 1e-20 and 1e20", "[traversal][extremes]") {
  // Such transforms are invertible and trace correctly (the test above traces them); their determinant
  // (1e-60, 1e60) is outside the float range, which must not make them "singular".
  std::vector<ls::Mesh> meshes;
  meshes.push_back(icosphere(1));
  for (float s : {1e-20f, 1e20f, 1e-15f, 1e15f}) {
    INFO("uniform scale " << s);
    const ls::Scene scene = scene_of(meshes, {{0u, glm::mat4(1.0f)}});
    CHECK_NOTHROW(ls::validate_scene(transformed_scene(scene, s, 0.0f, ScaleMode::Transforms)));
  }
  // A really singular transform is still refused.
  ls::Scene flat = scene_of(meshes, {{0u, glm::mat4(1.0f)}});
  flat.instances[0].object_to_world[2] = glm::vec4(0.0f);
  CHECK_THROWS_AS(ls::validate_scene(flat), ls::InputError);
}

// ---------------------------------------------------------------------------------------------------
// Ray offsets.

namespace {

// A power of two at least the largest absolute world coordinate, as common/render/surface.cpp computes it.
float scene_scale_of(const ls::Scene& scene) {
  const ls::Bounds b = ls::world_bounds(scene);
  const glm::vec3 m3 = glm::max(glm::abs(b.lo), glm::abs(b.hi));
  const float m = std::max({m3.x, m3.y, m3.z});
  int e = 0;
  std::frexp(m, &e);
  return std::ldexp(1.0f, std::clamp(e, -120, 120));
}

// A unit vector orthogonal to n.
glm::vec3 tangent(const glm::vec3& n, Rng& rng) {
  glm::vec3 t = glm::cross(n, rng.unit());
  while (glm::length(t) < 1e-3f) t = glm::cross(n, rng.unit());
  return glm::normalize(t);
}

}  // namespace

TEST_CASE("traversal: offset rays never re-hit their own triangle", "[traversal][offset]") {
  std::vector<ls::Mesh> meshes;
  meshes.push_back(random_soup(800, 1001, 1.0f, 0.2f));
  meshes.push_back(icosphere(2));
  meshes.push_back(square_grid(8));
  meshes.push_back(cube());
  const ls::Scene unit = scene_of(std::move(meshes),
                                  {{0u, glm::mat4(1.0f)},
                                   {1u, transform(glm::vec3(0.5f, 0.5f, 0.5f), 0.3f, glm::vec3(1, 1, 0), glm::vec3(0.4f, 0.6f, -0.5f))},
                                   {2u, transform(glm::vec3(0, 0, -1.3f), 0.0f, glm::vec3(0, 0, 1), glm::vec3(1.3f))},
                                   {3u, transform(glm::vec3(-0.6f, 0.4f, 0), 0.7f, glm::vec3(0, 0, 1), glm::vec3(0.2f))}});
  struct Variant {
    const char* name;
    float scale, translate;
  };
  const Variant variants[] = {{"scale 1e-20", 1e-20f, 0.0f}, {"scale 1", 1.0f, 0.0f}, {"scale 1e20", 1e20f, 0.0f},
                              {"offset 1e6", 1.0f, 1e6f}, {"scale 2^10, offset 1e6", 1024.0f, 1e6f}};
  for (const Variant& var : variants) {
    const ls::Scene scene = transformed_scene(unit, var.scale, var.translate);
    const Built b = build_both(scene);
    const ls::SurfaceLookup surfaces(scene);
    const float scene_scale = scene_scale_of(scene);
    REQUIRE(scene_scale == surfaces.scene_scale());
    Rng rng(1002);
    // Primary rays from outside towards the scene.
    std::vector<lsk::Ray> primary;
    for (int i = 0; i < 4000; ++i) {
      const glm::vec3 o = rng.unit() * 4.0f, target = rng.vec(-1.2f, 1.2f);
      primary.push_back(make_ray(o * var.scale + glm::vec3(var.translate), (target - o) * 1.0f));
    }
    for (const ls::Accel* a : {&b.flat, &b.two}) {
      const std::vector<lsk::Hit> first = trace_all(*a, primary);
      std::vector<lsk::Ray> second;
      std::vector<size_t> from;
      size_t wrong_normals = 0, degenerate_hits = 0;
      for (size_t i = 0; i < primary.size(); ++i) {
        if (!is_hit(first[i])) continue;
        // The hit point as common/render/surface.cpp computes it (barycentric interpolation in float); the
        // geometric normal exactly (double), facing the incoming ray.
        const lsk::Hit& h = first[i];
        glm::vec3 p0, p1, p2;
        world_triangle(scene, h.instance, h.triangle, p0, p1, p2);
        const glm::vec3 position = p0 * (1.0f - h.u - h.v) + p1 * h.u + p2 * h.v;
        const glm::dvec3 area = glm::cross(glm::dvec3(p1) - glm::dvec3(p0), glm::dvec3(p2) - glm::dvec3(p0));
        if (area == glm::dvec3(0.0)) {
          // Zero area in world space (vertices rounded together far from 0).  The flat structure must
          // never hit it; 2L-BVH tests the (non-degenerate) object-space triangle, so its hit is fine,
          // but has no world normal to offset along.
          if (!a->spec.two_level()) ++degenerate_hits;
          continue;
        }
        glm::dvec3 nd = glm::normalize(area);
        if (glm::dot(nd, glm::dvec3(primary[i].dir)) > 0.0) nd = -nd;
        const glm::vec3 n(nd);
        const glm::vec3 origin = lsk::offset_ray_origin(position, n, scene_scale);
        // SurfaceLookup (the path tracer's) must find the same normal and position.
        const ls::SurfacePoint sp = surfaces.at(h, primary[i].dir);
        if (!(glm::dot(glm::dvec3(sp.geometric_normal), nd) > 0.99999) || sp.position != position) ++wrong_normals;
        // Directions over the hemisphere of the offset normal, down to grazing ones.
        for (int k = 0; k < 8; ++k) {
          glm::vec3 d;
          if (k < 5) {
            d = rng.unit();
            if (glm::dot(d, n) < 0.0f) d = -d;
            if (!(glm::dot(d, n) > 0.0f)) continue;
          } else {
            const float c = k == 5 ? 1e-1f : (k == 6 ? 1e-2f : 1e-3f);
            d = tangent(n, rng) + c * n;
          }
          second.push_back(make_ray(origin, d));
          from.push_back(i);
        }
      }
      REQUIRE(second.size() > 10000);
      const std::vector<lsk::Hit> hits = trace_all(*a, second);
      size_t rehit = 0, rehit_kernel = 0;
      for (size_t k = 0; k < second.size(); ++k) {
        const lsk::Hit& h0 = first[from[k]];
        if (is_hit(hits[k]) && same_ids(hits[k], h0))
          if (++rehit <= 5)
            UNSCOPED_INFO(var.name << ", " << a->spec.name() << ": " << describe(second[k]) << " re-hit " << describe(hits[k])
                                   << " (first hit " << describe(h0) << " from " << describe(primary[from[k]]) << ")");
        // The triangle kernel alone, on the world-space triangle.
        glm::vec3 p0, p1, p2;
        world_triangle(scene, h0.instance, h0.triangle, p0, p1, p2);
        float t, u, v;
        if (lsk::ray_triangle(lsk::make_tri_ray(second[k].origin, second[k].dir), 0.0f, kInf, p0, p1, p2, t, u, v)) ++rehit_kernel;
      }
      INFO(var.name << ", " << a->spec.name() << ": " << rehit << " traced and " << rehit_kernel << " kernel re-hits of "
                    << second.size() << " offset rays (scene_scale " << scene_scale << ")");
      CHECK(rehit == 0);
      CHECK(rehit_kernel == 0);
      CHECK(count_nan(hits) == 0);
      INFO("ls::SurfaceLookup::at disagrees with the exact geometric normal (or the position) on " << wrong_normals
                                                                                                 << " primary hits");
      CHECK(wrong_normals == 0);
      INFO(degenerate_hits << " primary hits on zero-area world triangles");
      CHECK(degenerate_hits == 0);
    }
  }
}
