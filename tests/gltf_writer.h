// Writes small glTF files for tests: buffers embedded as base64 data URIs (.gltf) or packed into a
// hand-built .glb container.  Shared by the scene-loading and hostile-scene tests.
#pragma once

#include <glm/glm.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace ls_test {

inline std::string base64(const std::string& bytes) {
  static const char* table = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  size_t i = 0;
  for (; i + 2 < bytes.size(); i += 3) {
    const uint32_t v = uint32_t(uint8_t(bytes[i])) << 16 | uint32_t(uint8_t(bytes[i + 1])) << 8 | uint8_t(bytes[i + 2]);
    out += {table[v >> 18], table[(v >> 12) & 63], table[(v >> 6) & 63], table[v & 63]};
  }
  if (i + 1 == bytes.size()) {
    const uint32_t v = uint32_t(uint8_t(bytes[i])) << 16;
    out += {table[v >> 18], table[(v >> 12) & 63], '=', '='};
  } else if (i + 2 == bytes.size()) {
    const uint32_t v = uint32_t(uint8_t(bytes[i])) << 16 | uint32_t(uint8_t(bytes[i + 1])) << 8;
    out += {table[v >> 18], table[(v >> 12) & 63], table[(v >> 6) & 63], '='};
  }
  return out;
}

// Collects binary data, buffer views and accessors; json() wraps the caller's meshes/nodes/scenes.
struct Gltf {
  std::string bin;
  std::vector<std::string> views, accessors;

  int view(const void* data, size_t bytes, size_t stride = 0) {
    while (bin.size() % 4) bin += '\0';
    const size_t offset = bin.size();
    bin.append(static_cast<const char*>(data), bytes);
    views.push_back(R"({"buffer":0,"byteOffset":)" + std::to_string(offset) + R"(,"byteLength":)" +
                    std::to_string(bytes) + (stride ? R"(,"byteStride":)" + std::to_string(stride) : "") + "}");
    return int(views.size() - 1);
  }
  int accessor(const std::string& json) {
    accessors.push_back(json);
    return int(accessors.size() - 1);
  }
  int vec3(const std::vector<glm::vec3>& v) {
    const int bv = view(v.data(), v.size() * sizeof(glm::vec3));
    return accessor(R"({"bufferView":)" + std::to_string(bv) + R"(,"componentType":5126,"count":)" +
                    std::to_string(v.size()) + R"(,"type":"VEC3"})");
  }
  // Float SCALARs (animation key times, weights).
  int scalars(const std::vector<float>& v) {
    const int bv = view(v.data(), v.size() * sizeof(float));
    return accessor(R"({"bufferView":)" + std::to_string(bv) + R"(,"componentType":5126,"count":)" +
                    std::to_string(v.size()) + R"(,"type":"SCALAR"})");
  }
  int vec4(const std::vector<glm::vec4>& v) {
    const int bv = view(v.data(), v.size() * sizeof(glm::vec4));
    return accessor(R"({"bufferView":)" + std::to_string(bv) + R"(,"componentType":5126,"count":)" +
                    std::to_string(v.size()) + R"(,"type":"VEC4"})");
  }
  template <typename T>
  int indices(const std::vector<T>& idx) {
    const int type = sizeof(T) == 1 ? 5121 : sizeof(T) == 2 ? 5123 : 5125;
    const int bv = view(idx.data(), idx.size() * sizeof(T));
    return accessor(R"({"bufferView":)" + std::to_string(bv) + R"(,"componentType":)" + std::to_string(type) +
                    R"(,"count":)" + std::to_string(idx.size()) + R"(,"type":"SCALAR"})");
  }
  // rest: the remaining top-level members, e.g. R"("meshes":[...],"nodes":[...])".
  std::string json(const std::string& rest, bool embedded = true) const {
    std::string j = R"({"asset":{"version":"2.0"},"buffers":[{"byteLength":)" + std::to_string(bin.size());
    if (embedded) j += R"(,"uri":"data:application/octet-stream;base64,)" + base64(bin) + "\"";
    j += "}],\"bufferViews\":[";
    for (size_t i = 0; i < views.size(); ++i) j += (i ? "," : "") + views[i];
    j += "],\"accessors\":[";
    for (size_t i = 0; i < accessors.size(); ++i) j += (i ? "," : "") + accessors[i];
    return j + "]," + rest + "}";
  }
  // GLB container: 12-byte header, a JSON chunk and a BIN chunk, each padded to 4 bytes.
  std::string glb(const std::string& rest) const {
    std::string j = json(rest, false), b = bin;
    while (j.size() % 4) j += ' ';
    while (b.size() % 4) b += '\0';
    std::string out;
    const auto u32 = [&](uint32_t v) { out.append(reinterpret_cast<const char*>(&v), 4); };
    u32(0x46546C67);  // "glTF"
    u32(2);
    u32(uint32_t(12 + 8 + j.size() + 8 + b.size()));
    u32(uint32_t(j.size()));
    u32(0x4E4F534A);  // "JSON"
    out += j;
    u32(uint32_t(b.size()));
    u32(0x004E4942);  // "BIN"
    out += b;
    return out;
  }
};

// One animation channel with its own sampler, as the JSON of `"channels"` and `"samplers"` entries:
// channel_json(sampler index, node, path) and sampler_json(input, output, interpolation).
inline std::string channel_json(int sampler, int node, const std::string& path) {
  return R"({"sampler":)" + std::to_string(sampler) + R"(,"target":{"node":)" + std::to_string(node) + R"(,"path":")" +
         path + "\"}}";
}
inline std::string sampler_json(int input, int output, const std::string& interpolation) {
  return R"({"input":)" + std::to_string(input) + R"(,"output":)" + std::to_string(output) + R"(,"interpolation":")" +
         interpolation + "\"}";
}

inline const std::vector<glm::vec3> kTriangle = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};

// One mesh (a single indexed triangle) and the given nodes/scenes.
inline std::string one_triangle_gltf(const std::string& rest) {
  Gltf g;
  const int pos = g.vec3(kTriangle), idx = g.indices(std::vector<uint16_t>{0, 1, 2});
  return g.json(R"("meshes":[{"primitives":[{"attributes":{"POSITION":)" + std::to_string(pos) +
                R"(},"indices":)" + std::to_string(idx) + "}]}]," + rest);
}

}  // namespace ls_test
