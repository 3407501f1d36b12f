#include "cpu/build/build_structures.h"

#include "cpu/build/build_accel.h"
#include "cpu/build/ls_budget.h"

#include <memory>

namespace ls {

Accel build_planned_accel(const Scene& scene, const StructureSpec& spec, const AccelOptions& options) {
  if (!spec.budgeted || !options.ls.objects.empty()) return build_accel(scene, spec, options);
  if (options.plan.budget == 0) throw InputError("structure '2l-ls:auto' needs a Line Space budget: --ls-budget MB");
  Accel accel = build_bvhs(scene, spec, options);
  accel.ls_plan = std::make_shared<const LsPlan>(plan_line_space_budget(scene, accel, options));
  AccelOptions planned = options;
  planned.ls.objects = accel.ls_plan->objects(scene.meshes.size());
  accel.build_seconds += accel.ls_plan->seconds;
  finish_accel(scene, planned, accel);
  return accel;
}

std::map<std::string, Accel> build_schedule_structures(const Scene& scene, const Schedule& schedule,
                                                       const AccelOptions& options, const ThroughputSwitch& throughput_switch) {
  std::map<std::string, Accel> built;
  for (const StructureSpec& spec : schedule.per_bounce)
    if (!built.count(spec.name())) built.emplace(spec.name(), build_planned_accel(scene, spec, options));
  if (throughput_switch.enabled() && !built.count(throughput_switch.structure.name()))
    built.emplace(throughput_switch.structure.name(), build_planned_accel(scene, throughput_switch.structure, options));
  return built;
}

}  // namespace ls
