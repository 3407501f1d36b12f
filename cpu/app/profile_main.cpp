// linespace-profile: traces a ray file with one structure on one thread, for profilers.
//
// It exists beside linespace-cpu so that a profile holds the traversal and nothing else: no command
// line, no image or render code, one thread.  (It began because linespace-cpu then loaded OpenImageIO,
// whose libhwy runs an instruction valgrind 3.19 does not know; with OpenEXR and libpng valgrind
// runs linespace-cpu too.)  Instruction counts of the traversal alone:
//   valgrind --tool=callgrind --toggle-collect='ls::trace_rays*' linespace-profile SCENE STRUCTURE RAYS
// Timing: the best of --repeat runs, in ns per ray (one thread; compare binaries, not machines).
// --lookups: the Line Space lookups alone instead (lookup_timing.h).
// --skip refused-walks|lookups: a Line Space structure's fast path with that work left out (LsSkip,
// accel.h), so that a run beside the full one shows what the work costs; the answers are then wrong.
#include "common/base/ray_files.h"
#include "common/structure/accel.h"
#include "cpu/app/lookup_timing.h"
#include "cpu/build/build_structures.h"
#include "cpu/trace/embree_tracer.h"
#include "cpu/trace/trace_rays.h"
#include "scenes/load_scene.h"

#include <tbb/global_control.h>

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <functional>
#include <memory>
#include <string>

namespace {

// To stderr with exit 2 (bad usage, after `why`), or to stdout with exit 0 (--help).
int usage(const std::string& why = "", bool help = false) {
  if (!why.empty()) std::fprintf(stderr, "linespace-profile: %s\n", why.c_str());
  std::fprintf(help ? stdout : stderr,
               "usage: linespace-profile SCENE STRUCTURE RAYS [--repeat K] [--reference | --embree] [--any-hit | "
               "--occlusion | --lookups] [--ls-min-triangles M] [--ls-behind exact|empty|reverse] [--ls-leave-reach P] "
               "[--skip refused-walks|lookups] [--ls-budget MB] "
               "[--embree-isa ISA] [--exact-width 4|8]\n");
  return help ? 0 : 2;
}

// A whole decimal count in [lo, hi], or InputError naming the flag ("3x", "-1", "abc" are refused).
uint32_t count_flag(const char* flag, const std::string& text, uint32_t lo, uint32_t hi) {
  uint32_t v = 0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (error != std::errc() || end != text.data() + text.size() || v < lo || v > hi)
    throw ls::InputError(std::string(flag) + " must be a whole number in [" + std::to_string(lo) + ", " + std::to_string(hi) +
                         "], not '" + text + "'");
  return v;
}

}  // namespace

