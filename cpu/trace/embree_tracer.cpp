// Embree 3 as the correctness and performance peer (docs/design.md §7).
//
// The scene is handed to Embree as world-space triangles, one triangle geometry per instance, attached
// under the instance id (geomID = instance id, primID = triangle id), so Embree's ids are ours.  The
// world positions are computed exactly as the flat BVH computes them (ls::transform_point), so the two
// see bit-identical triangles.  RTC_SCENE_FLAG_ROBUST selects Embree's watertight intersector; both
// faces are hit (the Debian build has no back-face culling; the constructor checks).
//
// Errors reported by Embree (its error callback and rtcGetDeviceError) become ls::InputError.  The
// callback only records the message: throwing through Embree's C frames would be undefined.
#include "cpu/trace/embree_tracer.h"

#include "common/base/memory_budget.h"
#include "common/base/parallel.h"

#include <embree3/rtcore.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <mutex>
#include <string>

namespace ls {

struct EmbreeTracer::Impl {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  double build_seconds = 0.0;
  std::string isa;
  std::atomic<int64_t> bytes{0};
  int64_t max_bytes = 0;  // 0: no limit
  std::atomic<bool> over_limit{false};
  std::mutex error_mutex;
  std::string error;  // the first message the error callback reported, if any

  ~Impl() {
    if (scene) rtcReleaseScene(scene);
    if (device) rtcReleaseDevice(device);
  }

  static void on_error(void* user, RTCError code, const char* message) {
    Impl* self = static_cast<Impl*>(user);
    std::lock_guard<std::mutex> lock(self->error_mutex);
    if (self->error.empty())
      self->error = std::string(message ? message : "unknown error") + " (code " + std::to_string(int(code)) + ")";
  }

  // Counts Embree's memory; over max_bytes an allocation is refused, which cancels the current call
  // (RTC_ERROR_OUT_OF_MEMORY).  A refused allocation that has not happened yet (post == false) is
  // not counted, one that has is (Embree frees it later), as its manual page asks.
  static bool on_memory(void* user, ssize_t bytes, bool post) {
    Impl* self = static_cast<Impl*>(user);
    const int64_t now = self->bytes.fetch_add(int64_t(bytes), std::memory_order_relaxed) + int64_t(bytes);
    if (bytes <= 0 || self->max_bytes == 0 || now <= self->max_bytes) return true;
    self->over_limit.store(true, std::memory_order_relaxed);
    if (!post) self->bytes.fetch_sub(int64_t(bytes), std::memory_order_relaxed);
    return false;
  }

  // Throws when Embree reported an error since the last check.
  void check(const char* what) {
    const RTCError code = rtcGetDeviceError(device);
    std::string message;
    {
      std::lock_guard<std::mutex> lock(error_mutex);
      message.swap(error);
    }
    if (code == RTC_ERROR_NONE && message.empty()) return;
    if (over_limit.load(std::memory_order_relaxed))
      throw EmbreeOverBudget("Embree's scene would take more than the " + mib_budget_text(double(max_bytes)) +
                             " left of the memory budget (" + what + ")");
    if (message.empty()) message = "error code " + std::to_string(int(code));
    throw InputError(std::string("Embree: ") + what + ": " + message);
  }
};

const std::vector<std::string>& embree_isa_names() {
  // Embree 3's targets as the Debian package compiles them (rtcNewDevice("verbose=1") lists them).
  static const std::vector<std::string> names{"best", "sse2", "sse4.2", "avx", "avx2", "avx512"};
  return names;
}

namespace {

// The widest of Embree's targets this CPU runs, as an index into embree_isa_names() (1 = sse2).
// Embree's avx512 target is Skylake-X's set; its avx2 one also needs FMA and BMI.
size_t host_embree_isa() {
  __builtin_cpu_init();
  if (__builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512cd") && __builtin_cpu_supports("avx512dq") &&
      __builtin_cpu_supports("avx512bw") && __builtin_cpu_supports("avx512vl"))
    return 5;
  if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma") && __builtin_cpu_supports("bmi") &&
      __builtin_cpu_supports("bmi2"))
    return 4;
  if (__builtin_cpu_supports("avx")) return 3;
  if (__builtin_cpu_supports("sse4.2")) return 2;
  return 1;
}

size_t embree_isa_index(const std::string& isa) {
  const std::vector<std::string>& names = embree_isa_names();
  for (size_t i = 0; i < names.size(); ++i)
    if (names[i] == isa) return i;
  std::string list;
  for (const std::string& n : names) list += (list.empty() ? "" : ", ") + n;
  throw InputError("Embree: unknown instruction set '" + isa + "' (one of " + list + ")");
}

}  // namespace

