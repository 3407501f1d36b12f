// A list with each item once, at its first place: the programs' list flags ("--depths 2,2",
// "--structures bvh,f-bvh") name a configuration once however often it is repeated.
#pragma once

#include <algorithm>
#include <vector>

namespace ls {

template <class T>
std::vector<T> without_repeats(const std::vector<T>& items) {
  std::vector<T> out;
  for (const T& item : items)
    if (std::find(out.begin(), out.end(), item) == out.end()) out.push_back(item);
  return out;
}

}  // namespace ls
