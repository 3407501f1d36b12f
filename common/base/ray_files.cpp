#include "common/base/ray_files.h"

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

}  // namespace

std::vector<lsk::Ray> read_rays(const std::string& path) {
  std::vector<lsk::Ray> rays = read_records<lsk::Ray>(path, "ray");
  for (size_t i = 0; i < rays.size(); ++i) {
    const lsk::Ray& r = rays[i];
    const std::string where = "ray file '" + path + "', ray " + std::to_string(i) + ": ";
    if (!finite3(r.origin) || !finite3(r.dir)) throw InputError(where + "NaN or infinite origin or direction");
    if (r.dir == glm::vec3(0.0f)) throw InputError(where + "zero direction");
    if (std::isnan(r.tmin) || std::isnan(r.tmax) || r.tmin > r.tmax) throw InputError(where + "NaN bounds or tmin > tmax");
  }
  return rays;
}

size_t ray_file_count(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) return 0;
  const auto size = std::filesystem::file_size(path, ec);
  return ec ? 0 : size_t(size / sizeof(lsk::Ray));
}

void write_rays(const std::string& path, const std::vector<lsk::Ray>& rays) { write_records(path, rays, "ray"); }
std::vector<lsk::Hit> read_hits(const std::string& path) { return read_records<lsk::Hit>(path, "hit"); }
void write_hits(const std::string& path, const std::vector<lsk::Hit>& hits) { write_records(path, hits, "hit"); }

}  // namespace ls
