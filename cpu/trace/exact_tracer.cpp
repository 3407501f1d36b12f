// The fast path's tracer of the exact structures, in a translation unit of its own (wide_tracer.h),
// and make_fast_tracer, which picks it or the Line Space structures' (line_space_tracer.cpp).
#include "cpu/trace/wide_tracer.h"

#include <string>

namespace ls {

std::string fast_path_isa() {
  return std::string(wide_tracer::SimdArch::name()) + " (" + std::to_string(wide_tracer::FloatBatch::size) + " floats)";
}

std::shared_ptr<const FastTracer> make_fast_tracer(const Accel& accel, int exact_width) {
  if (exact_width != 4 && exact_width != 8)
    throw InputError("exact wide BVH width must be 4 or 8, not " + std::to_string(exact_width));
  if (accel.spec.line_space()) return make_line_space_tracer(accel, exact_width);
  if (exact_width == 8) return std::make_shared<wide_tracer::WideTracer<8, false>>(accel);
  return std::make_shared<wide_tracer::WideTracer<4, false>>(accel);
}

}  // namespace ls
