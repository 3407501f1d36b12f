// A glTF scene's rig: its node hierarchy (parent, rest TRS or matrix, the instance a mesh-bearing node
// places) and its animations' channels of node transforms.  Plain data, held by the Scene
// (scene.h); posing a scene with it is animation.h's.
#pragma once

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace ls {

struct RigNode {
  int parent = -1;                            // -1: a root
  bool has_matrix = false;                    // glTF `matrix` (such a node may not be animated)
  glm::dmat4 matrix{1.0};
  glm::dvec3 translation{0.0};
  glm::dquat rotation{1.0, 0.0, 0.0, 0.0};    // unit (glm order: w, x, y, z)
  glm::dvec3 scale{1.0};
  int instance = -1;                          // the instance this node places, or -1
};

enum class AnimationPath { Translation, Rotation, Scale };
enum class Interpolation { Linear, Step, CubicSpline };

struct AnimationChannel {
  uint32_t node = 0;
  AnimationPath path = AnimationPath::Translation;
  Interpolation interpolation = Interpolation::Linear;
  std::vector<float> times;          // seconds: finite, >= 0, strictly increasing, at least one
  // Per key: translation / scale in xyz, rotation as a quaternion x, y, z, w (glTF order, unit).
  // CUBICSPLINE: three per key (in-tangent, value, out-tangent), as glTF stores them.
  std::vector<glm::vec4> values;
};

struct Animation {
  std::string name;
  std::vector<AnimationChannel> channels;
  size_t weight_channels = 0;        // morph-target weight channels: not rigid, never posed
  double duration() const {          // the last key time of any channel (0 without channels)
    double d = 0.0;
    for (const AnimationChannel& c : channels)
      if (!c.times.empty() && double(c.times.back()) > d) d = double(c.times.back());
    return d;
  }
};

struct SceneRig {
  std::vector<RigNode> nodes;        // glTF node order
  std::vector<uint32_t> order;       // the nodes of the default scene, every parent before its children
  int camera_node = -1;              // the node of the scene's glTF camera, or -1 (camera not from a node)
  double camera_yfov = 0.0;
  std::vector<Animation> animations; // file order
};

}  // namespace ls
