// libFuzzer harness: the glTF loader from bytes.  Input starting with the GLB magic "glTF" is read as
// a binary .glb, anything else as .gltf JSON, so one corpus covers both containers.  A loader may
// refuse the input (InputError); anything else escaping, and every sanitizer report, is a bug.  What
// loads is also posed (rigid animation) at a few times of each of its first animations.
#include "common/model/animation.h"
#include "scenes/load_scene.h"

#include <cstddef>
#include <cstdint>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  const bool binary = bytes.compare(0, 4, "glTF") == 0;
  try {
    const ls::Scene scene = ls::load_gltf_bytes(bytes, binary ? "fuzz.glb" : "fuzz.gltf", binary);
    ls::validate_scene(scene);  // whatever loads must be a scene every structure can take
    // Posing its animations may refuse a pose (InputError), nothing else.
    ls::Scene posed = scene;
    for (size_t a = 0; a < posed.rig.animations.size() && a < 4; ++a)
      for (double t : {0.0, 0.37, 1e9}) {
        try {
          ls::pose_scene(posed, t, a);
        } catch (const ls::InputError&) {
        }
      }
  } catch (const ls::InputError&) {
  }
  return 0;
}
