// What the back ends build with: any structure, a 2l-ls:auto one planned first, and the structures
// of a render's schedule.
#pragma once

#include "common/model/scene.h"
#include "common/model/structure_name.h"
#include "common/render/throughput_switch.h"
#include "common/structure/accel.h"

#include <map>
#include <string>

namespace ls {

// Any structure as build_accel makes it, a 2l-ls:auto one planned first: its BVHs are built, the
// plan made on them (plan_line_space_budget) and kept in accel.ls_plan, then the Line Space of the
// plan is laid out and searched.  The back ends build every structure through it.  Throws InputError
// for 2l-ls:auto without --ls-budget.
Accel build_planned_accel(const Scene& scene, const StructureSpec& spec, const AccelOptions& options = {});

// Builds each distinct structure of the schedule once (and the throughput switch's, when given and on).
std::map<std::string, Accel> build_schedule_structures(const Scene& scene, const Schedule& schedule,
                                                       const AccelOptions& options = {},
                                                       const ThroughputSwitch& throughput_switch = {});

}  // namespace ls
