// Rigid animation: posing a scene at a time of one of its animations, with the rig (rig.h) it holds.
//
// A scene loaded from glTF keeps its nodes (parent, rest TRS or matrix, the instance a mesh-bearing
// node places, whether it holds the camera) and every animation's channels.  pose_scene(scene, t, a)
// gives every instance the world transform of its node at time t (seconds) of animation a, and moves
// the glTF camera when its node moves; ids, meshes and materials never change.  Interpolation follows
// the glTF 2.0 specification (Appendix C): before the first key the first value holds, after the last
// key the last; STEP holds a key's value until the next key; LINEAR interpolates translations and
// scales linearly and rotations by shortest-path slerp; CUBICSPLINE is the cubic Hermite spline with
// the in- and out-tangents scaled by the key interval, rotations normalised afterwards.  Values are
// read as the file's floats and interpolated and composed in double (as the loader composes the rest
// pose), then rounded once to the float transforms of the scene.
//
// Morph-target `weights` channels are not rigid: they are counted (Animation::weight_channels) and
// ignored by still renders, and an animation that has any is refused by pose_scene (InputError).
#pragma once

#include "common/model/rig.h"

#include <glm/glm.hpp>

#include <cstddef>

namespace ls {

struct Scene;
struct Camera;

// The local matrix of a node: its matrix, or T * R * S.
glm::dmat4 local_matrix(const RigNode& node);

// A glTF camera (looking down -Z, +Y up) placed by world matrix m.  False when m is degenerate
// (non-finite position, or a direction that cannot be made unit).
bool camera_from_node(const glm::dmat4& m, double yfov, Camera& camera);

// The value of a channel at time t (seconds): xyz for translation and scale, a unit quaternion
// (x, y, z, w) for rotation.
glm::dvec4 sample_channel(const AnimationChannel& channel, double t);

// Poses `scene` at time t of animation `animation` (see the top of this file).  A scene without
// animations keeps its rest pose.  Throws InputError for an animation index out of range, an
// animation with morph-target weight channels, and a pose validate_scene refuses (a singular or
// non-finite transform, vertices carried past the float range, a degenerate camera).
void pose_scene(Scene& scene, double t, size_t animation = 0);

}  // namespace ls
