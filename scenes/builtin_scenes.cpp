// Built-in procedural scenes, so that the default run needs no files.  Deterministic: a fixed
// splitmix64 stream (no std::random_device, no std:: distributions, whose output is implementation-defined).
//
//   cornell            the Cornell box as it is photographed: room [-1,1]^3 open at the front (floor,
//                      ceiling, back, red left and green right wall: one object each, facing inwards),
//                      one emissive quad flush in an opening of the ceiling, a tall and a short box, a
//                      sphere and an icosahedron: 10 objects, 10 instances; the camera outside the open
//                      front, looking in.
//   instances          closed room [-7.5,7.5]x[0,6]x[-7.5,7.5] (6 wall objects), two ceiling lights, an
//                      8x8 grid of 64 instances of ONE 51,200-triangle torus knot (own rotation and scale,
//                      every fourth non-uniform) and three unique objects: 12 objects, 75 instances.
//   carousel           rigid animation: the instances room with one ceiling light, a pedestal and a
//                      sphere (static, unique), 16 instances of one 12,800-triangle torus knot riding a
//                      carousel (a hub node turning once in 4 s; each knot spinning, every other one bobbing)
//                      and 8 instances of one 3,968-triangle ball pulsing in scale: 11 objects, 33 instances,
//                      238,778 world triangles; the animation (4 s, looping) exercises LINEAR, STEP and
//                      CUBICSPLINE channels of translation, rotation and scale.  Its still pose is t = 0.
//   generated:T:O:S    O objects (ellipsoids; an object whose budget is under 6 triangles gets loose
//                      triangles) holding exactly T triangles, seed S, each its own mesh and instance, PLUS
//                      one emissive quad light above them: O+1 objects, O+1 instances, T+2 triangles.
//                      Defaults 100000:16:1; T >= O >= 1, T <= 50,000,000, O <= 1,000,000.
//
// Every object is built so that its triangles wind counter-clockwise seen from the side its vertex
// normals point to (outwards for solids, into the room for walls).
#include "common/model/animation.h"
#include "scenes/load_scene.h"

#include <glm/gtc/matrix_transform.hpp>

#include <array>
#include <charconv>
#include <cmath>
#include <optional>