std::string embree_effective_isa(const std::string& isa) {
  const size_t asked = embree_isa_index(isa);
  const size_t host = host_embree_isa();
  return embree_isa_names()[asked == 0 || asked > host ? host : asked];
}

EmbreeTracer::EmbreeTracer(const Scene& scene, const std::string& isa, size_t max_bytes) : impl_(std::make_unique<Impl>()) {
  Impl& im = *impl_;
  im.max_bytes = int64_t(std::min(max_bytes, size_t(std::numeric_limits<int64_t>::max())));
  im.isa = embree_effective_isa(isa);
  // The threads TBB may use (all, or --threads: thread_limit.h); the instruction set limited where
  // asked (Embree's "isa=").
  const std::string config = isa == "best" ? std::string() : "isa=" + im.isa;
  im.device = rtcNewDevice(config.empty() ? nullptr : config.c_str());
  if (!im.device)
    throw InputError("Embree: cannot create a device (error code " + std::to_string(int(rtcGetDeviceError(nullptr))) + ")");
  rtcSetDeviceErrorFunction(im.device, &Impl::on_error, &im);
  rtcSetDeviceMemoryMonitorFunction(im.device, &Impl::on_memory, &im);
  if (rtcGetDeviceProperty(im.device, RTC_DEVICE_PROPERTY_BACKFACE_CULLING_ENABLED) != 0)
    throw InputError("Embree: this Embree library culls back faces; the peer needs both faces hit");
  if (rtcGetDeviceProperty(im.device, RTC_DEVICE_PROPERTY_TRIANGLE_GEOMETRY_SUPPORTED) == 0)
    throw InputError("Embree: this Embree library has no triangle geometry");

  im.scene = rtcNewScene(im.device);
  im.check("creating the scene");
  rtcSetSceneFlags(im.scene, RTC_SCENE_FLAG_ROBUST);
  rtcSetSceneBuildQuality(im.scene, RTC_BUILD_QUALITY_HIGH);

  for (size_t id = 0; id < scene.instances.size(); ++id) {
    const Instance& inst = scene.instances[id];
    if (inst.mesh >= scene.meshes.size())
      throw InputError("Embree: instance " + std::to_string(id) + " names a mesh that does not exist");
    const Mesh& mesh = scene.meshes[inst.mesh];
    if (mesh.triangles.empty() || mesh.positions.empty()) continue;  // nothing to hit: no geometry

    RTCGeometry geom = rtcNewGeometry(im.device, RTC_GEOMETRY_TYPE_TRIANGLE);
    im.check("creating a triangle geometry");
    rtcSetGeometryBuildQuality(geom, RTC_BUILD_QUALITY_HIGH);
    // Embree pads vertex buffers it allocates itself, so 16-byte loads of the last vertex are safe.
    auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                                 3 * sizeof(float), mesh.positions.size()));
    auto* indices = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                                   3 * sizeof(uint32_t), mesh.triangles.size()));
    if (!vertices || !indices) {
      rtcReleaseGeometry(geom);
      im.check("allocating geometry buffers");
      throw InputError("Embree: cannot allocate geometry buffers");
    }
    const glm::mat4 m = inst.object_to_world;
    ls::parallel_for(tbb::blocked_range<size_t>(0, mesh.positions.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t i = r.begin(); i != r.end(); ++i) {
        const glm::vec3 p = transform_point(m, mesh.positions[i]);
        vertices[3 * i + 0] = p.x;
        vertices[3 * i + 1] = p.y;
        vertices[3 * i + 2] = p.z;
      }
    });
    for (size_t t = 0; t < mesh.triangles.size(); ++t) {
      const glm::uvec3 idx = mesh.triangles[t];
      if (idx.x >= mesh.positions.size() || idx.y >= mesh.positions.size() || idx.z >= mesh.positions.size()) {
        rtcReleaseGeometry(geom);
        throw InputError("Embree: mesh '" + mesh.name + "' has a triangle index out of range");
      }
      indices[3 * t + 0] = idx.x;
      indices[3 * t + 1] = idx.y;
      indices[3 * t + 2] = idx.z;
    }
    rtcCommitGeometry(geom);
    rtcAttachGeometryByID(im.scene, geom, unsigned(id));  // geomID = instance id
    rtcReleaseGeometry(geom);                              // the scene holds its own reference
    im.check("attaching a geometry");
  }

  const auto start = std::chrono::steady_clock::now();
  rtcCommitScene(im.scene);
  im.build_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  im.check("building the scene");
}

