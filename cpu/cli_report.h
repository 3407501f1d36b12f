// What `build` and `trace` print, shared by linespace-cpu and linespace-gpu (DESIGN §9: the same keys
// from both programs).  The flags they share are in cli_flags.h.
#pragma once

#include "accel.h"

#include <cstdint>
#include <string>

namespace ls {

// Prints what `build` reports (DESIGN §9 keys); `device`, when given, names who built the candidates.
void print_build(const Accel& a, bool json, const std::string& device = "");

// Line Space lookup counters, one line on stderr.
void print_counters(const lsk::LsCounters& c);

}  // namespace ls
