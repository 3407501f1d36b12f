// What a hit means on the surface: world position, normals and material.  The path tracer and the
// ray generators share it.
#pragma once

#include "common/kernels/layouts.h"
#include "common/model/scene.h"
#include "common/render/shade_context.h"

#include <vector>

namespace ls {

struct SurfacePoint {
  glm::vec3 position;
  glm::vec3 geometric_normal;  // unit, world space, facing the side the ray came from
  glm::vec3 shading_normal;    // unit, interpolated vertex normal, on the same side
  uint32_t material;
};

// The scene's meshes, instances and materials as the std430 arrays of the shading kernel
// (common/kernels/shade_path.h), prepared once; the lookup itself is the kernel's surface_at.
class SurfaceLookup {
 public:
  explicit SurfaceLookup(const Scene& scene);
  // hit must be a hit (triangle != LS_INVALID); ray_dir is the direction of the ray that found it.
  SurfacePoint at(const lsk::Hit& hit, const glm::vec3& ray_dir) const;
  // The kernel's context over these arrays (no lights; ShadeParams with scene_scale and background).
  lsk::ShadeContext context() const;
  const std::vector<lsk::ShadeInstance>& shade_instances() const { return instances_; }
  const std::vector<lsk::ShadeVertex>& shade_vertices() const { return vertices_; }
  const std::vector<lsk::ShadeTriangle>& shade_triangles() const { return triangles_; }
  const std::vector<lsk::ShadeMaterial>& shade_materials() const { return materials_; }
  // World-space vertices of a triangle.
  void world_triangle(uint32_t instance, uint32_t triangle, glm::vec3& a, glm::vec3& b, glm::vec3& c) const;
  // A power of two at least the largest absolute world coordinate (the ray-offset scale).
  float scene_scale() const { return scene_scale_; }

 private:
  const Scene& scene_;
  std::vector<lsk::ShadeInstance> instances_;
  std::vector<lsk::ShadeVertex> vertices_;
  std::vector<lsk::ShadeTriangle> triangles_;
  std::vector<lsk::ShadeMaterial> materials_;
  float scene_scale_ = 1.0f;
};

lsk::CameraFrame camera_frame(const Camera& camera, uint32_t width, uint32_t height);

}  // namespace ls
