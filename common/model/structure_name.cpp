#include "common/model/structure_name.h"

#include "common/model/scene.h"

#include <algorithm>
#include <cctype>
#include <charconv>

namespace ls {
namespace {

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return s;
}

int parse_int(const std::string& text, const std::string& what, int lo, int hi, const std::string& whole) {
  int value = 0;
  const char* end = text.data() + text.size();
  auto [ptr, ec] = std::from_chars(text.data(), end, value);
  if (ec == std::errc::result_out_of_range && ptr == end)
    throw InputError("structure '" + whole + "': " + what + " " + text + " is outside [" + std::to_string(lo) + ", " +
                     std::to_string(hi) + "]");
  if (text.empty() || ec != std::errc() || ptr != end)
    throw InputError("structure '" + whole + "': " + what + " '" + text + "' is not an integer");
  if (value < lo || value > hi)
    throw InputError("structure '" + whole + "': " + what + " " + text + " is outside [" + std::to_string(lo) + ", " +
                     std::to_string(hi) + "]");
  return value;
}

}  // namespace

std::string StructureSpec::name() const {
  switch (kind) {
    case StructureKind::FlatBvh: return "bvh";
    case StructureKind::TwoLevelBvh: return "2l-bvh";
    case StructureKind::FlatLs: return "f-ls:" + std::to_string(depth) + ":" + std::to_string(subdivision);
    case StructureKind::TwoLevelLs:
      return budgeted ? "2l-ls:auto" : "2l-ls:" + std::to_string(depth) + ":" + std::to_string(subdivision);
  }
  return "?";
}

StructureSpec parse_structure(const std::string& raw) {
  const std::string text = lower(raw);
  StructureSpec spec;
  if (text == "bvh" || text == "f-bvh") return spec;
  if (text == "2l-bvh") {
    spec.kind = StructureKind::TwoLevelBvh;
    return spec;
  }
  if (text == "2l-ls:auto") {
    spec.kind = StructureKind::TwoLevelLs;
    spec.budgeted = true;
    return spec;
  }
  std::string prefix, d, n;
  for (const char* p : {"f-ls", "2l-ls"}) {
    const std::string pre(p);
    if (text.rfind(pre, 0) != 0) continue;
    const std::string rest = text.substr(pre.size());
    if (rest.size() > 2 && rest.front() == ':') {  // f-ls:D:N
      const size_t colon = rest.find(':', 1);
      if (colon == std::string::npos) break;
      prefix = pre, d = rest.substr(1, colon - 1), n = rest.substr(colon + 1);
    } else if (rest.size() > 2 && rest.front() == '(' && rest.back() == ')') {  // f-ls(D,N)
      const size_t comma = rest.find(',');
      if (comma == std::string::npos) break;
      prefix = pre, d = rest.substr(1, comma - 1), n = rest.substr(comma + 1, rest.size() - comma - 2);
    }
    break;
  }
  if (prefix.empty())
    throw InputError("unknown structure '" + raw + "' (expected bvh, f-bvh, 2l-bvh, f-ls:D:N, 2l-ls:D:N or 2l-ls:auto)");
  spec.kind = prefix == "f-ls" ? StructureKind::FlatLs : StructureKind::TwoLevelLs;
  spec.depth = parse_int(d, "depth D", 0, kMaxLsDepth, raw);
  spec.subdivision = parse_int(n, "subdivision N", 1, kMaxLsSubdivision, raw);
  return spec;
}

std::vector<StructureSpec> parse_structure_list(const std::string& text) {
  std::vector<StructureSpec> list;
  size_t start = 0;
  // Split on commas that are not inside parentheses (f-ls(8,6) holds one).
  int depth = 0;
  for (size_t i = 0; i <= text.size(); ++i) {
    if (i < text.size() && text[i] == '(') ++depth;
    if (i < text.size() && text[i] == ')') --depth;
    if (i == text.size() || (text[i] == ',' && depth == 0)) {
      std::string item = text.substr(start, i - start);
      item.erase(0, item.find_first_not_of(" \t"));
      item.erase(item.find_last_not_of(" \t") + 1);
      if (item.empty()) throw InputError("empty entry in structure list '" + text + "'");
      list.push_back(parse_structure(item));
      start = i + 1;
    }
  }
  return list;
}

std::string Schedule::name() const {
  std::string s;
  for (size_t i = 0; i < per_bounce.size(); ++i) {
    if (i) s += ',';
    s += per_bounce[i].name();
  }
  return s;
}

Schedule parse_schedule(const std::string& text) {
  Schedule schedule;
  schedule.per_bounce = parse_structure_list(text);
  return schedule;
}

}  // namespace ls
