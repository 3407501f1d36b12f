// Memory budgets: what a command will hold, estimated from its parameters alone, and refused
// (InputError naming the estimate, the budget and the parameter to change) before anything large is
// allocated.  The budget is --max-memory (Limits::max_memory), by default half of the physical memory.
// Estimates are upper bounds, so a refusal never waits for a failed allocation.  What a structure
// takes is estimated beside its builders (cpu/build/structure_budget.h, cpu/trace/fast_path_budget.h).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace ls {

// What a command may hold: --max-memory.
struct Limits {
  size_t max_memory = 0;  // bytes; 0: half of the physical memory (memory_budget)
};

size_t physical_memory_bytes();

// max_memory in bytes, or half of the physical memory when 0.
size_t memory_budget(size_t max_memory);

// Bytes as the refusals name them: whole MiB from 10 MiB on ("13 MiB"), tenths below ("0.9 MiB"), so
// that a small budget does not read "0 MiB".  What would be taken is rounded up (mib_text) and a
// budget, or what is left of one, down (mib_budget_text): a refusal's amount then always reads larger
// than the budget it exceeds, never "5 MiB ... over the budget of 5 MiB".
std::string mib_text(double bytes);
std::string mib_budget_text(double bytes);

// Bytes a command holds for `count` rays: the rays and `hits` hits a ray, and where the rays are
// made here (made), at least the generator's peak: the rays and one round of candidates with their
// flags (ray_generators.cpp).
size_t ray_bytes(size_t count, bool made, int hits);

// Throws InputError when `bytes` (what `what` names, e.g. "bench: 200000 rays and their hits")
// exceed memory_budget(max_memory); `remedy` says what to change.
void check_held_budget(const std::string& what, size_t bytes, size_t max_memory, const std::string& remedy);

// check_held_budget for a command's rays, before they are made or read: `count` rays made here where
// rays_path is empty, else the ray file's, each with `hits` hits kept ("bench: 1000 rays and their
// hits take up to 0.1 MiB, over the budget of ...: use a smaller ray file or raise --max-memory").
void check_ray_budget(const std::string& command, const std::string& rays_path, size_t count, int hits, size_t max_memory);

// Bytes of the render's image and per-pixel buffers: (bounces + 2) images of 12 B per pixel, the
// wavefront state (~170 B per pixel) and the 8-bit PNG, for width x height pixels.
size_t estimate_render_bytes(uint32_t width, uint32_t height, int bounces);

// Throws InputError when estimate_render_bytes() exceeds memory_budget(max_memory).
void check_render_budget(uint32_t width, uint32_t height, int bounces, size_t max_memory);

}  // namespace ls
