// What `build` and `trace` print, shared by linespace-cpu and linespace-gpu (docs/design.md §9: the same keys
// from both programs).  The flags they share are in cli_flags.h.
#pragma once

#include "common/structure/accel.h"

#include <nlohmann/json.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace ls {

// Prints what `build` reports (docs/design.md §9 keys); `device`, when given, names who built the candidates.
void print_build(const Accel& a, bool json, const std::string& device = "");

// A 2l-ls:auto plan (ls_budget.h): as JSON (the `ls_plan` key of build --json), and as a table.
nlohmann::json ls_plan_json(const LsPlan& plan);
void print_ls_plan(const LsPlan& plan);

// Line Space lookup counters, one line on stderr.
void print_counters(const lsk::LsCounters& c);

// trace --against: the rays whose hit (instance and triangle, a miss included) differs from another
// hit file's of the same rays, on stderr.
void print_other_hits(const std::vector<lsk::Hit>& hits, const std::vector<lsk::Hit>& against, const std::string& against_path);

}  // namespace ls
