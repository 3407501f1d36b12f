// libFuzzer harness: structure names, structure lists and schedules (common/structure_name).
// Whatever parses must print a canonical name that parses back to the same structures.
#include "common/model/scene.h"
#include "common/model/structure_name.h"

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const ls::StructureSpec spec = ls::parse_structure(text);
    if (!(ls::parse_structure(spec.name()) == spec)) std::abort();
  } catch (const ls::InputError&) {
  }
  try {
    const ls::Schedule schedule = ls::parse_schedule(text);
    if (schedule.per_bounce.empty()) std::abort();
    if (!(ls::parse_schedule(schedule.name()).per_bounce == schedule.per_bounce)) std::abort();
  } catch (const ls::InputError&) {
  }
  try {
    (void)ls::parse_structure_list(text);
  } catch (const ls::InputError&) {
  }
  return 0;
}
