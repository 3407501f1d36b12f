// `render --throughput-switch T:STRUCTURE` (common/kernels/throughput_switch.h decides per path and
// bounce): paths whose throughput luminance is below T trace that bounce's extension and shadow rays
// with STRUCTURE, the others follow the schedule.  Both groups are traced as batches of their own.
#pragma once

#include "common/model/structure_name.h"

#include <string>

namespace ls {

struct ThroughputSwitch {
  float threshold = 0.0f;  // 0: off
  StructureSpec structure;
  bool enabled() const { return threshold > 0.0f; }
  std::string name() const;  // "0.25:2l-ls:4:6" (the shortest text of the threshold), "off" when disabled
};

// The shortest text that reads back as the same float: "0.3", not "0.300000012".
std::string shortest_text(float value);

// T must be a finite number > 0; throws InputError naming `flag` otherwise.
float parse_switch_threshold(const std::string& text, const std::string& flag);
// "T:STRUCTURE"; throws InputError (one line) on anything else.
ThroughputSwitch parse_throughput_switch(const std::string& text);

}  // namespace ls
