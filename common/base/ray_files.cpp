#include "common/base/ray_files.h"

#include "common/base/float_text.h"
#include "common/base/interrupt.h"
#include "common/base/replace_file.h"
#include "common/model/scene.h"

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>

namespace ls {

static_assert(sizeof(lsk::Ray) == 32, "ray record must be 32 bytes");
static_assert(sizeof(lsk::Hit) == 20, "hit record must be 20 bytes");

namespace {

template <typename T>
std::vector<T> read_records(const std::string& path, const char* what) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) throw InputError(std::string(what) + " file '" + path + "' does not exist");
  const auto size = std::filesystem::file_size(path, ec);
  if (ec) throw InputError("cannot read " + std::string(what) + " file '" + path + "'");
  if (size % sizeof(T) != 0)
    throw InputError(std::string(what) + " file '" + path + "' is " + std::to_string(size) + " bytes, not a multiple of " +
                     std::to_string(sizeof(T)));
  std::vector<T> records(size / sizeof(T));
  std::ifstream in(path, std::ios::binary);
  if (!in.read(reinterpret_cast<char*>(records.data()), std::streamsize(size)))
    throw InputError("cannot read " + std::string(what) + " file '" + path + "'");
  return records;
}

template <typename T>
void write_records(const std::string& path, const std::vector<T>& records, const char* what) {
  throw_if_interrupted();
  const std::string temp = path + ".partial";
  {
    std::ofstream out(temp, std::ios::binary | std::ios::trunc);
    if (!out) throw InputError("cannot write " + std::string(what) + " file '" + path + "'");
    out.write(reinterpret_cast<const char*>(records.data()), std::streamsize(records.size() * sizeof(T)));
    if (!out) throw InputError("cannot write " + std::string(what) + " file '" + path + "'");
  }
  replace_file(temp, path);
}

bool finite3(const glm::vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

// What read_rays refuses in a ray, as "<where>why"; `where` names the file or the program and the ray.
void check_ray(const lsk::Ray& r, const std::string& where) {
  if (!finite3(r.origin) || !finite3(r.dir)) throw InputError(where + "NaN or infinite origin or direction");
  if (r.dir == glm::vec3(0.0f)) throw InputError(where + "zero direction");
  // The box test (common/kernels/ray_box.h) takes a subnormal component as 0, a ray parallel to the
  // slab, and can prune a box the ray reaches where t is large or the origin within a subnormal
  // distance of a face: refused rather than answered wrong.
  for (int a = 0; a < 3; ++a)
    if (r.dir[a] != 0.0f && std::fpclassify(r.dir[a]) == FP_SUBNORMAL)
      throw InputError(where + "direction component " + "xyz"[a] + " = " + float_text(r.dir[a]) +
                       " is subnormal (below 1.18e-38 in magnitude), which the box test takes as 0: set it to 0, "
                       "or scale the whole direction up (t scales down with it)");
  if (std::isnan(r.tmin) || std::isnan(r.tmax) || r.tmin > r.tmax) throw InputError(where + "NaN bounds or tmin > tmax");
}

}  // namespace

std::vector<lsk::Ray> read_rays(const std::string& path) {
  std::vector<lsk::Ray> rays = read_records<lsk::Ray>(path, "ray");
  for (size_t i = 0; i < rays.size(); ++i) check_ray(rays[i], "ray file '" + path + "', ray " + std::to_string(i) + ": ");
  return rays;
}

size_t ray_file_count(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) return 0;
  const auto size = std::filesystem::file_size(path, ec);
  return ec ? 0 : size_t(size / sizeof(lsk::Ray));
}

// A ray file is written only where read_rays will take it back (the rays of a scene near 1e-38 can
// have subnormal directions).
void write_rays(const std::string& path, const std::vector<lsk::Ray>& rays) {
  for (size_t i = 0; i < rays.size(); ++i) check_ray(rays[i], "ray file '" + path + "' not written, ray " + std::to_string(i) + ": ");
  write_records(path, rays, "ray");
}
std::vector<lsk::Hit> read_hits(const std::string& path) { return read_records<lsk::Hit>(path, "hit"); }
void write_hits(const std::string& path, const std::vector<lsk::Hit>& hits) { write_records(path, hits, "hit"); }

}  // namespace ls
