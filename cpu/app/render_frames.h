// `render --frames A:B` (rigid animation): renders frames A..B of a scene's animation, frame f
// posed at t = f / fps seconds, and measures what each frame's structures cost to bring up to date.
//
// Two-level structures (2l-bvh, 2l-ls:D:N) are built once, on frame A's pose, and then updated per
// frame by their top level alone (Backend::update_top_level): object BVHs and their Line Space are
// reused untouched.  Flat structures (bvh, f-ls:D:N) are rebuilt from scratch every frame.  Beside
// each two-level structure's update the frame reports what rebuilding its flat counterpart (bvh for
// 2l-bvh, f-ls:D:N for 2l-ls:D:N) on that frame's pose takes, measured by building it (the schedule's
// own rebuild when the schedule holds it; skipped with --no-flat-comparison).
//
// Writes OUT/frame_NNNN/ (the files of a single render, report.json with a "frame" entry) and
// OUT/frames.json (rewritten after every frame, past 100 frames at most once a second; "complete" true
// once the last one is written), a table on stdout and one line per frame on stderr.  A frame is
// rendered into frame_NNNN.partial/ and renamed when whole, and an interrupt (exit 130) lists the
// frames once more: it leaves only whole frames and a frames.json that lists exactly them.
#pragma once

#include "common/render/backend.h"
#include "common/render/exposure.h"
#include "common/render/render_types.h"
#include "common/structure/accel.h"
#include "common/structure/top_level.h"

#include <string>

namespace ls {

struct FrameRange {
  int first = 0, last = 0;
};

constexpr int kMaxFrames = 10000;          // frames per run
constexpr int kMaxFrameIndex = 9999999;    // frame_NNNN names stay short

// "A:B" (A <= B) or "N" (= N:N), non-negative decimal integers; throws InputError otherwise.
FrameRange parse_frames(const std::string& text);

struct FramesOptions {
  FrameRange range;
  double fps = 24.0;                        // (0, 1000]
  size_t animation = 0;                     // which of the scene's animations
  bool flat_comparison = true;              // build the flat counterpart of each 2L structure per frame
  TopLevelMode top_level = TopLevelMode::Rebuild;
  bool quiet = false;                       // no per-frame lines on stderr
  ExposureRequest exposure;                 // each frame's PNG (auto: each frame exposed on its own)
};

// The flat structure a two-level one is compared with: bvh for 2l-bvh, f-ls:D:N for 2l-ls:D:N, and
// for 2l-ls:auto the F-LS of its plan's reference (`built` holds the plan; bvh when it has none).
StructureSpec flat_counterpart(const StructureSpec& spec, const Accel& built);

// `scene` is posed frame by frame (a copy of the loaded scene).  scene_spec names it in the reports.
void render_frames(Scene scene, const std::string& scene_spec, const RenderOptions& options,
                   const AccelOptions& accel_options, const FramesOptions& frames, const std::string& out_dir,
                   Backend& backend, const Progress& progress);

}  // namespace ls
