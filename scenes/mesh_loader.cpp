// One OBJ/PLY/OFF/STL mesh -> a one-object scene, through OpenMesh.
//
// OpenMesh quietly skips a text vertex it cannot parse ("nan", "inf"), which shifts every later OBJ
// index and silently changes the geometry; OBJ and ASCII STL coordinates are therefore checked here
// first.  (OFF and ASCII PLY readers stop at such a vertex and end with no faces, which is refused.)
#include "load_scene.h"

// MeshIO.hh must come before the mesh kernel so that the readers are registered.
#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>

#include <cctype>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>

namespace ls {

namespace {

using TriMesh = OpenMesh::TriMesh_ArrayKernelT<>;

std::string lower_ext(const std::string& path) {
  std::string e = std::filesystem::path(path).extension().string();
  for (char& c : e) c = char(std::tolower(static_cast<unsigned char>(c)));
  return e;
}

// Throws when a line starting with `keyword` does not carry three finite numbers.
void check_text_vertices(const std::string& path, const std::string& keyword) {
  std::ifstream in(path, std::ios::binary);
  std::string line;
  for (size_t number = 1; std::getline(in, line); ++number) {
    const char* p = line.c_str();
    while (*p == ' ' || *p == '\t') ++p;
    if (line.compare(size_t(p - line.c_str()), keyword.size(), keyword) != 0) continue;
    p += keyword.size();
    if (*p != ' ' && *p != '\t') continue;  // "vt", "vn", "vertex_..." are other keywords
    for (int k = 0; k < 3; ++k) {
      char* end = nullptr;
      const double x = std::strtod(p, &end);  // accepts "nan" and "inf", unlike OpenMesh's streams
      if (end == p || !std::isfinite(x) || std::fabs(x) > std::numeric_limits<float>::max())
        throw InputError(path + ": line " + std::to_string(number) + ": vertex coordinate is not a finite number");
      p = end;
    }
  }
}

}  // namespace

Scene load_mesh_file(const std::string& path) {
  const std::string ext = lower_ext(path);
  if (ext == ".obj") check_text_vertices(path, "v");
  if (ext == ".stl") check_text_vertices(path, "vertex");  // matches nothing in a binary STL

  TriMesh tm;
  tm.request_vertex_normals();
  OpenMesh::IO::Options opt = OpenMesh::IO::Options::VertexNormal;
  if (!OpenMesh::IO::read_mesh(tm, path, opt)) throw InputError(path + ": cannot be read as a mesh");
  if (tm.n_faces() == 0) throw InputError(path + ": no faces");

  Mesh mesh;
  mesh.name = std::filesystem::path(path).stem().string();
  mesh.positions.reserve(tm.n_vertices());
  for (const auto v : tm.vertices()) {
    const auto& p = tm.point(v);
    mesh.positions.emplace_back(p[0], p[1], p[2]);
  }

  // The file's normals only if every one is usable (STL readers report normals and leave them zero).
  bool file_normals = opt.check(OpenMesh::IO::Options::VertexNormal);
  for (const auto v : tm.vertices()) {
    if (!file_normals) break;
    const auto& n = tm.normal(v);
    const float len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    file_normals = len > 0.0f && std::isfinite(len);
  }
  if (!file_normals) {
    tm.request_face_normals();
    tm.update_normals();
  }
  mesh.normals.reserve(tm.n_vertices());
  for (const auto v : tm.vertices()) {
    const auto& n = tm.normal(v);
    glm::vec3 u(n[0], n[1], n[2]);
    const float len = glm::length(u);
    // A vertex on no face (or on degenerate ones only) has no normal; any unit vector will do.
    u = len > 0.0f && std::isfinite(len) ? u / len : glm::vec3(0.0f, 0.0f, 1.0f);
    mesh.normals.push_back(u);
  }

  mesh.triangles.reserve(tm.n_faces());
  for (const auto f : tm.faces()) {
    glm::uvec3 t;
    int k = 0;
    for (const auto v : tm.fv_range(f)) {
      if (k < 3) t[k] = uint32_t(v.idx());
      ++k;
    }
    if (k != 3) throw InputError(path + ": face " + std::to_string(f.idx()) + " is not a triangle");
    mesh.triangles.push_back(t);
  }
  mesh.materials.assign(mesh.triangles.size(), 0);

  Scene scene;
  scene.name = path;
  scene.meshes.push_back(std::move(mesh));
  Instance inst;
  inst.name = scene.meshes[0].name;
  scene.instances.push_back(inst);
  Material grey;
  grey.albedo = glm::vec3(0.8f);
  grey.name = "default";
  scene.materials.push_back(grey);
  scene.background = glm::vec3(1.0f);  // a white sky lights a bare mesh from every direction
  validate_scene(scene);
  scene.camera = framing_camera(scene);
  return scene;
}

}  // namespace ls
