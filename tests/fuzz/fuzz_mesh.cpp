// libFuzzer harness: the OBJ/OFF/PLY/STL readers from bytes.  The first byte picks the format
// (its value mod 4: 0 OBJ, 1 OFF, 2 PLY, 3 STL; the seed files start with the digits '0'..'3'),
// the rest is the file.  Refusal (InputError) is fine; anything else is a bug.
#include "scenes/load_scene.h"

#include <cstddef>
#include <cstdint>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  static const char* const formats[4] = {".obj", ".off", ".ply", ".stl"};
  const std::string format = formats[data[0] % 4];
  const std::string bytes(reinterpret_cast<const char*>(data + 1), size - 1);
  try {
    const ls::Scene scene = ls::load_mesh_bytes(bytes, format, "fuzz" + format);
    ls::validate_scene(scene);
  } catch (const ls::InputError&) {
  }
  return 0;
}
