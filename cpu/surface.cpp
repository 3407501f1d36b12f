#include "surface.h"

#include "kernels/float_bits.h"
#include "kernels/scaled_geometry.h"

#include <algorithm>
#include <cmath>

namespace ls {

SurfaceLookup::SurfaceLookup(const Scene& scene) : scene_(scene) {
  for (const Instance& inst : scene.instances)
    normal_matrix_.push_back(glm::transpose(glm::inverse(glm::mat3(inst.object_to_world))));
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

SurfacePoint SurfaceLookup::at(const lsk::Hit& hit, const glm::vec3& ray_dir) const {
  const Instance& inst = scene_.instances[hit.instance];
  const Mesh& mesh = scene_.meshes[inst.mesh];
  const glm::uvec3 idx = mesh.triangles[hit.triangle];
  glm::vec3 a, b, c;
  world_triangle(hit.instance, hit.triangle, a, b, c);
  const float w0 = 1.0f - hit.u - hit.v;
  SurfacePoint sp;
  sp.position = a * w0 + b * hit.u + c * hit.v;
  // Edges scaled by a power of two first: at 1e20 or 1e-20 a float cross product over- or underflows.
  glm::vec3 e1 = b - a, e2 = c - a;
  const int k = lsk::unit_exponent(std::max(lsk::max_abs(e1), lsk::max_abs(e2)));
  glm::vec3 ng = glm::cross(lsk::scale_pow2(e1, k), lsk::scale_pow2(e2, k));
  const float len = glm::length(ng);
  ng = len > 0.0f && std::isfinite(len) ? ng / len : -glm::normalize(ray_dir);
  if (glm::dot(ng, ray_dir) > 0.0f) ng = -ng;
  glm::vec3 ns = normal_matrix_[hit.instance] *
                 (mesh.normals[idx.x] * w0 + mesh.normals[idx.y] * hit.u + mesh.normals[idx.z] * hit.v);
  ns = lsk::normalize_any(ns);  // the normal matrix of a 1e-20 scale has entries of 1e20
  if (ns == glm::vec3(0.0f) || !std::isfinite(ns.x + ns.y + ns.z)) ns = ng;
  if (glm::dot(ns, ng) < 0.0f) ns = -ns;
  sp.geometric_normal = ng;
  sp.shading_normal = ns;
  sp.material = mesh.materials[hit.triangle];
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
