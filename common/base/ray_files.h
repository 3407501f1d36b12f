// The ray and hit files of docs/design.md §9, little-endian:
//   ray: 8 x float32  ox oy oz tmin dx dy dz tmax                (32 bytes)
//   hit: float32 t, uint32 instance, uint32 triangle, float32 u, float32 v   (20 bytes)
// Both are the in-memory lsk::Ray / lsk::Hit records (this code runs on little-endian machines).
#pragma once

#include "common/kernels/layouts.h"

#include <cstddef>
#include <string>
#include <vector>

namespace ls {

// Throws InputError: missing file, size not a multiple of 32, NaN/Inf origins or directions, a zero
// direction, a subnormal direction component (the box test would take it as 0), NaN bounds or
// tmin > tmax (each names the first bad record).
std::vector<lsk::Ray> read_rays(const std::string& path);
// The rays a ray file holds, from its size (0 where it is no regular file: read_rays says why), so that
// a memory budget can be checked before it is read.
size_t ray_file_count(const std::string& path);
// Refuses, before writing, the rays read_rays would refuse.
void write_rays(const std::string& path, const std::vector<lsk::Ray>& rays);
std::vector<lsk::Hit> read_hits(const std::string& path);
void write_hits(const std::string& path, const std::vector<lsk::Hit>& hits);

}  // namespace ls
