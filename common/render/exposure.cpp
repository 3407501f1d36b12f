#include "common/render/exposure.h"

#include "common/model/scene.h"
#include "common/kernels/sampling.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>

namespace ls {

ExposureRequest parse_exposure(const std::string& text) {
  if (text == "auto") return {};
  // Decimal only, as every other number flag reads it (strtod took "0x10" and " 1"); "+1" is an EV.
  const char* begin = text.data() + (text.size() > 1 && text[0] == '+' && text[1] != '-');
  const char* end = text.data() + text.size();
  double ev = 0.0;
  const auto r = std::from_chars(begin, end, ev);
  if (text.empty() || r.ec != std::errc() || r.ptr != end || !std::isfinite(ev) || std::abs(ev) > double(kMaxExposureEv))
    throw InputError("--exposure '" + text + "': expected auto or a number of stops (EV) from -64 to 64");
  return ExposureRequest{false, float(ev)};
}

float auto_exposure(const std::vector<glm::vec3>& linear) {
  double sum = 0.0;
  size_t lit = 0;
  for (const glm::vec3& p : linear) {
    const float l = lsk::luminance(p);
    if (l > 0.0f && std::isfinite(l)) {
      sum += std::log(double(l));
      ++lit;
    }
  }
  if (lit == 0) return 1.0f;
  const double m = kExposureKey / std::exp(sum / double(lit));
  return float(std::clamp(m, std::exp2(-double(kMaxExposureEv)), std::exp2(double(kMaxExposureEv))));
}

Exposure choose_exposure(const ExposureRequest& request, const std::vector<glm::vec3>& linear) {
  Exposure e;
  e.automatic = request.automatic;
  if (request.automatic) {
    e.multiplier = auto_exposure(linear);
    e.ev = std::log2(e.multiplier);
  } else {
    e.ev = request.ev;
    e.multiplier = float(std::exp2(double(request.ev)));
  }
  return e;
}

nlohmann::json exposure_json(const Exposure& e) {
  return {{"mode", e.automatic ? "auto" : "given"}, {"ev", double(e.ev)}, {"multiplier", double(e.multiplier)}};
}

nlohmann::json exposure_request_json(const ExposureRequest& r) {
  if (r.automatic) return {{"mode", "auto"}};
  return {{"mode", "given"}, {"ev", double(r.ev)}};
}

ExposureRequest exposure_request_from_json(const nlohmann::json& report) {
  if (!report.contains("exposure")) return {};
  const nlohmann::json& e = report["exposure"];
  if (e.is_object() && e.value("mode", "") == "auto") return {};
  if (e.is_object() && e.value("mode", "") == "given" && e.contains("ev") && e["ev"].is_number()) {
    const double ev = e["ev"].get<double>();
    if (std::isfinite(ev) && std::abs(ev) <= double(kMaxExposureEv)) return ExposureRequest{false, float(ev)};
  }
  throw InputError("report's exposure is malformed: " + e.dump());
}

Exposure exposure_from_report(const nlohmann::json& report) {
  const nlohmann::json& e = report.at("exposure");
  return Exposure{e.at("mode").get<std::string>() == "auto", e.at("ev").get<float>(), e.at("multiplier").get<float>()};
}

std::string exposure_text(const Exposure& e) {
  char buffer[96];
  std::snprintf(buffer, sizeof buffer, "%s, EV %+.2f (x%.4g)", e.automatic ? "auto" : "given", double(e.ev),
                double(e.multiplier));
  return buffer;
}

}  // namespace ls
