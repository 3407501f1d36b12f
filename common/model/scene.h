// The scene model every loader produces and every structure consumes (C++ only).
//
// A Mesh is an *object*: geometry in its own object space.  An Instance places one mesh in the world
// with an affine transform.  Ids (docs/design.md §9): instance id = index into Scene::instances (the loaders
// order instances by glTF node index); triangle id = index into Mesh::triangles.
#pragma once

#include "common/model/rig.h"

#include <glm/glm.hpp>

#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

namespace ls {

// Bad input of any kind (files, flags, parameters): the programs print what() and exit 2.
struct InputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct Material {
  glm::vec3 albedo{0.8f};    // Lambertian reflectance (glTF baseColorFactor)
  glm::vec3 emission{0.0f};  // radiance emitted by each side (glTF emissiveFactor); non-zero: area light
  std::string name;
};

struct Mesh {
  std::string name;
  std::vector<glm::vec3> positions;
  std::vector<glm::vec3> normals;      // one per position, unit length (from the file, else computed)
  std::vector<glm::uvec3> triangles;   // indices into positions
  std::vector<uint32_t> materials;     // one per triangle: index into Scene::materials
};

struct Instance {
  uint32_t mesh = 0;
  glm::mat4 object_to_world{1.0f};     // affine
  std::string name;
};

struct Camera {
  glm::vec3 position{0.0f, 0.0f, 1.0f};
  glm::vec3 target{0.0f};
  glm::vec3 up{0.0f, 1.0f, 0.0f};
  float yfov = 0.7f;                   // vertical field of view, radians
};

struct Scene {
  std::string name;
  std::vector<Mesh> meshes;
  std::vector<Instance> instances;
  std::vector<Material> materials;
  Camera camera;
  glm::vec3 background{0.0f};          // radiance of rays that leave the scene (a default light for meshes)
  SceneRig rig;                        // glTF nodes and animations (rig.h); empty for static scenes
};

struct Bounds {
  glm::vec3 lo{std::numeric_limits<float>::infinity()};
  glm::vec3 hi{-std::numeric_limits<float>::infinity()};
  void grow(const glm::vec3& p) { lo = glm::min(lo, p); hi = glm::max(hi, p); }
  void grow(const Bounds& b) { lo = glm::min(lo, b.lo); hi = glm::max(hi, b.hi); }
  bool empty() const { return lo.x > hi.x; }
  glm::vec3 centre() const { return 0.5f * (lo + hi); }
  glm::vec3 extent() const { return hi - lo; }
};

size_t triangle_count(const Scene& scene);       // world triangles, every instance counted
Bounds world_bounds(const Scene& scene);
glm::vec3 transform_point(const glm::mat4& m, const glm::vec3& p);
// The box around the 8 transformed corners of `box` (an affine map's image of the box lies inside it).
Bounds transform_bounds(const glm::mat4& m, const Bounds& box);

// Throws InputError when the scene cannot be traced correctly: no triangles, indices out of range,
// NaN/Inf positions or normals, singular or projective transforms, materials out of range, a camera
// with NaN/Inf parameters, no view direction or a field of view outside (0, pi).
void validate_scene(const Scene& scene);

// A camera that frames the world bounds from the front (+z side), looking at the centre.
Camera framing_camera(const Scene& scene);

}  // namespace ls
