#include "common/base/memory_budget.h"

#include "common/base/ray_files.h"
#include "common/kernels/layouts.h"
#include "common/model/scene.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>

namespace ls {
namespace {

// bytes in MiB rounded by `round` (std::ceil or std::floor) to whole MiB, or to tenths below 10 MiB.
std::string mib_rounded(double bytes, double (*round)(double)) {
  const double mib = bytes / double(1 << 20);
  const double tenths = round(mib * 10.0);
  if (tenths >= 100.0) return std::to_string(uint64_t(round(mib))) + " MiB";
  const uint64_t t = uint64_t(tenths);
  std::string text = std::to_string(t / 10u);
  if (t % 10u != 0u) text += '.' + std::to_string(t % 10u);
  return text + " MiB";
}

}  // namespace

std::string mib_text(double bytes) { return mib_rounded(bytes, std::ceil); }

std::string mib_budget_text(double bytes) { return mib_rounded(bytes, std::floor); }

size_t physical_memory_bytes() {
  const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGE_SIZE);
  return pages > 0 && page > 0 ? size_t(pages) * size_t(page) : size_t(8) << 30;
}

size_t memory_budget(size_t max_memory) { return max_memory ? max_memory : physical_memory_bytes() / 2; }

size_t ray_bytes(size_t count, bool made, int hits) {
  const size_t held = sizeof(lsk::Ray) + size_t(hits) * sizeof(lsk::Hit);
  const size_t making = 2 * sizeof(lsk::Ray) + 1;
  return count * (made ? std::max(held, making) : held);
}

void check_held_budget(const std::string& what, size_t bytes, size_t max_memory, const std::string& remedy) {
  const size_t budget = memory_budget(max_memory);
  if (bytes <= budget) return;
  throw InputError(what + " take up to " + mib_text(double(bytes)) + ", over the budget of " + mib_budget_text(double(budget)) +
                   ": " + remedy);
}

void check_ray_budget(const std::string& command, const std::string& rays_path, size_t count, int hits, size_t max_memory) {
  const bool made = rays_path.empty();
  if (!made) count = ray_file_count(rays_path);
  check_held_budget(command + ": " + std::to_string(count) + " rays" + (hits > 0 ? " and their hits" : ""),
                    ray_bytes(count, made, hits), max_memory,
                    made ? "use fewer rays (--count) or raise --max-memory" : "use a smaller ray file or raise --max-memory");
}

size_t estimate_render_bytes(uint32_t width, uint32_t height, int bounces) {
  // Per pixel: bounce images and the total (12 B each), path state, hit, batch ray and hit, shadow
  // query, flags and counters (~170 B), the PNG's 3 bytes and one EXR conversion copy (12 B).
  const double per_pixel = 12.0 * double(bounces + 2) + 170.0 + 3.0 + 12.0;
  return size_t(double(width) * double(height) * per_pixel);
}

void check_render_budget(uint32_t width, uint32_t height, int bounces, size_t max_memory) {
  const size_t budget = memory_budget(max_memory);
  const size_t estimate = estimate_render_bytes(width, height, bounces);
  if (estimate <= budget) return;
  throw InputError("render " + std::to_string(width) + "x" + std::to_string(height) + " with " + std::to_string(bounces) +
                   " bounces would take about " + mib_text(double(estimate)) + " of image buffers, over the budget of " +
                   mib_budget_text(double(budget)) + ": lower --size or --bounces, or raise --max-memory");
}

}  // namespace ls
