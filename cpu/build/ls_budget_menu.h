// The (D, N) a 2l-ls:auto plan can give an object (cpu/build/ls_budget.h), apart from the planner so
// that the memory estimate (cpu/build/structure_budget.h) can bound a plan by its largest entry.
#pragma once

#include "common/structure/accel.h"

#include <array>
#include <vector>

namespace ls {

inline constexpr std::array<int, 5> kLsBudgetDepths = {0, 2, 4, 6, 8};
inline constexpr std::array<int, 5> kLsBudgetSubdivisions = {2, 4, 6, 8, 10};

// Every pair, depth-major.
inline std::vector<ObjectLs> ls_budget_menu() {
  std::vector<ObjectLs> menu;
  for (int d : kLsBudgetDepths)
    for (int n : kLsBudgetSubdivisions) menu.push_back(ObjectLs{d, n});
  return menu;
}

}  // namespace ls
