// Scene loading: a path (.gltf .glb .obj .ply .off .stl) or `builtin:NAME`.  Throws ls::InputError
// with a one-line reason on anything it cannot load; each loader below returns only scenes that have
// passed validate_scene().
#pragma once

#include "common/model/scene.h"

#include <cstdint>
#include <string>

namespace ls {

Scene load_scene(const std::string& spec);

// glTF 2.0 (.gltf or .glb): meshes are objects, mesh-bearing nodes of the default scene are instances
// (ordered by node index), baseColorFactor is the albedo, emissiveFactor makes an area light, the
// first perspective camera is the view (else a framing camera).  The node hierarchy and every
// animation of node transforms are kept in Scene::rig for posing (common/model/animation.h); the scene
// itself is in its rest pose.
Scene load_gltf(const std::string& path);

// The same from bytes already in memory (fuzzing, tests): `name` only labels messages.  binary picks
// .glb over .gltf.  External buffer URIs are refused: there is no folder to resolve them against.
Scene load_gltf_bytes(const std::string& bytes, const std::string& name, bool binary);

// One OBJ/PLY/OFF/STL mesh, read by strict readers of our own (OpenMesh 9's readers crash or hang on
// malformed files, and drop non-manifold faces, which would shift triangle ids): a one-object scene with a framing camera and a
// default light (a white background that lights the mesh from every direction).
Scene load_mesh_file(const std::string& path);

// The same from bytes in memory; `format` is the extension (".obj", ".off", ".ply" or ".stl") and
// `name` labels messages.
Scene load_mesh_bytes(const std::string& bytes, const std::string& format, const std::string& name);

// Built-in, deterministic scenes (no files):
//   builtin:cornell                  the Cornell box seen through its open front, one light flush in the
//                                    ceiling (the default scene)
//   builtin:instances                room with 64 instances of one 51,200-triangle mesh + unique objects
//   builtin:carousel                 animated (common/model/animation.h): 24 instances of two meshes riding,
//                                    spinning, bobbing and pulsing, plus static unique objects
//   builtin:generated:T:O:S          T triangles spread over O objects, seed S (scaling studies)
Scene builtin_scene(const std::string& name);

// Applies a uniform scale and then an offset to every instance (numerical-extreme studies).
void scale_and_offset(Scene& scene, float scale, const glm::vec3& offset);

}  // namespace ls
