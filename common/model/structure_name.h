// Names of the acceleration structures and per-bounce schedules (docs/design.md §9):
//   bvh (alias f-bvh), 2l-bvh, f-ls:D:N, 2l-ls:D:N   (f-ls(D,N) and 2l-ls(D,N) accepted too)
//   2l-ls:auto: a two-level Line Space whose D and N are chosen per object under --ls-budget MB
//   schedule: comma-separated structures, one per bounce from bounce 0, the last repeating.
#pragma once

#include <string>
#include <vector>

namespace ls {

enum class StructureKind { FlatBvh, TwoLevelBvh, FlatLs, TwoLevelLs };

struct StructureSpec {
  StructureKind kind = StructureKind::FlatBvh;
  int depth = 0;        // LS integration depth D (LS kinds only)
  int subdivision = 0;  // LS patches per face edge N (LS kinds only)
  bool budgeted = false;  // 2l-ls:auto: D and N per object, from the Line Space budget (depth, subdivision 0)

  bool two_level() const { return kind == StructureKind::TwoLevelBvh || kind == StructureKind::TwoLevelLs; }
  bool line_space() const { return kind == StructureKind::FlatLs || kind == StructureKind::TwoLevelLs; }
  std::string name() const;  // canonical: bvh, 2l-bvh, f-ls:D:N, 2l-ls:D:N
  bool operator==(const StructureSpec&) const = default;
};

constexpr int kMaxLsDepth = 60;
constexpr int kMaxLsSubdivision = 64;

StructureSpec parse_structure(const std::string& text);                 // throws InputError
std::vector<StructureSpec> parse_structure_list(const std::string& text);  // comma-separated

struct Schedule {
  std::vector<StructureSpec> per_bounce;  // never empty
  const StructureSpec& at(int bounce) const {
    return per_bounce[size_t(bounce) < per_bounce.size() ? size_t(bounce) : per_bounce.size() - 1];
  }
  std::string name() const;
};

Schedule parse_schedule(const std::string& text);  // throws InputError

}  // namespace ls
