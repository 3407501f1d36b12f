// The fast path's tracer of the Line Space structures, in a translation unit of its own (wide_tracer.h).
#include "cpu/trace/wide_tracer.h"

namespace ls {

std::shared_ptr<const FastTracer> make_line_space_tracer(const Accel& accel, int exact_width) {
  if (exact_width == 8) return std::make_shared<wide_tracer::WideTracer<8, true>>(accel);
  return std::make_shared<wide_tracer::WideTracer<4, true>>(accel);
}

}  // namespace ls
