// An interrupt (Ctrl-C) stops builds, renders and output writing with ls::Interrupted, and leaves no
// output file.  The signal itself is exercised end to end in test_cli; here the pending flag is set
// directly.
#include "common/base/interrupt.h"
#include "common/render/image_output.h"
#include "common/render/render_types.h"
#include "cpu/build/build_accel.h"
#include "cpu/build/build_structures.h"
#include "cpu/render/path_tracer.h"
#include "scenes/load_scene.h"

#include <catch2/catch.hpp>

#include <csignal>
#include <filesystem>
#include <unistd.h>

using namespace ls;
namespace fs = std::filesystem;

namespace {

// Clears the flag however the test case ends.
struct PendingInterrupt {
  explicit PendingInterrupt(int signal) { request_interrupt(signal); }
  ~PendingInterrupt() { clear_interrupt(); }
};

}  // namespace

TEST_CASE("a pending interrupt stops builds and renders with Interrupted", "[interrupt]") {
  const Scene scene = builtin_scene("generated:60000:3:1");
  RenderOptions o;
  o.schedule = parse_schedule("bvh");
  o.width = o.height = 8;
  o.spp = 1;
  const auto built = build_schedule_structures(scene, o.schedule);
  PendingInterrupt pending(SIGINT);
  CHECK_THROWS_AS(build_accel(scene, parse_structure("bvh")), Interrupted);     // large BVH subtrees check
  CHECK_THROWS_AS(build_accel(scene, parse_structure("2l-ls:1:4")), Interrupted);
  CHECK_THROWS_WITH(render(scene, built, o), "interrupted by SIGINT");
}

TEST_CASE("no image file is begun once an interrupt is pending", "[interrupt]") {
  const fs::path dir = fs::temp_directory_path() / ("linespace_interrupt_" + std::to_string(getpid()));
  fs::create_directories(dir);
  Image image{4, 4, std::vector<glm::vec3>(16, glm::vec3(0.5f))};
  {
    PendingInterrupt pending(SIGTERM);
    CHECK_THROWS_WITH(write_exr((dir / "a.exr").string(), image), "interrupted by SIGTERM");
  }
  CHECK(fs::is_empty(dir));
  write_exr((dir / "a.exr").string(), image);  // and with none pending it writes
  CHECK(fs::exists(dir / "a.exr"));
  fs::remove_all(dir);
}
