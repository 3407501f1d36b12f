// Facts of the machine that reports name beside their figures.
#pragma once

#include <string>

namespace ls {

// The CPU's model name from /proc/cpuinfo ("unknown CPU" where it has none).
std::string cpu_model();

}  // namespace ls
