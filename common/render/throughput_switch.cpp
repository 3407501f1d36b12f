#include "common/render/throughput_switch.h"

#include "common/model/scene.h"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace ls {

std::string shortest_text(float value) {
  char t[32];
  for (int digits = 1; digits <= 9; ++digits) {
    std::snprintf(t, sizeof(t), "%.*g", digits, double(value));
    if (std::strtof(t, nullptr) == value) break;
  }
  return t;
}

std::string ThroughputSwitch::name() const { return enabled() ? shortest_text(threshold) + ":" + structure.name() : "off"; }

float parse_switch_threshold(const std::string& text, const std::string& flag) {
  float v = 0.0f;
  const auto r = std::from_chars(text.data(), text.data() + text.size(), v);
  if (text.empty() || r.ec != std::errc() || r.ptr != text.data() + text.size() || !std::isfinite(v) || !(v > 0.0f))
    throw InputError(flag + ": the threshold '" + text + "' is not a finite number > 0");
  return v;
}

ThroughputSwitch parse_throughput_switch(const std::string& text) {
  const std::string flag = "--throughput-switch " + text;
  const size_t colon = text.find(':');
  if (colon == std::string::npos || colon + 1 == text.size())
    throw InputError(flag + ": expected T:STRUCTURE, e.g. 0.25:2l-ls:4:6");
  ThroughputSwitch s;
  s.threshold = parse_switch_threshold(text.substr(0, colon), flag);
  try {
    s.structure = parse_structure(text.substr(colon + 1));
  } catch (const InputError& e) {
    throw InputError(flag + ": " + e.what());
  }
  return s;
}

}  // namespace ls
