#include "common/model/scene.h"


#include <cmath>
#include <cstdio>

namespace ls {

glm::vec3 transform_point(const glm::mat4& m, const glm::vec3& p) {
  return glm::vec3(m * glm::vec4(p, 1.0f));
}

size_t triangle_count(const Scene& scene) {
  size_t n = 0;
  for (const Instance& inst : scene.instances) n += scene.meshes[inst.mesh].triangles.size();
  return n;
}

Bounds transform_bounds(const glm::mat4& m, const Bounds& box) {
  Bounds out;
  for (int corner = 0; corner < 8; ++corner) {
    const glm::vec3 p((corner & 1) ? box.hi.x : box.lo.x, (corner & 2) ? box.hi.y : box.lo.y, (corner & 4) ? box.hi.z : box.lo.z);
    out.grow(transform_point(m, p));
  }
  return out;
}

Bounds world_bounds(const Scene& scene) {
  Bounds b;
  for (const Instance& inst : scene.instances)
    for (const glm::vec3& p : scene.meshes[inst.mesh].positions) b.grow(transform_point(inst.object_to_world, p));
  return b;
}

static bool finite(const glm::vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

void validate_scene(const Scene& scene) {
  const std::string where = scene.name.empty() ? std::string("scene") : scene.name;
  if (scene.instances.empty()) throw InputError(where + ": no mesh instances, nothing to trace");
  for (size_t m = 0; m < scene.meshes.size(); ++m) {
    const Mesh& mesh = scene.meshes[m];
    const std::string mname = where + ": mesh " + std::to_string(m) + (mesh.name.empty() ? "" : " '" + mesh.name + "'");
    if (mesh.normals.size() != mesh.positions.size()) throw InputError(mname + ": normals and positions differ in count");
    if (mesh.materials.size() != mesh.triangles.size()) throw InputError(mname + ": one material per triangle expected");
    for (size_t i = 0; i < mesh.positions.size(); ++i)
      if (!finite(mesh.positions[i])) throw InputError(mname + ": vertex " + std::to_string(i) + " is NaN or infinite");
    for (size_t i = 0; i < mesh.normals.size(); ++i)
      if (!finite(mesh.normals[i])) throw InputError(mname + ": normal " + std::to_string(i) + " is NaN or infinite");
    for (const glm::uvec3& t : mesh.triangles)
      if (t.x >= mesh.positions.size() || t.y >= mesh.positions.size() || t.z >= mesh.positions.size())
        throw InputError(mname + ": triangle index out of range");
    for (uint32_t mat : mesh.materials)
      if (mat >= scene.materials.size()) throw InputError(mname + ": material index out of range");
  }
  size_t tris = 0;
  for (size_t i = 0; i < scene.instances.size(); ++i) {
    const Instance& inst = scene.instances[i];
    if (inst.mesh >= scene.meshes.size()) throw InputError(where + ": instance " + std::to_string(i) + " names a missing mesh");
    const glm::mat4& m = inst.object_to_world;
    for (int c = 0; c < 4; ++c)
      for (int r = 0; r < 4; ++r)
        if (!std::isfinite(m[c][r])) throw InputError(where + ": instance " + std::to_string(i) + " has a NaN or infinite transform");
    if (m[0][3] != 0.0f || m[1][3] != 0.0f || m[2][3] != 0.0f || m[3][3] != 1.0f)
      throw InputError(where + ": instance " + std::to_string(i) + " has a projective (non-affine) transform");
    // In double: a uniform scale of 1e-20 has a float determinant of 1e-60, which underflows.
    const double det = glm::determinant(glm::dmat3(glm::mat3(m)));
    if (!(std::fabs(det) > 0.0) || !std::isfinite(det))
      throw InputError(where + ": instance " + std::to_string(i) + " has a singular transform");
    tris += scene.meshes[inst.mesh].triangles.size();
  }
  if (tris == 0) throw InputError(where + ": zero triangles");
  if (tris >= (size_t(1) << 31)) throw InputError(where + ": more than 2^31 triangles");
  for (const Material& mat : scene.materials)
    if (!finite(mat.albedo) || !finite(mat.emission) || glm::any(glm::lessThan(mat.emission, glm::vec3(0.0f))))
      throw InputError(where + ": material '" + mat.name + "' has a NaN, infinite or negative colour");
  const Bounds bounds = world_bounds(scene);
  if (!finite(bounds.lo) || !finite(bounds.hi)) throw InputError(where + ": transformed vertices overflow to infinity");
  const Camera& cam = scene.camera;
  if (!finite(cam.position) || !finite(cam.target) || !finite(cam.up) || !std::isfinite(cam.yfov))
    throw InputError(where + ": the camera has a NaN or infinite parameter");
  if (cam.position == cam.target) throw InputError(where + ": the camera looks at its own position");
  if (!(cam.yfov > 0.0f && cam.yfov < 3.14159f)) throw InputError(where + ": the camera's field of view is not in (0, pi)");
}

Camera framing_camera(const Scene& scene) {
  // In double: the extent's squared length overflows float past 1.8e19 (and underflows below 1e-19),
  // which put the camera at infinity or at distance 1 from a tiny scene, silently.
  const Bounds b = world_bounds(scene);
  const glm::dvec3 lo(b.lo), hi(b.hi);
  const glm::dvec3 centre = 0.5 * (lo + hi);
  Camera cam;
  cam.yfov = 0.7f;
  const double radius = 0.5 * glm::length(hi - lo);
  const double dist = radius / std::tan(0.5 * double(cam.yfov)) * 1.1;
  cam.target = glm::vec3(centre);
  cam.position = glm::vec3(centre + glm::dvec3(0.0, 0.0, dist > 0.0 ? dist : 1.0));
  cam.up = glm::vec3(0.0f, 1.0f, 0.0f);
  if (!std::isfinite(cam.position.z) || cam.position == cam.target) {
    char text[160];
    std::snprintf(text, sizeof text, "a camera framing this scene (%g in radius) cannot be placed in float", radius);
    throw InputError(std::string(text) + ": the scene needs a camera of its own (glTF) or a smaller scale");
  }
  return cam;
}

}  // namespace ls
