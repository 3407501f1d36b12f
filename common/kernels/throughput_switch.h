// The per-path structure choice of the paper's section 4, as a rule of the path's own importance
// rather than its bounce depth (`render --throughput-switch T:X`): at every bounce, a path whose
// throughput luminance - what its extension ray carries at that bounce, and so its shadow ray too - is
// below T traces that bounce's rays with the structure X instead of the schedule's entry.  A path
// starts with throughput 1 (luminance exactly 1), so T <= 1 never switches a camera ray and T > 1
// switches every ray of scenes whose albedos are at most 1.
//
// Decided here, once for both back ends, from bits both have (the throughput), so the CPU and the GPU
// make the very same choice; luminance() is `precise`, so no compiler can move a path across T.
#ifndef LS_THROUGHPUT_SWITCH_H
#define LS_THROUGHPUT_SWITCH_H

#include "sampling.h"

#ifdef __cplusplus
namespace lsk {
#endif

// 1: the rays of this bounce go to the switch's structure; threshold <= 0 switches nothing.
LS_FN uint throughput_switched(IN(vec3) throughput, float threshold) {
  return luminance(throughput) < threshold ? 1u : 0u;
}

#ifdef __cplusplus
}  // namespace lsk
#endif

#endif
