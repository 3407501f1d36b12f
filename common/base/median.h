// The median of timings (the middle value, or the mean of the two middle ones); 0 for none.
#pragma once

#include <algorithm>
#include <vector>

namespace ls {

inline double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

}  // namespace ls
