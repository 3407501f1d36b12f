// glTF 2.0 (.gltf, .glb) -> ls::Scene (docs/design.md §8, ids §9).
//
// tinygltf parses the JSON and the buffers; it does not check that accessors, buffer views and indices
// stay inside their buffers, so every range is checked here before a byte is read.  Anything the
// renderer could not trace faithfully is an InputError naming the file and the offending element.
#include "common/model/animation.h"
#include "scenes/load_scene.h"

#include <tiny_gltf.h>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <new>
#include <optional>
#include <set>
#include <utility>

namespace ls {

namespace {

constexpr int kMaxDepth = 1000;  // deeper node hierarchies are refused (and cannot blow the stack)

std::string lower_ext(const std::string& path) {
  std::string e = std::filesystem::path(path).extension().string();
  for (char& c : e) c = char(std::tolower(static_cast<unsigned char>(c)));
  return e;
}

// tinygltf's messages are multi-line; the programs print one line.
std::string first_line(const std::string& s) {
  const size_t b = s.find_first_not_of(" \t\r\n");
  if (b == std::string::npos) return "unknown error";
  std::string line = s.substr(b, s.find('\n', b) - b);
  while (!line.empty() && (line.back() == '\r' || line.back() == ' ')) line.pop_back();
  if (line.size() > 200) line = line.substr(0, 200) + "...";  // tinygltf quotes whole data URIs
  return line;
}

// Only colour factors are used: images are neither decoded nor required to exist.
bool ignore_image(tinygltf::Image*, const int, std::string*, std::string*, int, int, const unsigned char*, int,
                  void*) {
  return true;
}

bool finite(const glm::vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

// A unit vector, or nothing when v is zero, tiny or not finite.
std::optional<glm::vec3> unit(const glm::vec3& v) {
  const float len = glm::length(v);
  if (!(len > 0.0f) || !std::isfinite(len)) return std::nullopt;
  const glm::vec3 u = v / len;
  if (!finite(u)) return std::nullopt;
  return u;
}

class GltfReader {
 public:
  GltfReader(const tinygltf::Model& model, const std::string& path) : model_(model), path_(path) {}

  Scene read() {
    Scene scene;
    scene.background = glm::vec3(0.0f);  // glTF scenes are lit by their emissive materials only
    read_materials(scene);
    for (size_t m = 0; m < model_.meshes.size(); ++m) scene.meshes.push_back(read_mesh(m));
    if (default_material_used_) {
      Material grey;
      grey.name = "default";
      scene.materials.push_back(grey);
    }
    read_nodes(scene);
    read_animations(scene);
    return scene;
  }

  // Whether read() found a perspective camera; if not, the caller frames the validated scene.
  bool has_camera() const { return has_camera_; }

 private:
  [[noreturn]] void fail(const std::string& what) const { throw InputError(path_ + ": " + what); }

  // ---- accessors: the only place that touches buffer bytes ----

  // A checked accessor: element i lies at base + i * stride, and every element is inside its buffer.
  struct View {
    const unsigned char* base = nullptr;
    size_t stride = 0;
    size_t count = 0;
    int component = 0;
  };

  View view(int index, const std::string& what, int type, std::initializer_list<int> components) const {
    const std::string name = what + " accessor " + std::to_string(index);
    if (index < 0 || size_t(index) >= model_.accessors.size()) fail(name + " does not exist");
    const tinygltf::Accessor& acc = model_.accessors[size_t(index)];
    if (acc.sparse.isSparse) fail(name + " is sparse, which is not supported");
    if (acc.type != type) fail(name + " has the wrong type");
    bool known = false;
    for (int c : components) known = known || acc.componentType == c;
    if (!known) fail(name + " has an unsupported component type " + std::to_string(acc.componentType));
    View v;
    v.component = acc.componentType;
    v.count = acc.count;
    if (acc.count == 0) return v;
    if (acc.bufferView < 0 || size_t(acc.bufferView) >= model_.bufferViews.size())
      fail(name + " has no valid bufferView");
    const tinygltf::BufferView& bv = model_.bufferViews[size_t(acc.bufferView)];
    const std::string bvname = "bufferView " + std::to_string(acc.bufferView);
    if (bv.buffer < 0 || size_t(bv.buffer) >= model_.buffers.size()) fail(bvname + " names a missing buffer");
    const size_t buffer_size = model_.buffers[size_t(bv.buffer)].data.size();
    if (bv.byteOffset > buffer_size || bv.byteLength > buffer_size - bv.byteOffset)
      fail(bvname + " runs past the end of buffer " + std::to_string(bv.buffer));
    const size_t elem = size_t(tinygltf::GetComponentSizeInBytes(uint32_t(acc.componentType))) *
                        size_t(tinygltf::GetNumComponentsInType(uint32_t(acc.type)));
    const size_t stride = bv.byteStride ? bv.byteStride : elem;
    if (stride < elem) fail(bvname + " has a byteStride smaller than one element of " + name);
    // The last element must end inside the view: byteOffset + (count-1)*stride + elem <= byteLength,
    // written so that nothing overflows.
    if (acc.byteOffset > bv.byteLength || elem > bv.byteLength - acc.byteOffset ||
        acc.count - 1 > (bv.byteLength - acc.byteOffset - elem) / stride)
      fail(name + " runs past the end of " + bvname);
    v.base = model_.buffers[size_t(bv.buffer)].data.data() + bv.byteOffset + acc.byteOffset;
    v.stride = stride;
    return v;
  }

  std::vector<glm::vec3> read_vec3(int index, const std::string& what) const {
    const View v = view(index, what, TINYGLTF_TYPE_VEC3, {TINYGLTF_COMPONENT_TYPE_FLOAT});
    std::vector<glm::vec3> out(v.count);
    for (size_t i = 0; i < v.count; ++i) std::memcpy(&out[i], v.base + i * v.stride, sizeof(glm::vec3));
    return out;
  }

  std::vector<uint32_t> read_indices(int index) const {
    const View v = view(index, "index", TINYGLTF_TYPE_SCALAR,
                        {TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT,
                         TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT});
    std::vector<uint32_t> out(v.count);
    for (size_t i = 0; i < v.count; ++i) {
      const unsigned char* p = v.base + i * v.stride;
      if (v.component == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE) {
        out[i] = *p;
      } else if (v.component == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT) {
        uint16_t s;
        std::memcpy(&s, p, 2);
        out[i] = s;
      } else {
        std::memcpy(&out[i], p, 4);
      }
    }
    return out;
  }

  // ---- materials ----

  void read_materials(Scene& scene) const {
    for (const tinygltf::Material& gm : model_.materials) {
      Material m;
      m.name = gm.name;
      const std::vector<double>& base = gm.pbrMetallicRoughness.baseColorFactor;
      if (base.size() >= 3) m.albedo = glm::vec3(float(base[0]), float(base[1]), float(base[2]));
      if (gm.emissiveFactor.size() >= 3)
        m.emission = glm::vec3(float(gm.emissiveFactor[0]), float(gm.emissiveFactor[1]), float(gm.emissiveFactor[2]));
      const auto ext = gm.extensions.find("KHR_materials_emissive_strength");
      if (ext != gm.extensions.end() && ext->second.IsObject() && ext->second.Has("emissiveStrength") &&
          ext->second.Get("emissiveStrength").IsNumber())
        m.emission *= float(ext->second.Get("emissiveStrength").GetNumberAsDouble());
      scene.materials.push_back(m);
    }
  }

  // ---- meshes ----

  // Area-weighted vertex normals (the cross product's length is twice the area); unused vertices
  // get +z so that every normal is a unit vector.
  static std::vector<glm::vec3> area_weighted_normals(const std::vector<glm::vec3>& pos,
                                                      const std::vector<glm::uvec3>& tris) {
    std::vector<glm::vec3> acc(pos.size(), glm::vec3(0.0f));
    for (const glm::uvec3& t : tris) {
      const glm::vec3 n = glm::cross(pos[t.y] - pos[t.x], pos[t.z] - pos[t.x]);
      acc[t.x] += n;
      acc[t.y] += n;
      acc[t.z] += n;
    }
    for (glm::vec3& n : acc) n = unit(n).value_or(glm::vec3(0.0f, 0.0f, 1.0f));
    return acc;
  }

  Mesh read_mesh(size_t mi) {
    const tinygltf::Mesh& gm = model_.meshes[mi];
    Mesh mesh;
    mesh.name = gm.name;
    for (size_t pi = 0; pi < gm.primitives.size(); ++pi) {
      const tinygltf::Primitive& prim = gm.primitives[pi];
      const std::string where = "mesh " + std::to_string(mi) + " primitive " + std::to_string(pi);
      // tinygltf writes TRIANGLES for an absent mode (-1 only in a default-constructed primitive).
      const int mode = prim.mode == -1 ? TINYGLTF_MODE_TRIANGLES : prim.mode;
      if (mode == TINYGLTF_MODE_POINTS || mode == TINYGLTF_MODE_LINE || mode == TINYGLTF_MODE_LINE_LOOP ||
          mode == TINYGLTF_MODE_LINE_STRIP)
        fail(where + ": non-triangle primitive (points or lines)");
      if (mode != TINYGLTF_MODE_TRIANGLES && mode != TINYGLTF_MODE_TRIANGLE_STRIP && mode != TINYGLTF_MODE_TRIANGLE_FAN)
        fail(where + ": unknown primitive mode " + std::to_string(mode));

      const auto pos_attr = prim.attributes.find("POSITION");
      if (pos_attr == prim.attributes.end()) fail(where + ": no POSITION attribute");
      const std::vector<glm::vec3> pos = read_vec3(pos_attr->second, where + " POSITION");

      std::vector<uint32_t> idx;
      if (prim.indices >= 0) {
        idx = read_indices(prim.indices);
        for (uint32_t i : idx)
          if (i >= pos.size())
            fail(where + ": index " + std::to_string(i) + " out of range (" + std::to_string(pos.size()) + " vertices)");
      } else {
        if (pos.size() > UINT32_MAX) fail(where + ": too many vertices");
        idx.resize(pos.size());
        for (size_t i = 0; i < idx.size(); ++i) idx[i] = uint32_t(i);
      }

      // Triangles in primitive order; strips and fans unrolled as the glTF specification orders them.
      std::vector<glm::uvec3> tris;
      if (mode == TINYGLTF_MODE_TRIANGLES) {
        if (idx.size() % 3 != 0) fail(where + ": " + std::to_string(idx.size()) + " indices, not a multiple of 3");
        for (size_t i = 0; i + 2 < idx.size(); i += 3) tris.emplace_back(idx[i], idx[i + 1], idx[i + 2]);
      } else if (mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
        for (size_t i = 0; i + 2 < idx.size(); ++i)
          tris.emplace_back(idx[i], idx[i + 1 + i % 2], idx[i + 2 - i % 2]);
      } else {
        for (size_t i = 1; i + 1 < idx.size(); ++i) tris.emplace_back(idx[i], idx[i + 1], idx[0]);
      }

      // Normals: the file's, made unit; computed where absent or unusable.
      std::vector<glm::vec3> nrm;
      const auto nrm_attr = prim.attributes.find("NORMAL");
      if (nrm_attr != prim.attributes.end()) {
        nrm = read_vec3(nrm_attr->second, where + " NORMAL");
        if (nrm.size() != pos.size()) fail(where + ": NORMAL and POSITION differ in count");
        std::vector<glm::vec3> computed;
        for (size_t i = 0; i < nrm.size(); ++i) {
          if (const auto u = unit(nrm[i])) {
            nrm[i] = *u;
          } else {
            if (computed.empty()) computed = area_weighted_normals(pos, tris);
            nrm[i] = computed[i];
          }
        }
      } else {
        nrm = area_weighted_normals(pos, tris);
      }

      uint32_t material;
      if (prim.material < 0) {
        material = uint32_t(model_.materials.size());  // the grey default, appended after the file's
        default_material_used_ = true;
      } else if (size_t(prim.material) >= model_.materials.size()) {
        fail(where + ": material " + std::to_string(prim.material) + " does not exist");
      } else {
        material = uint32_t(prim.material);
      }

      const size_t offset = mesh.positions.size();
      if (offset + pos.size() > UINT32_MAX) fail("mesh " + std::to_string(mi) + ": more than 2^32 vertices");
      mesh.positions.insert(mesh.positions.end(), pos.begin(), pos.end());
      mesh.normals.insert(mesh.normals.end(), nrm.begin(), nrm.end());
      for (const glm::uvec3& t : tris) mesh.triangles.push_back(t + glm::uvec3(uint32_t(offset)));
      mesh.materials.insert(mesh.materials.end(), tris.size(), material);
    }
    return mesh;
  }

  // ---- animations (common/model/animation.h) ----

  // Key times: float, finite, >= 0, strictly increasing (glTF 2.0, animation.sampler.input).
  std::vector<float> read_times(int index, const std::string& where) const {
    const View v = view(index, where + " input", TINYGLTF_TYPE_SCALAR, {TINYGLTF_COMPONENT_TYPE_FLOAT});
    if (v.count == 0) fail(where + ": no keyframes");
    std::vector<float> times(v.count);
    for (size_t i = 0; i < v.count; ++i) {
      std::memcpy(&times[i], v.base + i * v.stride, sizeof(float));
      if (!std::isfinite(times[i])) fail(where + ": key time " + std::to_string(i) + " is NaN or infinite");
      if (i == 0 && times[i] < 0.0f) fail(where + ": the first key time is negative");
      if (i > 0 && !(times[i] > times[i - 1]))
        fail(where + ": key times are not strictly increasing (key " + std::to_string(i) + ")");
    }
    return times;
  }

  // Output values: translation and scale as float VEC3; rotation as float VEC4 or a normalized
  // (signed or unsigned) byte or short VEC4, decoded as the glTF specification says.
  std::vector<glm::vec4> read_values(int index, AnimationPath path, const std::string& where) const {
    const std::string what = where + " output";
    std::vector<glm::vec4> out;
    if (path != AnimationPath::Rotation) {
      const View v = view(index, what, TINYGLTF_TYPE_VEC3, {TINYGLTF_COMPONENT_TYPE_FLOAT});
      out.resize(v.count);
      for (size_t i = 0; i < v.count; ++i) {
        glm::vec3 x;
        std::memcpy(&x, v.base + i * v.stride, sizeof(x));
        out[i] = glm::vec4(x, 0.0f);
      }
    } else {
      const View v = view(index, what, TINYGLTF_TYPE_VEC4,
                          {TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_COMPONENT_TYPE_BYTE, TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE,
                           TINYGLTF_COMPONENT_TYPE_SHORT, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT});
      if (v.component != TINYGLTF_COMPONENT_TYPE_FLOAT && !model_.accessors[size_t(index)].normalized)
        fail(what + " accessor " + std::to_string(index) + " holds integer rotations that are not normalized");
      out.resize(v.count);
      for (size_t i = 0; i < v.count; ++i)
        for (int c = 0; c < 4; ++c) {
          const unsigned char* p = v.base + i * v.stride;
          float& x = out[i][c];
          if (v.component == TINYGLTF_COMPONENT_TYPE_FLOAT) {
            std::memcpy(&x, p + 4 * c, 4);
          } else if (v.component == TINYGLTF_COMPONENT_TYPE_BYTE) {
            x = std::max(float(int8_t(p[c])) / 127.0f, -1.0f);
          } else if (v.component == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE) {
            x = float(p[c]) / 255.0f;
          } else if (v.component == TINYGLTF_COMPONENT_TYPE_SHORT) {
            int16_t h;
            std::memcpy(&h, p + 2 * c, 2);
            x = std::max(float(h) / 32767.0f, -1.0f);
          } else {
            uint16_t h;
            std::memcpy(&h, p + 2 * c, 2);
            x = float(h) / 65535.0f;
          }
        }
    }
    for (size_t i = 0; i < out.size(); ++i)
      for (int c = 0; c < 4; ++c)
        if (!std::isfinite(out[i][c])) fail(what + " value " + std::to_string(i) + " is NaN or infinite");
    return out;
  }

  void read_animations(Scene& scene) const {
    for (size_t ai = 0; ai < model_.animations.size(); ++ai) {
      const tinygltf::Animation& ga = model_.animations[ai];
      const std::string where = "animation " + std::to_string(ai);
      Animation animation;
      animation.name = ga.name;
      std::set<std::pair<int, AnimationPath>> targeted;
      for (size_t ci = 0; ci < ga.channels.size(); ++ci) {
        const tinygltf::AnimationChannel& ch = ga.channels[ci];
        const std::string cw = where + " channel " + std::to_string(ci);
        if (ch.sampler < 0 || size_t(ch.sampler) >= ga.samplers.size())
          fail(cw + ": sampler " + std::to_string(ch.sampler) + " does not exist");
        const tinygltf::AnimationSampler& sampler = ga.samplers[size_t(ch.sampler)];
        AnimationChannel c;
        if (sampler.interpolation == "LINEAR") c.interpolation = Interpolation::Linear;
        else if (sampler.interpolation == "STEP") c.interpolation = Interpolation::Step;
        else if (sampler.interpolation == "CUBICSPLINE") c.interpolation = Interpolation::CubicSpline;
        else fail(cw + ": unknown interpolation '" + sampler.interpolation.substr(0, 40) + "'");
        const bool weights = ch.target_path == "weights";
        if (ch.target_path == "translation") c.path = AnimationPath::Translation;
        else if (ch.target_path == "rotation") c.path = AnimationPath::Rotation;
        else if (ch.target_path == "scale") c.path = AnimationPath::Scale;
        else if (!weights) fail(cw + ": unknown target path '" + ch.target_path.substr(0, 40) + "'");
        if (ch.target_node < 0) continue;  // no node: the channel targets something of an extension
        if (size_t(ch.target_node) >= model_.nodes.size())
          fail(cw + ": node " + std::to_string(ch.target_node) + " does not exist");
        c.node = uint32_t(ch.target_node);
        c.times = read_times(sampler.input, cw);
        const size_t per_key = c.interpolation == Interpolation::CubicSpline ? 3 : 1;
        const size_t expected = c.times.size() * per_key;
        if (weights) {  // not rigid: checked for size, counted, never posed
          const View v = view(sampler.output, cw + " output", TINYGLTF_TYPE_SCALAR,
                              {TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_COMPONENT_TYPE_BYTE, TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE,
                               TINYGLTF_COMPONENT_TYPE_SHORT, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT});
          if (v.count == 0 || v.count % expected != 0)
            fail(cw + ": " + std::to_string(v.count) + " weights do not fit " + std::to_string(c.times.size()) + " keys");
          ++animation.weight_channels;
          continue;
        }
        if (!targeted.insert({ch.target_node, c.path}).second)
          fail(cw + ": node " + std::to_string(ch.target_node) + " already has a " + ch.target_path + " channel");
        if (!model_.nodes[c.node].matrix.empty())
          fail(cw + ": node " + std::to_string(c.node) + " has a matrix, which glTF does not allow on animated nodes");
        c.values = read_values(sampler.output, c.path, cw);
        if (c.values.size() != expected)
          fail(cw + ": " + std::to_string(c.values.size()) + " output values for " + std::to_string(c.times.size()) +
               " keys (expected " + std::to_string(expected) + ")");
        if (c.path == AnimationPath::Rotation)
          for (size_t k = 0; k < c.times.size(); ++k) {  // the values (tangents may be anything finite)
            glm::vec4& q = c.values[k * per_key + per_key / 2];
            const double len = glm::length(glm::dvec4(q));
            if (!(len > 0.0)) fail(cw + ": key " + std::to_string(k) + " is a quaternion of zero length");
            q = glm::vec4(glm::dvec4(q) / len);
          }
        if (state_[c.node] != kDone) continue;  // outside the default scene: moves nothing
        animation.channels.push_back(std::move(c));
      }
      scene.rig.animations.push_back(std::move(animation));
    }
  }

  // ---- nodes ----

  // A node's rest transform as posing needs it (animation.h); local_matrix() composes it.
  RigNode rig_node(size_t n) const {
    const tinygltf::Node& node = model_.nodes[n];
    const std::string where = "node " + std::to_string(n);
    RigNode rig;
    if (!node.matrix.empty()) {
      if (node.matrix.size() != 16) fail(where + ": matrix needs 16 numbers");
      glm::dmat4 m;
      for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r) m[c][r] = node.matrix[size_t(c * 4 + r)];  // column-major, as glTF
      // Instances are affine: a projective bottom row would be silently ignored by every transform.
      if (m[0][3] != 0.0 || m[1][3] != 0.0 || m[2][3] != 0.0 || m[3][3] != 1.0)
        fail(where + ": matrix is not affine (bottom row must be 0 0 0 1)");
      rig.has_matrix = true;
      rig.matrix = m;
      return rig;
    }
    if (!node.translation.empty()) {
      if (node.translation.size() != 3) fail(where + ": translation needs 3 numbers");
      rig.translation = glm::dvec3(node.translation[0], node.translation[1], node.translation[2]);
    }
    if (!node.rotation.empty()) {
      if (node.rotation.size() != 4) fail(where + ": rotation needs 4 numbers");
      // glTF stores x, y, z, w; glm's constructor takes w first.
      glm::dquat q(node.rotation[3], node.rotation[0], node.rotation[1], node.rotation[2]);
      const double len = glm::length(q);
      if (!(len > 0.0) || !std::isfinite(len)) fail(where + ": rotation is not a valid quaternion");
      rig.rotation = q / len;
    }
    if (!node.scale.empty()) {
      if (node.scale.size() != 3) fail(where + ": scale needs 3 numbers");
      rig.scale = glm::dvec3(node.scale[0], node.scale[1], node.scale[2]);
    }
    return rig;
  }

  // Depth-first from the roots; a node met again is a cycle (on the current path) or a second parent.
  void visit(int n, const glm::dmat4& parent, int parent_node, int depth) {
    if (n < 0 || size_t(n) >= model_.nodes.size()) fail("node " + std::to_string(n) + " does not exist");
    if (depth > kMaxDepth) fail("node hierarchy deeper than " + std::to_string(kMaxDepth));
    if (state_[size_t(n)] == kOnPath) fail("node " + std::to_string(n) + " is its own ancestor (cycle)");
    if (state_[size_t(n)] == kDone)
      fail("node " + std::to_string(n) + " is reached twice (glTF nodes must form a tree)");
    state_[size_t(n)] = kOnPath;
    RigNode& node = rig_[size_t(n)];
    node = rig_node(size_t(n));
    node.parent = parent_node;
    order_.push_back(uint32_t(n));
    world_[size_t(n)] = parent * local_matrix(node);
    for (int child : model_.nodes[size_t(n)].children) visit(child, world_[size_t(n)], n, depth + 1);
    state_[size_t(n)] = kDone;
  }

  std::vector<int> roots() const {
    if (!model_.scenes.empty()) {
      const int s = model_.defaultScene >= 0 ? model_.defaultScene : 0;
      if (size_t(s) >= model_.scenes.size()) fail("default scene " + std::to_string(s) + " does not exist");
      return model_.scenes[size_t(s)].nodes;
    }
    // No scenes: every node that is nobody's child is a root.
    std::vector<bool> child(model_.nodes.size(), false);
    for (const tinygltf::Node& node : model_.nodes)
      for (int c : node.children)
        if (c >= 0 && size_t(c) < child.size()) child[size_t(c)] = true;
    std::vector<int> r;
    for (size_t n = 0; n < model_.nodes.size(); ++n)
      if (!child[n]) r.push_back(int(n));
    return r;
  }

  void read_nodes(Scene& scene) {
    state_.assign(model_.nodes.size(), kUnseen);
    world_.assign(model_.nodes.size(), glm::dmat4(1.0));
    rig_.assign(model_.nodes.size(), RigNode{});
    for (int root : roots()) visit(root, glm::dmat4(1.0), -1, 0);

    // Instance id = rank by node index of the reached mesh-bearing nodes (docs/design.md §9).
    std::optional<size_t> camera_node;
    for (size_t n = 0; n < model_.nodes.size(); ++n) {
      if (state_[n] != kDone) continue;
      const tinygltf::Node& node = model_.nodes[n];
      if (node.mesh >= 0) {
        if (size_t(node.mesh) >= model_.meshes.size())
          fail("node " + std::to_string(n) + ": mesh " + std::to_string(node.mesh) + " does not exist");
        rig_[n].instance = int(scene.instances.size());
        Instance inst;
        inst.mesh = uint32_t(node.mesh);
        inst.object_to_world = glm::mat4(world_[n]);
        inst.name = node.name;
        scene.instances.push_back(inst);
      }
      if (node.camera >= 0) {
        if (size_t(node.camera) >= model_.cameras.size())
          fail("node " + std::to_string(n) + ": camera " + std::to_string(node.camera) + " does not exist");
        if (!camera_node && model_.cameras[size_t(node.camera)].type == "perspective") camera_node = n;
      }
    }

    if (camera_node) {
      const double yfov = model_.cameras[size_t(model_.nodes[*camera_node].camera)].perspective.yfov;
      if (!(yfov > 0.0 && yfov < 3.14159)) fail("camera yfov " + std::to_string(yfov) + " is not in (0, pi)");
      if (!camera_from_node(world_[*camera_node], yfov, scene.camera))
        fail("camera node " + std::to_string(*camera_node) + " has a degenerate transform");
      has_camera_ = true;
      scene.rig.camera_node = int(*camera_node);
      scene.rig.camera_yfov = yfov;
    }
    scene.rig.nodes = std::move(rig_);
    scene.rig.order = std::move(order_);
  }

  enum : uint8_t { kUnseen, kOnPath, kDone };
  const tinygltf::Model& model_;
  const std::string& path_;
  bool default_material_used_ = false;
  bool has_camera_ = false;
  std::vector<uint8_t> state_;
  std::vector<glm::dmat4> world_;
  std::vector<RigNode> rig_;
  std::vector<uint32_t> order_;  // visit order: parents before children
};

}  // namespace

namespace {

// Loads through `load` (which fills model, err and warn), then reads and validates the model.
template <typename Load>
Scene load_gltf_with(const std::string& name, Load&& load) {
  tinygltf::TinyGLTF loader;
  loader.SetImageLoader(ignore_image, nullptr);
  tinygltf::Model model;
  std::string err, warn;
  bool ok = false;
  try {
    ok = load(loader, model, err, warn);
  } catch (const std::bad_alloc&) {
    throw;
  } catch (const std::exception& e) {  // tinygltf 2.7 indexes with .at() on some malformed files
    throw InputError(name + ": malformed glTF (" + e.what() + ")");
  }
  // Warnings alone (an unreadable texture, say) do not matter: only colour factors are used.
  if (!ok) throw InputError(name + ": " + first_line(err.empty() ? warn : err));

  GltfReader reader(model, name);
  Scene scene = reader.read();
  scene.name = name;
  validate_scene(scene);
  if (!reader.has_camera()) scene.camera = framing_camera(scene);
  return scene;
}

// File callbacks for bytes in memory: no file may be opened (a URI would name one relative to a
// folder the bytes do not have).
bool no_file_exists(const std::string&, void*) { return false; }
std::string no_expand(const std::string& path, void*) { return path; }
bool no_read(std::vector<unsigned char>*, std::string* err, const std::string& path, void*) {
  if (err) *err += "external file '" + path + "' cannot be read from bytes in memory\n";
  return false;
}
bool no_write(std::string*, const std::string&, const std::vector<unsigned char>&, void*) { return false; }

// Debian's tinygltf reads a GLB's BIN chunk for as many bytes as the chunk says, past the end of the
// file when it lies (heap overflow, found by fuzzing).  So every chunk's header and data must lie
// within the file, and within the length its header gives, before tinygltf sees it.  Empty: sound.
std::string glb_layout_error(const unsigned char* data, size_t size) {
  const auto u32 = [&](size_t at) {
    uint32_t v;
    std::memcpy(&v, data + at, 4);  // little-endian, as x86-64 and the GLB format are
    return uint64_t(v);
  };
  if (size < 12 || std::memcmp(data, "glTF", 4) != 0) return "not a GLB file (no 'glTF' header)";
  const uint64_t length = u32(8);
  if (length > size) return "the GLB header's length " + std::to_string(length) + " exceeds the file's " + std::to_string(size) + " bytes";
  for (uint64_t at = 12; at < length;) {
    if (at + 8 > length) return "a GLB chunk header runs past the end of the data";
    const uint64_t chunk = u32(size_t(at));
    if (at + 8 + chunk > length)
      return "a GLB chunk of " + std::to_string(chunk) + " bytes at byte " + std::to_string(at) + " runs past the end of the data";
    at += 8 + chunk;
  }
  return "";
}

// A GLB in memory, its layout checked first; external files are looked up in base_dir.
bool load_glb(tinygltf::TinyGLTF& loader, tinygltf::Model& model, std::string& err, std::string& warn,
              const unsigned char* data, size_t size, const std::string& base_dir) {
  if (size > UINT32_MAX) {
    err = "larger than 4 GiB";
    return false;
  }
  err = glb_layout_error(data, size);
  return err.empty() && loader.LoadBinaryFromMemory(&model, &err, &warn, data, unsigned(size), base_dir);
}

}  // namespace

Scene load_gltf(const std::string& path) {
  const bool binary = lower_ext(path) == ".glb";
  return load_gltf_with(path, [&](tinygltf::TinyGLTF& loader, tinygltf::Model& model, std::string& err, std::string& warn) {
    if (!binary) return loader.LoadASCIIFromFile(&model, &err, &warn, path);
    std::ifstream in(path, std::ios::binary);
    std::vector<unsigned char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (!in.good() && !in.eof()) {
      err = "cannot read the file";
      return false;
    }
    // What LoadBinaryFromFile does, on bytes checked first: external files relative to the file's folder.
    return load_glb(loader, model, err, warn, bytes.data(), bytes.size(), std::filesystem::path(path).parent_path().string());
  });
}

Scene load_gltf_bytes(const std::string& bytes, const std::string& name, bool binary) {
  return load_gltf_with(name, [&](tinygltf::TinyGLTF& loader, tinygltf::Model& model, std::string& err, std::string& warn) {
    tinygltf::FsCallbacks fs{&no_file_exists, &no_expand, &no_read, &no_write, nullptr};
    loader.SetFsCallbacks(fs);
    if (bytes.size() > UINT32_MAX) {
      err = "larger than 4 GiB";
      return false;
    }
    if (!binary) return loader.LoadASCIIFromString(&model, &err, &warn, bytes.data(), unsigned(bytes.size()), "");
    return load_glb(loader, model, err, warn, reinterpret_cast<const unsigned char*>(bytes.data()), bytes.size(), "");
  });
}

}  // namespace ls