EmbreeTracer::~EmbreeTracer() = default;

double EmbreeTracer::build_seconds() const { return impl_->build_seconds; }

const std::string& EmbreeTracer::isa() const { return impl_->isa; }

size_t EmbreeTracer::bytes() const {
  const int64_t b = impl_->bytes.load(std::memory_order_relaxed);
  return b > 0 ? size_t(b) : 0;
}

std::string embree_ray_domain_error(const lsk::Ray* rays, size_t count) {
  constexpr float kLarge = 1.844E18f;  // Embree's FLT_LARGE
  auto within = [&](const glm::vec3& v) { return std::abs(v.x) <= kLarge && std::abs(v.y) <= kLarge && std::abs(v.z) <= kLarge; };
  for (size_t i = 0; i < count; ++i) {
    const lsk::Ray& r = rays[i];
    const bool ok = within(r.origin) && within(r.dir) && r.tmin >= 0.0f && r.tmin <= r.tmax;
    if (ok) continue;
    char text[512];
    std::snprintf(text, sizeof text,
                  "Embree 3 takes rays with 0 <= tmin <= tmax and origin and direction components within +-1.844e18; "
                  "ray %zu has origin (%g, %g, %g), direction (%g, %g, %g), tmin %g, tmax %g",
                  i, double(r.origin.x), double(r.origin.y), double(r.origin.z), double(r.dir.x), double(r.dir.y),
                  double(r.dir.z), double(r.tmin), double(r.tmax));
    return text;
  }
  return {};
}

double embree_disagreement(const lsk::Hit* embree, const lsk::Hit* ours, size_t count, bool any_hit) {
  if (count == 0) return 0.0;
  size_t differ = 0;
  for (size_t i = 0; i < count; ++i) {
    const bool e = std::isfinite(embree[i].t), o = std::isfinite(ours[i].t);
    if (e != o) ++differ;
    else if (e && !any_hit && std::abs(embree[i].t - ours[i].t) > 1e-3f * std::max(std::abs(embree[i].t), std::abs(ours[i].t)))
      ++differ;
  }
  return double(differ) / double(count);
}

void EmbreeTracer::trace(const lsk::Ray* rays, lsk::Hit* hits, size_t count, bool any_hit) const {
  const RTCScene scene = impl_->scene;
  constexpr float inf = std::numeric_limits<float>::infinity();
  ls::parallel_for(tbb::blocked_range<size_t>(0, count, 256), [&](const tbb::blocked_range<size_t>& range) {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    for (size_t i = range.begin(); i != range.end(); ++i) {
      const lsk::Ray& ray = rays[i];
      RTCRayHit rh;
      rh.ray.org_x = ray.origin.x;
      rh.ray.org_y = ray.origin.y;
      rh.ray.org_z = ray.origin.z;
      rh.ray.tnear = ray.tmin;
      rh.ray.dir_x = ray.dir.x;
      rh.ray.dir_y = ray.dir.y;
      rh.ray.dir_z = ray.dir.z;
      rh.ray.time = 0.0f;
      rh.ray.tfar = ray.tmax;
      rh.ray.mask = 0xFFFFFFFFu;
      rh.ray.id = unsigned(i);
      rh.ray.flags = 0;
      lsk::Hit& h = hits[i];
      h.instance = lsk::LS_INVALID;
      h.triangle = lsk::LS_INVALID;
      h.u = 0.0f;
      h.v = 0.0f;
      if (any_hit) {
        rtcOccluded1(scene, &context, &rh.ray);
        // Occluded: Embree sets tfar to -inf.  It names no triangle.
        h.t = rh.ray.tfar == -inf ? ray.tmin : inf;
        continue;
      }
      rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
      rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
      rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
      rtcIntersect1(scene, &context, &rh);
      if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) {
        h.t = inf;
        continue;
      }
      h.t = rh.ray.tfar;
      h.instance = rh.hit.geomID;
      h.triangle = rh.hit.primID;
      h.u = rh.hit.u;
      h.v = rh.hit.v;
    }
  });
}

}  // namespace ls
