#include "common/render/surface.h"

#include "common/kernels/float_bits.h"
#include "common/kernels/scaled_geometry.h"

#include <algorithm>
#include <cmath>

namespace ls {

SurfaceLookup::SurfaceLookup(const Scene& scene) : scene_(scene) {
  std::vector<uint32_t> first_vertex, first_triangle;
  for (const Mesh& mesh : scene.meshes) {
    first_vertex.push_back(uint32_t(vertices_.size()));
    first_triangle.push_back(uint32_t(triangles_.size()));
    for (size_t v = 0; v < mesh.positions.size(); ++v) {
      lsk::ShadeVertex sv{};
      sv.position = mesh.positions[v];
      sv.normal = mesh.normals[v];
      vertices_.push_back(sv);
    }
    for (size_t t = 0; t < mesh.triangles.size(); ++t) {
      lsk::ShadeTriangle st{};
      st.idx = mesh.triangles[t] + glm::uvec3(first_vertex.back());
      st.material = mesh.materials[t];
      triangles_.push_back(st);
    }
  }
  for (const Instance& inst : scene.instances) {
    const glm::mat3 normal_matrix = glm::transpose(glm::inverse(glm::mat3(inst.object_to_world)));
    lsk::ShadeInstance si{};
    si.col0 = glm::vec3(inst.object_to_world[0]);
    si.col1 = glm::vec3(inst.object_to_world[1]);
    si.col2 = glm::vec3(inst.object_to_world[2]);
    si.col3 = glm::vec3(inst.object_to_world[3]);
    si.ncol0 = normal_matrix[0];
    si.ncol1 = normal_matrix[1];
    si.ncol2 = normal_matrix[2];
    si.first_vertex = first_vertex[inst.mesh];
    si.first_triangle = first_triangle[inst.mesh];
    instances_.push_back(si);
  }
  for (const Material& m : scene.materials) {
    lsk::ShadeMaterial sm{};
    sm.albedo = m.albedo;
    sm.emission = m.emission;
    materials_.push_back(sm);
  }
  const Bounds b = world_bounds(scene);
  const glm::vec3 m3 = glm::max(glm::abs(b.lo), glm::abs(b.hi));
  const float m = std::max({m3.x, m3.y, m3.z});
  int e = 0;
  std::frexp(m, &e);  // m < 2^e
  scene_scale_ = std::ldexp(1.0f, std::clamp(e, -120, 120));
}

void SurfaceLookup::world_triangle(uint32_t instance, uint32_t triangle, glm::vec3& a, glm::vec3& b, glm::vec3& c) const {
  const Instance& inst = scene_.instances[instance];
  const Mesh& mesh = scene_.meshes[inst.mesh];
  const glm::uvec3 idx = mesh.triangles[triangle];
  a = transform_point(inst.object_to_world, mesh.positions[idx.x]);
  b = transform_point(inst.object_to_world, mesh.positions[idx.y]);
  c = transform_point(inst.object_to_world, mesh.positions[idx.z]);
}

lsk::ShadeContext SurfaceLookup::context() const {
  lsk::ShadeContext c;
  c.shade_instances = instances_.data();
  c.shade_vertices = vertices_.data();
  c.shade_triangles = triangles_.data();
  c.materials = materials_.data();
  c.shade.background = scene_.background;
  c.shade.scene_scale = scene_scale_;
  return c;
}

SurfacePoint SurfaceLookup::at(const lsk::Hit& hit, const glm::vec3& ray_dir) const {
  SurfacePoint sp;
  context().surface_at(hit, ray_dir, sp.position, sp.geometric_normal, sp.shading_normal, sp.material);
  return sp;
}

lsk::CameraFrame camera_frame(const Camera& camera, uint32_t width, uint32_t height) {
  lsk::CameraFrame f;
  f.position = camera.position;
  // normalize_any: at 1e20 the length of target - position overflows (kernels/scaled_geometry.h).
  f.forward = lsk::normalize_any(camera.target - camera.position);
  if (f.forward == glm::vec3(0.0f)) f.forward = glm::vec3(0.0f, 0.0f, -1.0f);
  glm::vec3 right = glm::cross(f.forward, camera.up);
  if (!(glm::length(right) > 1e-6f)) right = glm::cross(f.forward, std::fabs(f.forward.y) < 0.9f ? glm::vec3(0, 1, 0) : glm::vec3(1, 0, 0));
  f.right = glm::normalize(right);
  f.up = glm::cross(f.right, f.forward);
  f.tan_half_fov = std::tan(0.5f * camera.yfov);
  f.width = width;
  f.height = height;
  f.aspect = float(width) / float(height);
  return f;
}

}  // namespace ls
