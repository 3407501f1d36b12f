#include "common/model/animation.h"

#include "common/model/scene.h"

#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>

namespace ls {

namespace {

std::optional<glm::vec3> unit(const glm::vec3& v) {
  const float len = glm::length(v);
  if (!(len > 0.0f) || !std::isfinite(len)) return std::nullopt;
  const glm::vec3 u = v / len;
  if (!std::isfinite(u.x) || !std::isfinite(u.y) || !std::isfinite(u.z)) return std::nullopt;
  return u;
}

std::string seconds_text(double t) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.9g", t);
  return buf;
}

// Key k's value (part 1 of a CUBICSPLINE triple), in-tangent (part 0) or out-tangent (part 2).
glm::dvec4 key(const AnimationChannel& c, size_t k, int part = 1) {
  return glm::dvec4(c.values[c.interpolation == Interpolation::CubicSpline ? 3 * k + size_t(part) : k]);
}

// Shortest-path spherical linear interpolation of unit quaternions, as the glTF specification writes
// it (Appendix C); nearly equal keys are interpolated linearly (the spec's own note).
glm::dvec4 slerp(const glm::dvec4& a, const glm::dvec4& b, double u) {
  const double d = glm::dot(a, b);
  const double s = d < 0.0 ? -1.0 : 1.0;
  const double angle = std::acos(std::min(1.0, std::fabs(d)));
  const double sin_angle = std::sin(angle);
  if (sin_angle < 1e-9) return (1.0 - u) * a + u * s * b;
  return (std::sin(angle * (1.0 - u)) / sin_angle) * a + s * (std::sin(angle * u) / sin_angle) * b;
}

}  // namespace

glm::dmat4 local_matrix(const RigNode& node) {
  if (node.has_matrix) return node.matrix;
  return glm::translate(glm::dmat4(1.0), node.translation) * glm::mat4_cast(node.rotation) *
         glm::scale(glm::dmat4(1.0), node.scale);
}

bool camera_from_node(const glm::dmat4& m, double yfov, Camera& camera) {
  const glm::vec3 position(m * glm::dvec4(0.0, 0.0, 0.0, 1.0));
  const auto forward = unit(glm::vec3(m * glm::dvec4(0.0, 0.0, -1.0, 0.0)));  // glTF cameras look down -Z
  const auto up = unit(glm::vec3(m * glm::dvec4(0.0, 1.0, 0.0, 0.0)));
  if (!std::isfinite(position.x) || !std::isfinite(position.y) || !std::isfinite(position.z) || !forward || !up)
    return false;
  camera.position = position;
  // One unit ahead vanishes into the rounding of a position 1e30 away: look as far ahead as the
  // position is from the origin.
  const float reach = std::max({1.0f, std::fabs(position.x), std::fabs(position.y), std::fabs(position.z)});
  camera.target = position + *forward * reach;
  camera.up = *up;
  camera.yfov = float(yfov);
  return true;
}

glm::dvec4 sample_channel(const AnimationChannel& c, double t) {
  const size_t n = c.times.size();
  glm::dvec4 v;
  if (t <= double(c.times.front())) {
    v = key(c, 0);
  } else if (t >= double(c.times.back())) {
    v = key(c, n - 1);
  } else {
    // times[k] <= t < times[k + 1]
    const size_t k = size_t(std::upper_bound(c.times.begin(), c.times.end(), t,
                                             [](double x, float y) { return x < double(y); }) -
                            c.times.begin()) - 1;
    const double t0 = double(c.times[k]), t1 = double(c.times[k + 1]);
    const double td = t1 - t0;
    const double u = (t - t0) / td;
    switch (c.interpolation) {
      case Interpolation::Step:
        v = key(c, k);
        break;
      case Interpolation::Linear:
        v = c.path == AnimationPath::Rotation ? slerp(key(c, k), key(c, k + 1), u)
                                               : (1.0 - u) * key(c, k) + u * key(c, k + 1);
        break;
      case Interpolation::CubicSpline: {
        const double u2 = u * u, u3 = u2 * u;
        v = (2.0 * u3 - 3.0 * u2 + 1.0) * key(c, k) + td * (u3 - 2.0 * u2 + u) * key(c, k, 2) +
            (-2.0 * u3 + 3.0 * u2) * key(c, k + 1) + td * (u3 - u2) * key(c, k + 1, 0);
        break;
      }
    }
  }
  if (c.path == AnimationPath::Rotation) {
    const double len = glm::length(v);
    if (!(len > 0.0) || !std::isfinite(len))
      throw InputError("the rotation channel of node " + std::to_string(c.node) + " gives no valid quaternion at t = " +
                       seconds_text(t) + " s");
    v /= len;
  } else {
    v.w = 0.0;
  }
  return v;
}

void pose_scene(Scene& scene, double t, size_t index) {
  SceneRig& rig = scene.rig;
  if (rig.animations.empty()) return;  // nothing moves: the loaded transforms stay, bit for bit
  const std::string where = scene.name.empty() ? std::string("scene") : scene.name;
  if (index >= rig.animations.size())
    throw InputError(where + ": animation " + std::to_string(index) + " does not exist (the scene has " +
                     std::to_string(rig.animations.size()) + ")");
  const Animation& animation = rig.animations[index];
  if (animation.weight_channels > 0)
    throw InputError(where + ": animation " + std::to_string(index) + " animates morph-target weights (" +
                     std::to_string(animation.weight_channels) + (animation.weight_channels == 1 ? " channel" : " channels") +
                     "), which rigid animation cannot pose");

  std::vector<RigNode> posed = rig.nodes;
  for (const AnimationChannel& c : animation.channels) {
    RigNode& node = posed[c.node];
    const glm::dvec4 v = sample_channel(c, t);
    if (c.path == AnimationPath::Translation) node.translation = glm::dvec3(v);
    else if (c.path == AnimationPath::Scale) node.scale = glm::dvec3(v);
    else node.rotation = glm::dquat(v.w, v.x, v.y, v.z);
  }
  std::vector<glm::dmat4> world(posed.size(), glm::dmat4(1.0));
  for (uint32_t n : rig.order) {
    const glm::dmat4 local = local_matrix(posed[n]);
    world[n] = posed[n].parent >= 0 ? world[size_t(posed[n].parent)] * local : local;
    if (posed[n].instance >= 0) scene.instances[size_t(posed[n].instance)].object_to_world = glm::mat4(world[n]);
  }
  const std::string when = " (animation " + std::to_string(index) + " at t = " + seconds_text(t) + " s)";
  if (rig.camera_node >= 0 && !camera_from_node(world[size_t(rig.camera_node)], rig.camera_yfov, scene.camera))
    throw InputError(where + ": camera node " + std::to_string(rig.camera_node) + " has a degenerate transform" + when);
  try {
    validate_scene(scene);
  } catch (const InputError& e) {
    throw InputError(e.what() + when);
  }
}

}  // namespace ls
