// A float as text that reads back as the same float ("%.9g"): for file headers that must compare
// equal and for messages that name a value exactly.
#pragma once

#include <cstdio>
#include <string>

namespace ls {

inline std::string float_text(float v) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.9g", double(v));
  return text;
}

}  // namespace ls
