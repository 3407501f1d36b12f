// How a render's PNG is exposed: its linear image is multiplied by one number before write_png clamps
// it and applies the sRGB curve.  Automatic by default, so that any scene's picture is seen whatever
// its lights' power: the key value of Reinhard et al. (2002), the log-average luminance of the lit
// pixels (luminance > 0) becomes 0.18, middle grey.  Not the validator's 99th-percentile rule
// (image_metrics.h, a scale for RMSE): where a ceiling light fills more than 1 % of the picture, as in
// four of the five real scenes, that rule makes the light white and the room dark (PNG means 36-43 of
// 255 against 119-123; docs/usage.md).  `--exposure EV` gives the multiplier 2^EV instead (0: the
// radiance as is).  EXRs are never scaled.  The automatic choice reads the finished image only, in
// pixel order, so the same image (a single render, or the merge of its shards) gets the same bits.
#pragma once

#include <glm/glm.hpp>
#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace ls {

// What the command line asked for.
struct ExposureRequest {
  bool automatic = true;
  float ev = 0.0f;  // given: stops
};

// What was used.
struct Exposure {
  bool automatic = true;
  float ev = 0.0f;          // log2(multiplier)
  float multiplier = 1.0f;  // what write_png multiplies by
};

constexpr float kMaxExposureEv = 64.0f;  // 2^64 and 2^-64 stay far from float's limits
constexpr double kExposureKey = 0.18;    // what the log-average luminance becomes

// The automatic multiplier: kExposureKey / exp(mean of log luminance over pixels with 0 < luminance <
// inf), within 2^-64 .. 2^64; 1 when no pixel is lit.
float auto_exposure(const std::vector<glm::vec3>& linear);

// "auto", or a finite number of stops in [-64, 64]; anything else throws InputError (one line).
ExposureRequest parse_exposure(const std::string& text);
Exposure choose_exposure(const ExposureRequest& request, const std::vector<glm::vec3>& linear);

// report.json's "exposure": {"mode": "auto" | "given", "ev": E, "multiplier": M}.
nlohmann::json exposure_json(const Exposure& e);
// A shard's request in its partial's report ({"mode": ..., "ev": E when given}), and back; a report
// without the key asked for auto.  Throws InputError on a malformed value.
nlohmann::json exposure_request_json(const ExposureRequest& r);
ExposureRequest exposure_request_from_json(const nlohmann::json& report);
// The "exposure" that write_render_outputs put into a report (throws json errors when absent).
Exposure exposure_from_report(const nlohmann::json& report);
// "auto, EV +3.21 (x9.27)": for the command's summary line.
std::string exposure_text(const Exposure& e);

}  // namespace ls
