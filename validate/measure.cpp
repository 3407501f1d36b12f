#include "validate/measure.h"

#include "common/render/image_metrics.h"
#include "common/render/render_types.h"

namespace ls {

RenderOptions ImageSettings::options(const Schedule& schedule) const {
  RenderOptions o;
  o.schedule = schedule;
  o.width = width;
  o.height = height;
  o.spp = spp;
  o.bounces = bounces;
  o.seed = seed;
  o.lookup = lookup;
  return o;
}

Reference render_reference(StudyRenderer& renderer, const ImageSettings& settings) {
  const Schedule exact = parse_schedule("bvh");
  Reference r;
  r.result = renderer.render(settings.options(exact));
  r.scale = exposure_scale(r.result.total);
  r.bytes = schedule_bytes(renderer, exact, settings.bounces);
  return r;
}

Measured measure(StudyRenderer& renderer, const Schedule& schedule, const ImageSettings& settings,
                 const Reference& reference) {
  return measure(renderer, settings.options(schedule), reference);
}

Measured measure(StudyRenderer& renderer, const RenderOptions& options, const Reference& reference) {
  Measured m;
  m.schedule = options.schedule.name();
  m.result = renderer.render(options);
  m.rmse = rmse(reference.result.total, m.result.total, reference.scale);
  for (size_t k = 0; k < m.result.bounce_images.size(); ++k)
    m.contribution_rmse.push_back(rmse(reference.result.bounce_images[k], m.result.bounce_images[k], reference.scale));
  m.mrays_per_s = m.result.indirect_mrays_per_s();
  for (const StructureSpec& spec : render_structures(options)) m.bytes += renderer.structure(spec).bytes_total();
  return m;
}

nlohmann::json study_json(const std::string& scene, const std::string& device, const ImageSettings& settings,
                          double reference_mrays_per_s, size_t reference_bytes) {
  return {{"scene", scene},
          {"device", device},
          {"width", settings.width},
          {"height", settings.height},
          {"spp", settings.spp},
          {"bounces", settings.bounces},
          {"seed", settings.seed},
          {"reference", {{"structure", "bvh"}, {"mrays_per_s", reference_mrays_per_s}, {"bytes", reference_bytes}}}};
}

}  // namespace ls