namespace ls {

namespace {

constexpr float kPi = 3.14159265358979f;

// ---- randomness ----

// splitmix64 (Steele, Lea, Flood 2014): tiny, fast, and the same on every platform.
struct Random {
  uint64_t state;
  explicit Random(uint64_t seed) : state(seed) {}
  uint64_t next() {
    uint64_t z = (state += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
  }
  float uniform() { return float(next() >> 40) * (1.0f / 16777216.0f); }  // [0, 1), exact 24-bit steps
  float uniform(float lo, float hi) { return lo + (hi - lo) * uniform(); }
};

// ---- mesh building ----

uint32_t add_vertex(Mesh& m, const glm::vec3& p, const glm::vec3& n) {
  m.positions.push_back(p);
  m.normals.push_back(n);
  return uint32_t(m.positions.size() - 1);
}

void add_triangle(Mesh& m, uint32_t a, uint32_t b, uint32_t c, uint32_t material) {
  m.triangles.emplace_back(a, b, c);
  m.materials.push_back(material);
}

// A flat quad, its corners counter-clockwise seen from the side it faces.
void add_quad(Mesh& m, const glm::vec3& p0, const glm::vec3& p1, const glm::vec3& p2, const glm::vec3& p3,
              uint32_t material) {
  const glm::vec3 n = glm::normalize(glm::cross(p1 - p0, p3 - p0));
  const uint32_t a = add_vertex(m, p0, n), b = add_vertex(m, p1, n), c = add_vertex(m, p2, n),
                 d = add_vertex(m, p3, n);
  add_triangle(m, a, b, c, material);
  add_triangle(m, a, c, d, material);
}

// Face `side` (0 low, 1 high) across `axis` of the box [lo, hi] moved by the rigid transform xf, facing
// out of the box, or into it for room walls.
void add_box_face(Mesh& m, const glm::vec3& lo, const glm::vec3& hi, int axis, int side, bool inward,
                  uint32_t material, const glm::mat4& xf = glm::mat4(1.0f)) {
  const int u = (axis + 1) % 3, v = (axis + 2) % 3;
  const auto corner = [&](int cu, int cv) {
    glm::vec3 p;
    p[axis] = side ? hi[axis] : lo[axis];
    p[u] = cu ? hi[u] : lo[u];
    p[v] = cv ? hi[v] : lo[v];
    return transform_point(xf, p);
  };
  // (u, v, axis) is right-handed, so this corner order is counter-clockwise seen from +axis.
  if ((side == 1) != inward)
    add_quad(m, corner(0, 0), corner(1, 0), corner(1, 1), corner(0, 1), material);
  else
    add_quad(m, corner(0, 0), corner(0, 1), corner(1, 1), corner(1, 0), material);
}

void add_box(Mesh& m, const glm::vec3& half, uint32_t material, const glm::mat4& xf) {
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side < 2; ++side) add_box_face(m, -half, half, axis, side, false, material, xf);
}

// Ellipsoid with radii r (moved by the rigid transform xf) from `stacks` latitude bands and `slices`
// longitudes: 2 * slices * (stacks - 1) triangles, analytic normals.
void add_ellipsoid(Mesh& m, const glm::vec3& r, uint32_t stacks, uint32_t slices, uint32_t material,
                   const glm::mat4& xf = glm::mat4(1.0f)) {
  const uint32_t base = uint32_t(m.positions.size());
  const auto put = [&](const glm::vec3& s) {  // s on the unit sphere
    add_vertex(m, transform_point(xf, r * s), glm::normalize(glm::mat3(xf) * (s / r)));  // gradient of |p/r|^2
  };
  put(glm::vec3(0.0f, 1.0f, 0.0f));
  for (uint32_t i = 1; i < stacks; ++i) {
    const double theta = 3.14159265358979323846 * double(i) / double(stacks);
    for (uint32_t j = 0; j < slices; ++j) {
      const double phi = 2.0 * 3.14159265358979323846 * double(j) / double(slices);
      put(glm::vec3(float(std::sin(theta) * std::cos(phi)), float(std::cos(theta)),
                    float(std::sin(theta) * std::sin(phi))));
    }
  }
  put(glm::vec3(0.0f, -1.0f, 0.0f));
  const uint32_t north = base, south = base + 1 + (stacks - 1) * slices;
  const auto ring = [&](uint32_t i, uint32_t j) { return base + 1 + (i - 1) * slices + j % slices; };
  for (uint32_t j = 0; j < slices; ++j) add_triangle(m, north, ring(1, j + 1), ring(1, j), material);
  for (uint32_t i = 1; i + 1 < stacks; ++i)
    for (uint32_t j = 0; j < slices; ++j) {
      const uint32_t a = ring(i, j), b = ring(i, j + 1), c = ring(i + 1, j + 1), d = ring(i + 1, j);
      add_triangle(m, a, b, c, material);
      add_triangle(m, a, c, d, material);
    }
  for (uint32_t j = 0; j < slices; ++j) add_triangle(m, ring(stacks - 1, j), ring(stacks - 1, j + 1), south, material);
}

// Regular icosahedron with flat faces (each face its own three vertices).
void add_icosahedron(Mesh& m, const glm::vec3& centre, float radius, uint32_t material) {
  const float g = 1.6180339887f;
  const glm::vec3 v[12] = {{-1, g, 0}, {1, g, 0}, {-1, -g, 0}, {1, -g, 0}, {0, -1, g},  {0, 1, g},
                           {0, -1, -g}, {0, 1, -g}, {g, 0, -1}, {g, 0, 1},  {-g, 0, -1}, {-g, 0, 1}};
  const int f[20][3] = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                        {11, 10, 2}, {10, 7, 6}, {7, 1, 8},   {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
                        {3, 8, 9},  {4, 9, 5},  {2, 4, 11},  {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (const auto& face : f) {
    glm::vec3 a = centre + radius * glm::normalize(v[face[0]]);
    glm::vec3 b = centre + radius * glm::normalize(v[face[1]]);
    glm::vec3 c = centre + radius * glm::normalize(v[face[2]]);
    glm::vec3 n = glm::cross(b - a, c - a);
    if (glm::dot(n, a + b + c - 3.0f * centre) < 0.0f) {  // convex: outward = away from the centre
      std::swap(b, c);
      n = -n;
    }
    n = glm::normalize(n);
    add_triangle(m, add_vertex(m, a, n), add_vertex(m, b, n), add_vertex(m, c, n), material);
  }
}

// A (2,3) torus knot tube of `along` x `around` quads (2 * along * around triangles) inside the unit
// ball.  The tube follows the curve's Frenet frame, which is periodic because the curve is closed and
// never straight.
Mesh torus_knot(uint32_t along, uint32_t around, double tube, uint32_t material) {
  Mesh m;
  m.name = "torus knot";
  m.positions.reserve(size_t(along) * around);
  m.normals.reserve(size_t(along) * around);
  const double scale = 1.0 / (3.0 + tube);  // the curve reaches radius 3
  for (uint32_t i = 0; i < along; ++i) {
    const double t = 2.0 * 3.14159265358979323846 * double(i) / double(along);
    // C(t) = (rho cos 2t, rho sin 2t, -sin 3t) with rho = 2 + cos 3t, and its first two derivatives.
    const double c2 = std::cos(2 * t), s2 = std::sin(2 * t), c3 = std::cos(3 * t), s3 = std::sin(3 * t);
    const double rho = 2 + c3, rho1 = -3 * s3, rho2 = -9 * c3;
    const glm::dvec3 p(rho * c2, rho * s2, -s3);
    const glm::dvec3 d1(rho1 * c2 - 2 * rho * s2, rho1 * s2 + 2 * rho * c2, -3 * c3);
    const glm::dvec3 d2(rho2 * c2 - 4 * rho1 * s2 - 4 * rho * c2, rho2 * s2 + 4 * rho1 * c2 - 4 * rho * s2, 9 * s3);
    const glm::dvec3 T = glm::normalize(d1);
    const glm::dvec3 B = glm::normalize(glm::cross(d1, d2));
    const glm::dvec3 N = glm::cross(B, T);
    for (uint32_t j = 0; j < around; ++j) {
      const double a = 2.0 * 3.14159265358979323846 * double(j) / double(around);
      const glm::dvec3 n = std::cos(a) * N + std::sin(a) * B;
      add_vertex(m, glm::vec3((p + tube * n) * scale), glm::vec3(n));
    }
  }
  const auto idx = [&](uint32_t i, uint32_t j) { return (i % along) * around + j % around; };
  for (uint32_t i = 0; i < along; ++i)
    for (uint32_t j = 0; j < around; ++j) {
      // Stepping along the curve then around the tube turns inwards, so these go the other way.
      const uint32_t a = idx(i, j), b = idx(i + 1, j), c = idx(i + 1, j + 1), d = idx(i, j + 1);
      add_triangle(m, a, c, b, material);
      add_triangle(m, a, d, c, material);
    }
  return m;
}

// ---- scene building ----

uint32_t add_material(Scene& s, const std::string& name, const glm::vec3& albedo,
                      const glm::vec3& emission = glm::vec3(0.0f)) {
  Material m;
  m.name = name;
  m.albedo = albedo;
  m.emission = emission;
  s.materials.push_back(m);
  return uint32_t(s.materials.size() - 1);
}

// One object placed once.
uint32_t add_object(Scene& s, Mesh&& mesh, const std::string& name, const glm::mat4& xf = glm::mat4(1.0f)) {
  mesh.name = name;
  s.meshes.push_back(std::move(mesh));
  Instance inst;
  inst.mesh = uint32_t(s.meshes.size() - 1);
  inst.object_to_world = xf;
  inst.name = name;
  s.instances.push_back(inst);
  return inst.mesh;
}

// Six inward-facing walls of the box [lo, hi], one object each, sharing their corners exactly so that
// together they are closed.  walls: materials of -x, +x, -y, +y, -z, +z.
void add_room(Scene& s, const glm::vec3& lo, const glm::vec3& hi, const std::array<uint32_t, 6>& walls) {
  const char* names[6] = {"left wall", "right wall", "floor", "ceiling", "back wall", "front wall"};
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side < 2; ++side) {
      Mesh m;
      add_box_face(m, lo, hi, axis, side, true, walls[size_t(2 * axis + side)]);
      add_object(s, std::move(m), names[2 * axis + side]);
    }
}

// A horizontal quad light at height y facing down.
void add_ceiling_light(Scene& s, const std::string& name, float x, float z, float half_x, float half_z, float y,
                       uint32_t material) {
  Mesh m;
  add_quad(m, {x - half_x, y, z - half_z}, {x + half_x, y, z - half_z}, {x + half_x, y, z + half_z},
           {x - half_x, y, z + half_z}, material);
  add_object(s, std::move(m), name);
}

glm::mat4 rigid(const glm::vec3& position, float angle_y) {
  return glm::rotate(glm::translate(glm::mat4(1.0f), position), angle_y, glm::vec3(0.0f, 1.0f, 0.0f));
}

// Objects sit this far above the surface they rest on: coplanar faces would make hit ids ambiguous.
constexpr float kGap = 1e-3f;

// Half the width (x) and depth (z) of cornell's light: 130 x 105 of the classic 555-unit box.
constexpr float kCornellLightX = 0.234f, kCornellLightZ = 0.189f;

Scene cornell() {
  Scene s;
  const uint32_t white = add_material(s, "white", glm::vec3(0.73f));
  const uint32_t red = add_material(s, "red", {0.65f, 0.05f, 0.05f});
  const uint32_t green = add_material(s, "green", {0.12f, 0.45f, 0.15f});
  const uint32_t light = add_material(s, "light", glm::vec3(0.78f), {17.0f, 12.0f, 4.0f});
  const uint32_t tall = add_material(s, "tall box", {0.72f, 0.72f, 0.68f});
  const uint32_t shrt = add_material(s, "short box", {0.70f, 0.72f, 0.75f});
  const uint32_t blue = add_material(s, "sphere", {0.25f, 0.35f, 0.75f});
  const uint32_t gold = add_material(s, "icosahedron", {0.85f, 0.65f, 0.15f});

  // Open at the front (+z), as the classic box is photographed: five walls.
  const glm::vec3 lo(-1.0f), hi(1.0f);
  const char* names[5] = {"left wall", "right wall", "floor", "ceiling", "back wall"};
  const uint32_t materials[5] = {red, green, white, white, white};
  for (int w = 0; w < 5; ++w) {
    Mesh m;
    if (w == 3) {
      // The ceiling around the light's opening, the classic 130 x 105 of the 555-unit box: the light
      // fills it flush, so no gap above it lets a path reach its back or a ceiling point beside it at
      // a millimetre's distance (the fireflies of a light hung below the ceiling).  Four trapezoids
      // from the room's corners to the opening's: no T-junction with the walls or the light.
      const glm::vec2 outer[4] = {{-1.0f, -1.0f}, {1.0f, -1.0f}, {1.0f, 1.0f}, {-1.0f, 1.0f}};
      const glm::vec2 inner[4] = {{-kCornellLightX, -kCornellLightZ}, {kCornellLightX, -kCornellLightZ},
                                  {kCornellLightX, kCornellLightZ}, {-kCornellLightX, kCornellLightZ}};
      for (int k = 0; k < 4; ++k) {
        const auto at = [](const glm::vec2& q) { return glm::vec3(q.x, 1.0f, q.y); };
        // Corners in this order turn counter-clockwise seen from below: the trapezoid faces down.
        add_quad(m, at(outer[k]), at(outer[(k + 1) % 4]), at(inner[(k + 1) % 4]), at(inner[k]), white);
      }
    } else {
      add_box_face(m, lo, hi, w / 2, w % 2, true, materials[w]);
    }
    add_object(s, std::move(m), names[w]);
  }
  add_ceiling_light(s, "light", 0.0f, 0.0f, kCornellLightX, kCornellLightZ, 1.0f, light);

  Mesh tall_box, short_box, sphere, ico;
  add_box(tall_box, {0.3f, 0.6f, 0.3f}, tall, rigid({-0.35f, -0.4f + kGap, -0.35f}, 0.3f));
  add_object(s, std::move(tall_box), "tall box");
  add_box(short_box, {0.3f, 0.3f, 0.3f}, shrt, rigid({0.35f, -0.7f + kGap, 0.3f}, -0.3f));
  add_object(s, std::move(short_box), "short box");
  add_ellipsoid(sphere, glm::vec3(0.3f), 32, 64, blue, glm::translate(glm::mat4(1.0f), {-0.5f, -0.7f + kGap, 0.45f}));
  add_object(s, std::move(sphere), "sphere");
  // Resting on an edge on the short box (its lowest vertices are 0.8507 radius below its centre).
  const float r = 0.18f;
  add_icosahedron(ico, {0.35f, -0.4f + 2.0f * kGap + 0.8507f * r, 0.3f}, r, gold);
  add_object(s, std::move(ico), "icosahedron");

  // The classic camera, scaled from the 555-unit box: 800 units before the open front, looking in,
  // a 39.3 degree vertical field of view that just takes in the front opening.
  s.camera.position = {0.0f, 0.0f, 1.0f + 800.0f * 2.0f / 555.0f};
  s.camera.target = {0.0f, 0.0f, 0.0f};
  s.camera.up = {0.0f, 1.0f, 0.0f};
  s.camera.yfov = 0.6859f;
  s.background = glm::vec3(0.0f);
  return s;
}

Scene instances() {
  Scene s;
  const uint32_t walls = add_material(s, "walls", {0.75f, 0.75f, 0.72f});
  const uint32_t floor = add_material(s, "floor", {0.55f, 0.55f, 0.55f});
  const uint32_t ceiling = add_material(s, "ceiling", glm::vec3(0.8f));
  const uint32_t light = add_material(s, "light", glm::vec3(0.78f), {15.0f, 15.0f, 14.0f});
  const uint32_t knot = add_material(s, "knot", {0.8f, 0.45f, 0.2f});
  const uint32_t box_a = add_material(s, "tall box", {0.3f, 0.6f, 0.35f});
  const uint32_t box_b = add_material(s, "short box", {0.35f, 0.4f, 0.7f});
  const uint32_t ball = add_material(s, "sphere", {0.7f, 0.2f, 0.25f});

  const glm::vec3 lo(-7.5f, 0.0f, -7.5f), hi(7.5f, 6.0f, 7.5f);
  add_room(s, lo, hi, {walls, walls, floor, ceiling, walls, walls});
  add_ceiling_light(s, "light left", -3.0f, 0.0f, 1.2f, 1.2f, hi.y - 2e-3f, light);
  add_ceiling_light(s, "light right", 3.0f, 0.0f, 1.2f, 1.2f, hi.y - 2e-3f, light);

  Mesh tall_box, short_box, sphere;
  add_box(tall_box, {0.4f, 1.2f, 0.4f}, box_a, rigid({-6.6f, 1.2f + kGap, -6.6f}, 0.4f));
  add_object(s, std::move(tall_box), "tall box");
  add_box(short_box, {0.5f, 0.5f, 0.5f}, box_b, rigid({6.6f, 0.5f + kGap, -6.6f}, -0.3f));
  add_object(s, std::move(short_box), "short box");
  add_ellipsoid(sphere, glm::vec3(0.55f), 24, 48, ball, glm::translate(glm::mat4(1.0f), {0.0f, 0.55f + kGap, -6.8f}));
  add_object(s, std::move(sphere), "sphere");

  // One 51,200-triangle object (320 x 80 quads), instanced on an 8 x 8 grid.  Object space is the unit
  // ball, so with scales <= 0.55 * 1.25 every instance stays inside its 1.5-wide cell and the room.
  s.meshes.push_back(torus_knot(320, 80, 0.5, knot));
  const uint32_t knot_mesh = uint32_t(s.meshes.size() - 1);
  Random rng(0x1a2b3c4dULL);
  for (int gi = 0; gi < 8; ++gi)
    for (int gj = 0; gj < 8; ++gj) {
      const int k = gi * 8 + gj;
      const float angle = rng.uniform(0.0f, 2.0f * kPi);
      const float sc = rng.uniform(0.45f, 0.55f);
      const glm::vec3 scale = k % 4 == 3 ? glm::vec3(1.25f * sc, 0.8f * sc, sc) : glm::vec3(sc);  // some squashed
      Instance inst;
      inst.mesh = knot_mesh;
      inst.object_to_world = glm::scale(rigid({(float(gi) - 3.5f) * 1.5f, 0.75f, (float(gj) - 3.5f) * 1.5f}, angle), scale);
      inst.name = "knot " + std::to_string(k);
      s.instances.push_back(inst);
    }

  s.camera.position = {0.0f, 3.5f, 7.3f};
  s.camera.target = {0.0f, 0.5f, -0.5f};
  s.camera.up = {0.0f, 1.0f, 0.0f};
  s.camera.yfov = 1.0f;
  s.background = glm::vec3(0.0f);
  return s;
}

// ---- carousel (rigid animation) ----

// A rig node that places one instance with its current transform (static objects).
void add_static_node(Scene& s, uint32_t instance) {
  RigNode node;
  node.has_matrix = true;
  node.matrix = glm::dmat4(s.instances[instance].object_to_world);
  node.instance = int(instance);
  s.rig.order.push_back(uint32_t(s.rig.nodes.size()));
  s.rig.nodes.push_back(node);
}

uint32_t add_rig_node(Scene& s, const RigNode& node) {
  s.rig.order.push_back(uint32_t(s.rig.nodes.size()));
  s.rig.nodes.push_back(node);
  return uint32_t(s.rig.nodes.size() - 1);
}

// glTF order x, y, z, w: the rotation by `angle` about the unit `axis`.
glm::vec4 axis_angle(const glm::dvec3& axis, double angle) {
  const glm::dvec3 v = axis * std::sin(0.5 * angle);
  return glm::vec4(float(v.x), float(v.y), float(v.z), float(std::cos(0.5 * angle)));
}

Scene carousel() {
  Scene s;
  const uint32_t walls = add_material(s, "walls", {0.75f, 0.75f, 0.72f});
  const uint32_t floor = add_material(s, "floor", {0.55f, 0.55f, 0.55f});
  const uint32_t ceiling = add_material(s, "ceiling", glm::vec3(0.8f));
  const uint32_t light = add_material(s, "light", glm::vec3(0.78f), {18.0f, 17.0f, 15.0f});
  const uint32_t knot = add_material(s, "knot", {0.8f, 0.45f, 0.2f});
  const uint32_t ball = add_material(s, "ball", {0.25f, 0.4f, 0.75f});
  const uint32_t stone = add_material(s, "pedestal", {0.6f, 0.58f, 0.55f});
  const uint32_t red = add_material(s, "sphere", {0.7f, 0.2f, 0.25f});

  const glm::vec3 lo(-7.5f, 0.0f, -7.5f), hi(7.5f, 6.0f, 7.5f);
  add_room(s, lo, hi, {walls, walls, floor, ceiling, walls, walls});
  add_ceiling_light(s, "light", 0.0f, 0.0f, 1.5f, 1.5f, hi.y - 2e-3f, light);
  Mesh pedestal, sphere;
  add_box(pedestal, {0.9f, 0.5f, 0.9f}, stone, glm::translate(glm::mat4(1.0f), {0.0f, 0.5f + kGap, 0.0f}));
  add_object(s, std::move(pedestal), "pedestal");
  add_ellipsoid(sphere, glm::vec3(0.7f), 24, 48, red, glm::translate(glm::mat4(1.0f), {0.0f, 1.7f + 2.0f * kGap, 0.0f}));
  add_object(s, std::move(sphere), "sphere");
  for (uint32_t i = 0; i < uint32_t(s.instances.size()); ++i) add_static_node(s, i);

  s.meshes.push_back(torus_knot(160, 40, 0.5, knot));
  const uint32_t knot_mesh = uint32_t(s.meshes.size() - 1);
  Mesh ball_mesh;
  add_ellipsoid(ball_mesh, glm::vec3(0.45f), 32, 64, ball);
  ball_mesh.name = "ball";
  s.meshes.push_back(std::move(ball_mesh));
  const uint32_t ball_mesh_index = uint32_t(s.meshes.size() - 1);

  const double pi = 3.14159265358979323846;
  Animation anim;
  anim.name = "carousel";
  // Keys every 0.5 s (hub: 45 degrees apart, so every slerp takes the intended way round).
  std::vector<float> half_seconds;
  for (int k = 0; k <= 8; ++k) half_seconds.push_back(0.5f * float(k));

  RigNode hub;
  const uint32_t hub_node = add_rig_node(s, hub);
  AnimationChannel turn;
  turn.node = hub_node;
  turn.path = AnimationPath::Rotation;
  turn.times = half_seconds;
  for (float t : half_seconds) turn.values.push_back(axis_angle({0.0, 1.0, 0.0}, -2.0 * pi * double(t) / 4.0));
  anim.channels.push_back(turn);

  // 16 knots on a ring of radius 5 around the hub, each spinning twice in 4 s about its own tilted
  // axis; the even ones bob (a cubic spline through samples of a sine, its derivative as tangents).
  for (int k = 0; k < 16; ++k) {
    const double phi = 2.0 * pi * double(k) / 16.0;
    Instance inst;
    inst.mesh = knot_mesh;
    inst.name = "knot " + std::to_string(k);
    s.instances.push_back(inst);
    RigNode node;
    node.parent = int(hub_node);
    node.translation = glm::dvec3(5.0 * std::cos(phi), 1.6, 5.0 * std::sin(phi));
    node.scale = glm::dvec3(0.6);
    node.instance = int(s.instances.size() - 1);
    const uint32_t n = add_rig_node(s, node);
    const glm::dvec3 axis = glm::normalize(glm::dvec3(std::cos(phi + 1.0), 2.0, std::sin(phi + 1.0)));
    AnimationChannel spin;
    spin.node = n;
    spin.path = AnimationPath::Rotation;
    for (int i = 0; i <= 16; ++i) {  // 45 degrees every 0.25 s
      spin.times.push_back(0.25f * float(i));
      spin.values.push_back(axis_angle(axis, phi + 0.25 * pi * double(i)));
    }
    anim.channels.push_back(spin);
    if (k % 2 == 0) {
      AnimationChannel bob;
      bob.node = n;
      bob.path = AnimationPath::Translation;
      bob.interpolation = Interpolation::CubicSpline;
      bob.times = half_seconds;
      for (float t : half_seconds) {  // y = 1.6 + 0.5 sin(pi t + phi), period 2 s
        const double a = pi * double(t) + phi;
        const glm::vec4 tangent(0.0f, float(0.5 * pi * std::cos(a)), 0.0f, 0.0f);
        bob.values.push_back(tangent);
        bob.values.push_back(glm::vec4(glm::vec3(node.translation.x, 1.6 + 0.5 * std::sin(a), node.translation.z), 0.0f));
        bob.values.push_back(tangent);
      }
      anim.channels.push_back(bob);
    }
  }
  // 8 balls on an inner ring, pulsing in scale once a second: LINEAR (even) and STEP (odd).
  for (int j = 0; j < 8; ++j) {
    const double phi = 2.0 * pi * (double(j) + 0.5) / 8.0;
    Instance inst;
    inst.mesh = ball_mesh_index;
    inst.name = "ball " + std::to_string(j);
    s.instances.push_back(inst);
    RigNode node;
    node.translation = glm::dvec3(2.6 * std::cos(phi), 0.62, 2.6 * std::sin(phi));
    node.instance = int(s.instances.size() - 1);
    AnimationChannel pulse;
    pulse.node = add_rig_node(s, node);
    pulse.path = AnimationPath::Scale;
    pulse.interpolation = j % 2 == 0 ? Interpolation::Linear : Interpolation::Step;
    for (int i = 0; i <= 8; ++i) {
      pulse.times.push_back(0.5f * float(i));
      const float scale = (i + j) % 2 == 0 ? 0.7f : 1.3f;
      pulse.values.push_back(glm::vec4(scale, scale, scale, 0.0f));
    }
    anim.channels.push_back(pulse);
  }
  s.rig.animations.push_back(std::move(anim));

  s.camera.position = {0.0f, 4.2f, 7.3f};
  s.camera.target = {0.0f, 1.2f, -0.5f};
  s.camera.up = {0.0f, 1.0f, 0.0f};
  s.camera.yfov = 1.0f;
  s.background = glm::vec3(0.0f);
  s.name = "builtin:carousel";
  pose_scene(s, 0.0);  // the still pose: t = 0
  return s;
}

// ---- generated:T:O:S ----

// A strictly parsed decimal number: digits only, no sign, no spaces, no overflow.
uint64_t parse_count(const std::string& text, const std::string& what, const std::string& spec) {
  uint64_t value = 0;
  const char* end = text.data() + text.size();
  const auto [ptr, ec] = std::from_chars(text.data(), end, value);
  if (text.empty() || text[0] < '0' || text[0] > '9' || ec != std::errc() || ptr != end)
    throw InputError("builtin:" + spec + ": " + what + " '" + text + "' is not a non-negative integer");
  return value;
}

// `count` triangles of side ~0.1 scattered in the cube of half-size `half` around the origin.
void add_loose_triangles(Mesh& m, uint64_t count, float half, Random& rng, uint32_t material) {
  for (uint64_t i = 0; i < count; ++i) {
    const glm::vec3 p(rng.uniform(-half, half), rng.uniform(-half, half), rng.uniform(-half, half));
    glm::mat4 r = glm::rotate(glm::mat4(1.0f), rng.uniform(0.0f, 2.0f * kPi), glm::vec3(0.0f, 1.0f, 0.0f));
    r = glm::rotate(r, rng.uniform(0.0f, 2.0f * kPi), glm::vec3(1.0f, 0.0f, 0.0f));
    const glm::vec3 e1 = glm::mat3(r) * glm::vec3(0.1f, 0.0f, 0.0f), e2 = glm::mat3(r) * glm::vec3(0.0f, 0.1f, 0.0f);
    const glm::vec3 n = glm::normalize(glm::cross(e1, e2));
    add_triangle(m, add_vertex(m, p, n), add_vertex(m, p + e1, n), add_vertex(m, p + e2, n), material);
  }
}

// params: what follows "generated:", or nothing at all for plain "generated".
Scene generated(const std::string& spec, const std::optional<std::string>& params) {
  std::vector<std::string> fields;
  if (params) {
    size_t start = 0;
    for (;;) {
      const size_t colon = params->find(':', start);
      fields.push_back(params->substr(start, colon - start));
      if (colon == std::string::npos) break;
      start = colon + 1;
    }
  }
  if (fields.size() > 3) throw InputError("builtin:" + spec + ": expected generated[:T[:O[:S]]]");
  const uint64_t T = fields.size() > 0 ? parse_count(fields[0], "T (triangles)", spec) : 100000;
  const uint64_t O = fields.size() > 1 ? parse_count(fields[1], "O (objects)", spec) : 16;
  const uint64_t S = fields.size() > 2 ? parse_count(fields[2], "S (seed)", spec) : 1;
  if (O < 1) throw InputError("builtin:" + spec + ": O (objects) must be at least 1");
  if (T < O) throw InputError("builtin:" + spec + ": T (triangles) must be at least O (objects)");
  if (T > 50000000) throw InputError("builtin:" + spec + ": T (triangles) must be at most 50,000,000");
  if (O > 1000000) throw InputError("builtin:" + spec + ": O (objects) must be at most 1,000,000");

  Scene s;
  Random rng(S ^ 0x6a09e667f3bcc909ULL);
  const uint32_t palette = uint32_t(std::min<uint64_t>(O, 8));
  for (uint32_t i = 0; i < palette; ++i) {
    const glm::vec3 albedo(rng.uniform(0.2f, 0.9f), rng.uniform(0.2f, 0.9f), rng.uniform(0.2f, 0.9f));
    add_material(s, "blob " + std::to_string(i), albedo);
  }
  const uint32_t light = add_material(s, "light", glm::vec3(0.78f), glm::vec3(10.0f));

  // Centres fill a cube whose side grows with the cube root of O, so the density stays about the same.
  const float side = 2.0f + 2.5f * std::cbrt(float(O));
  uint64_t made = 0;
  for (uint64_t i = 0; i < O; ++i) {
    // Cumulative targets spread T exactly; what one object cannot use passes to the next.
    const uint64_t budget = T * (i + 1) / O - made;
    const uint32_t material = uint32_t(i % palette);
    const glm::vec3 radii(rng.uniform(0.3f, 1.0f), rng.uniform(0.3f, 1.0f), rng.uniform(0.3f, 1.0f));
    Mesh m;
    uint64_t produced = budget;
    if (budget >= 6) {
      // 2 * slices * bands triangles (bands = stacks - 1), about twice as many slices as bands.
      uint64_t bands = std::max<uint64_t>(1, uint64_t(std::sqrt(double(budget) / 4.0)));
      while (bands > 1 && budget / (2 * bands) < 3) --bands;
      const uint64_t slices = budget / (2 * bands);
      produced = 2 * slices * bands;
      m.positions.reserve(slices * bands + 2);
      m.normals.reserve(slices * bands + 2);
      m.triangles.reserve(budget);
      m.materials.reserve(budget);
      add_ellipsoid(m, radii, uint32_t(bands + 1), uint32_t(slices), material);
    } else {
      add_loose_triangles(m, budget, 0.5f, rng, material);
    }
    // The last object takes up the rest as loose triangles hidden near its centre, so T is exact.
    if (i + 1 == O && produced < budget) add_loose_triangles(m, budget - produced, 0.1f, rng, material);
    made += m.triangles.size();
    const glm::vec3 centre(rng.uniform(-0.5f, 0.5f) * side, rng.uniform(-0.5f, 0.5f) * side,
                           rng.uniform(-0.5f, 0.5f) * side);
    glm::mat4 xf = glm::rotate(glm::translate(glm::mat4(1.0f), centre), rng.uniform(0.0f, 2.0f * kPi),
                               glm::vec3(0.0f, 1.0f, 0.0f));
    xf = glm::rotate(xf, rng.uniform(0.0f, 2.0f * kPi), glm::vec3(1.0f, 0.0f, 0.0f));
    add_object(s, std::move(m), "blob " + std::to_string(i), xf);
  }
  const float top = 0.5f * side + 1.5f;
  add_ceiling_light(s, "light", 0.0f, 0.0f, 0.25f * side, 0.25f * side, top, light);

  s.background = glm::vec3(0.1f);  // a dim sky, so that what the light misses is not pitch black
  s.camera = framing_camera(s);
  return s;
}

}  // namespace

Scene builtin_scene(const std::string& name_in) {
  const std::string prefix = "builtin:";
  const std::string name = name_in.compare(0, prefix.size(), prefix) == 0 ? name_in.substr(prefix.size()) : name_in;
  Scene s;
  if (name == "cornell") {
    s = cornell();
  } else if (name == "instances") {
    s = instances();
  } else if (name == "carousel") {
    s = carousel();
  } else if (name == "generated" || name.compare(0, 10, "generated:") == 0) {
    s = generated(name, name.size() > 9 ? std::optional<std::string>(name.substr(10)) : std::nullopt);
  } else {
    throw InputError("builtin:" + name + ": unknown built-in scene (known: cornell, instances, carousel, generated[:T[:O[:S]]])");
  }
  s.name = prefix + name;
  validate_scene(s);
  return s;
}

}  // namespace ls
