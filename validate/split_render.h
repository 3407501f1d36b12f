// One sample set of a render as two disjoint halves, so that their sampling noise is independent
// (validate/bias_estimate.h).  Samples 0 .. n-1 are rendered as ranges; of each range, half A takes
// the first ceil(n/2) sample indices and half B the rest (RenderOptions::first_sample).  Combined,
// the halves are the render of samples 0 .. n-1 with the same random numbers as a plain render; only
// the float rounding of the pixel averages differs (a plain render sums all its samples in one order).
#pragma once

#include "common/render/render_types.h"
#include "validate/study_renderer.h"

#include <array>

namespace ls {

struct SplitRender {
  std::array<RenderResult, 2> half;  // each half's average over its own samples
  std::array<int, 2> spp{0, 0};      // samples in each half (B may hold none: 1 sample in all)
  RenderResult combined;             // the spp-weighted average of the halves; statistics summed
  int total_spp() const { return spp[0] + spp[1]; }
};

// Samples 0 .. options.spp - 1 of `options` (whose first_sample must be 0).
SplitRender render_split(StudyRenderer& renderer, const RenderOptions& options);

// Adds the next `more` samples (total_spp() .. total_spp() + more - 1), cut as above.
void extend_split(StudyRenderer& renderer, const RenderOptions& options, int more, SplitRender& split);

// The images averaged with weights n_a, n_b (in double, rounded once); rays, seconds and counters summed.
RenderResult combine_renders(const RenderResult& a, int n_a, const RenderResult& b, int n_b);

}  // namespace ls
