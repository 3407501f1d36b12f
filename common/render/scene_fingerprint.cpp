#include "common/render/scene_fingerprint.h"


#include <cstdio>
#include <cstring>

namespace ls {
namespace {

// FNV-1a over the bytes of each value, in a fixed order.
struct Fnv {
  uint64_t h = 0xcbf29ce484222325ull;
  void bytes(const void* data, size_t n) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (size_t i = 0; i < n; ++i) h = (h ^ p[i]) * 0x100000001b3ull;
  }
  template <typename T>
  void value(const T& v) {
    bytes(&v, sizeof(T));
  }
  template <typename T>
  void array(const std::vector<T>& v) {
    value(uint64_t(v.size()));
    bytes(v.data(), v.size() * sizeof(T));
  }
};

}  // namespace

uint64_t scene_fingerprint(const Scene& scene) {
  Fnv f;
  f.value(uint64_t(scene.meshes.size()));
  for (const Mesh& m : scene.meshes) {
    f.array(m.positions);
    f.array(m.normals);
    f.array(m.triangles);
    f.array(m.materials);
  }
  f.value(uint64_t(scene.instances.size()));
  for (const Instance& i : scene.instances) {
    f.value(i.mesh);
    f.value(i.object_to_world);
  }
  f.value(uint64_t(scene.materials.size()));
  for (const Material& m : scene.materials) {
    f.value(m.albedo);
    f.value(m.emission);
  }
  f.value(scene.camera.position);
  f.value(scene.camera.target);
  f.value(scene.camera.up);
  f.value(scene.camera.yfov);
  f.value(scene.background);
  return f.h;
}

std::string fingerprint_text(uint64_t fingerprint) {
  char text[17];
  std::snprintf(text, sizeof(text), "%016llx", static_cast<unsigned long long>(fingerprint));
  return text;
}

}  // namespace ls