int main(int argc, char** argv) try {
  for (int i = 1; i < argc; ++i)
    if (std::string(argv[i]) == "--help" || std::string(argv[i]) == "-h") return usage("", true);
  if (argc < 4) return usage("SCENE, STRUCTURE and RAYS are required");
  int repeat = 1;
  enum class Path { Fast, Reference, Embree } path = Path::Fast;
  enum class Query { Closest, AnyHit, Occlusion, Lookups } query = Query::Closest;
  ls::AccelOptions options;
  ls::LsLookup lookup;
  std::string embree_isa = "best";  // valgrind 3.19 has no AVX-512: under it, "best" is Embree's avx2
  for (int i = 4; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--repeat" && i + 1 < argc) repeat = int(count_flag("--repeat", argv[++i], 1, 1000));
    else if (a == "--reference" || a == "--embree") {
      const Path asked = a == "--reference" ? Path::Reference : Path::Embree;
      if (path != Path::Fast && path != asked) return usage("--reference and --embree: one path at a time");
      path = asked;
    }
    else if (a == "--any-hit") query = Query::AnyHit;
    else if (a == "--occlusion") query = Query::Occlusion;
    else if (a == "--lookups") query = Query::Lookups;
    else if (a == "--embree-isa" && i + 1 < argc) embree_isa = argv[++i];
    else if (a == "--ls-min-triangles" && i + 1 < argc)
      options.ls.min_triangles = count_flag("--ls-min-triangles", argv[++i], 0, UINT32_MAX);
    else if (a == "--ls-budget" && i + 1 < argc) {  // 2l-ls:auto's MB of Line Space
      const std::string text = argv[++i];
      double mb = 0.0;
      const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), mb);
      if (error != std::errc() || end != text.data() + text.size() || !(mb > 0.0 && mb <= 1e9))
        throw ls::InputError("--ls-budget must be MB in (0, 1e9], not '" + text + "'");
      options.plan.budget = std::max<size_t>(1, size_t(mb * 1e6));
    }
    else if (a == "--ls-behind" && i + 1 < argc) lookup.behind = ls::parse_ls_behind(argv[++i]);  // else InputError
    else if (a == "--ls-leave-reach" && i + 1 < argc) lookup.leave_reach = ls::parse_ls_leave_reach(argv[++i]);
    else if (a == "--skip" && i + 1 < argc) {
      const std::string what = argv[++i];
      if (what == "refused-walks") lookup.skip = ls::LsSkip::RefusedWalks;
      else if (what == "lookups") lookup.skip = ls::LsSkip::Lookups;
      else return usage("--skip takes refused-walks or lookups, not '" + what + "'");
    }
    else if (a == "--exact-width" && i + 1 < argc)
      options.exact_width = int(count_flag("--exact-width", argv[++i], 4, 8));  // 5 to 7: InputError when built
    else return usage("unknown flag, or a flag without its value: '" + a + "'");
  }
  if (lookup.skip != ls::LsSkip::Nothing && (path != Path::Fast || query == Query::AnyHit || query == Query::Lookups)) {
    std::fprintf(stderr, "linespace-profile: --skip times the fast path's closest-hit and occlusion queries only\n");
    return 2;
  }
  tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
  const ls::Scene scene = ls::load_scene(argv[1]);
  const std::vector<lsk::Ray> rays = ls::read_rays(argv[3]);
  if (path == Path::Embree) {
    const std::string outside = ls::embree_ray_domain_error(rays.data(), rays.size());
    if (!outside.empty()) throw ls::InputError(outside);
  }
  std::vector<lsk::Hit> hits(rays.size());
  std::function<void()> run;
  ls::Accel accel;
  std::unique_ptr<ls::EmbreeTracer> embree;
  const bool any_hit = query != Query::Closest;
  if (path == Path::Embree) {
    embree = std::make_unique<ls::EmbreeTracer>(scene, embree_isa);
    run = [&] { embree->trace(rays.data(), hits.data(), rays.size(), any_hit); };
  } else {
    accel = ls::build_planned_accel(scene, ls::parse_structure(argv[2]), options);
    if (lookup.skip != ls::LsSkip::Nothing && accel.ls_nodes.empty())
      throw ls::InputError("--skip needs a structure with Line Space nodes");
    if (query == Query::Lookups) {
      ls::time_lookups(accel, lookup, rays, repeat);
      return 0;
    }
    // By value: run() is called after this block, where a reference to traversal would dangle.
    const ls::Traversal traversal = path == Path::Fast ? ls::Traversal::Fast : ls::Traversal::Reference;
    if (query == Query::Occlusion)
      run = [&, traversal] { ls::trace_occlusion(accel, lookup, rays.data(), hits.data(), rays.size(), nullptr, traversal); };
    else
      run = [&, traversal] { ls::trace_rays(accel, lookup, rays.data(), hits.data(), rays.size(), any_hit, nullptr, traversal); };
  }
  double best = 0.0;
  for (int r = 0; r < repeat; ++r) {
    const auto start = std::chrono::steady_clock::now();
    run();
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (r == 0 || s < best) best = s;
  }
  size_t blocked = 0;
  for (const lsk::Hit& h : hits) blocked += h.triangle != lsk::LS_INVALID;
  const std::string skipped = lookup.skip == ls::LsSkip::RefusedWalks ? " without refused walks"
                              : lookup.skip == ls::LsSkip::Lookups    ? " without lookups"
                                                                      : "";
  std::printf("%s%s, %s path: %.1f ns per ray (best of %d, one thread), %zu of %zu rays hit\n",
              path == Path::Embree ? ("embree (" + embree->isa() + ")").c_str() : argv[2], skipped.c_str(),
              path == Path::Fast ? "fast" : path == Path::Reference ? "reference" : "Embree's", best / double(rays.size()) * 1e9,
              repeat, blocked, rays.size());
  return 0;
} catch (const ls::InputError& e) {
  std::fprintf(stderr, "linespace-profile: %s\n", e.what());
  return 2;
} catch (const std::exception& e) {
  std::fprintf(stderr, "linespace-profile: %s\n", e.what());
  return 1;
}
