// libFuzzer harness: the glTF loader from bytes.  Input starting with the GLB magic "glTF" is read as
// a binary .glb, anything else as .gltf JSON, so one corpus covers both containers.  A loader may
// refuse the input (InputError); anything else escaping, and every sanitizer report, is a bug.
#include "load_scene.h"

#include <cstddef>
#include <cstdint>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  const bool binary = bytes.compare(0, 4, "glTF") == 0;
  try {
    const ls::Scene scene = ls::load_gltf_bytes(bytes, binary ? "fuzz.glb" : "fuzz.gltf", binary);
    ls::validate_scene(scene);  // whatever loads must be a scene every structure can take
  } catch (const ls::InputError&) {
  }
  return 0;
}
