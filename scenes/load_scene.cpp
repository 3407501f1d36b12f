// Scene specs -> loaders, and the one scene-wide edit (scale_and_offset).
#include "scenes/load_scene.h"


#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <system_error>

namespace ls {

namespace {

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return s;
}

}  // namespace

Scene load_scene(const std::string& spec) {
  Scene scene;
  const std::string builtin = "builtin:";
  if (spec.compare(0, builtin.size(), builtin) == 0) {
    scene = builtin_scene(spec.substr(builtin.size()));
  } else {
    namespace fs = std::filesystem;
    // The extension decides the format, so an unknown one fails before the file system is touched.
    const std::string ext = lower(fs::path(spec).extension().string());
    const bool gltf = ext == ".gltf" || ext == ".glb";
    const bool mesh = ext == ".obj" || ext == ".ply" || ext == ".off" || ext == ".stl";
    if (!gltf && !mesh)
      throw InputError(spec + ": unknown scene format '" + ext +
                       "' (expected .gltf .glb .obj .ply .off .stl or builtin:NAME)");
    std::error_code ec;
    const fs::file_status st = fs::status(spec, ec);
    if (!fs::exists(st)) throw InputError(spec + ": no such file");
    if (!fs::is_regular_file(st)) throw InputError(spec + ": not a regular file");
    scene = gltf ? load_gltf(spec) : load_mesh_file(spec);
  }
  scene.name = spec;  // every loader has already validated the scene it returns
  return scene;
}

void scale_and_offset(Scene& scene, float scale, const glm::vec3& offset) {
  if (!std::isfinite(scale) || scale == 0.0f)
    throw InputError("scale " + std::to_string(scale) + " must be finite and non-zero");
  if (!std::isfinite(offset.x) || !std::isfinite(offset.y) || !std::isfinite(offset.z))
    throw InputError("offset must be finite");
  const glm::mat4 m = glm::translate(glm::mat4(1.0f), offset) * glm::scale(glm::mat4(1.0f), glm::vec3(scale));
  for (Instance& inst : scene.instances) inst.object_to_world = m * inst.object_to_world;
  // The camera moves with the world so that it still sees the same picture.
  scene.camera.position = transform_point(m, scene.camera.position);
  scene.camera.target = transform_point(m, scene.camera.target);
  if (scale < 0.0f) scene.camera.up = -scene.camera.up;  // up is a direction: it scales, it does not move
}

}  // namespace ls
