#include "common/structure/accel.h"

#include <cmath>

namespace ls {

namespace {

constexpr Traversal kTraversals[] = {Traversal::Fast, Traversal::Reference};
constexpr LsBehind kLsBehinds[] = {LsBehind::Exact, LsBehind::Empty, LsBehind::Reverse};

// A flag's values by name, listed once (`all`, the default first): the names, and the parse whose
// error names them all.
template <class E, size_t N>
std::vector<std::string> names_of(const E (&all)[N], const char* (*name)(E)) {
  std::vector<std::string> names;
  for (E e : all) names.push_back(name(e));
  return names;
}

template <class E, size_t N>
E parse_named(const std::string& text, const E (&all)[N], const char* (*name)(E), const std::string& what) {
  std::string names;
  for (E e : all) {
    if (text == name(e)) return e;
    names += std::string(names.empty() ? "" : ", ") + name(e);
  }
  throw InputError(what + " '" + text + "' is not one of " + names);
}

}  // namespace

Traversal parse_traversal(const std::string& text) { return parse_named(text, kTraversals, traversal_name, "traversal"); }

const char* traversal_name(Traversal t) { return t == Traversal::Fast ? "fast" : "reference"; }

std::vector<std::string> traversal_names() { return names_of(kTraversals, traversal_name); }

LsBehind parse_ls_behind(const std::string& text) { return parse_named(text, kLsBehinds, ls_behind_name, "--ls-behind"); }

std::vector<std::string> ls_behind_names() { return names_of(kLsBehinds, ls_behind_name); }

float parse_ls_leave_reach(const std::string& text) {
  size_t used = 0;
  float reach = -1.0f;
  try {
    reach = std::stof(text, &used);
  } catch (const std::exception&) {  // not a number, or out of float's range
    used = 0;
  }
  if (used == 0 || used != text.size() || !(reach >= 0.0f))
    throw InputError("--ls-leave-reach '" + text + "' is not a number of patches >= 0 (inf: anywhere in the candidate's plane)");
  return reach;
}

const char* ls_behind_name(LsBehind behind) {
  switch (behind) {
    case LsBehind::Empty: return "empty";
    case LsBehind::Reverse: return "reverse";
    case LsBehind::Exact: break;
  }
  return "exact";
}

std::vector<ObjectLs> LsPlan::objects(size_t meshes) const {
  std::vector<ObjectLs> objects(meshes);
  for (const LsPlanRow& r : rows) objects[r.mesh] = r.chosen;
  return objects;
}

size_t Accel::bytes_ls() const {
  return node_ls.size() * sizeof(uint32_t) + ls_nodes.size() * sizeof(lsk::LsNode) +
         ls_candidates.size() * sizeof(uint32_t) + ls_records.size() * sizeof(lsk::LsRecord);
}

size_t Accel::bytes_total() const {
  return nodes.size() * sizeof(lsk::BvhNode) + tris.size() * sizeof(lsk::Triangle) +
         tri_ids.size() * sizeof(uint32_t) + tri_instances.size() * sizeof(uint32_t) +
         top_nodes.size() * sizeof(lsk::BvhNode) + instances.size() * sizeof(lsk::InstanceRecord) + bytes_ls();
}

float ls_cos2(const LsLookup& lookup) {
  const double a = double(lookup.angle_degrees) * 3.14159265358979323846 / 180.0;
  return lookup.angle_degrees <= 0.0f ? -1.0f : float(std::cos(a) * std::cos(a));
}

uint32_t ls_behind_code(const LsLookup& lookup) {
  switch (lookup.behind) {
    case LsBehind::Empty: return lsk::TraceContext::LS_BEHIND_EMPTY;
    case LsBehind::Reverse: return lsk::TraceContext::LS_BEHIND_REVERSE;
    case LsBehind::Exact: break;
  }
  return lsk::TraceContext::LS_BEHIND_EXACT;
}

lsk::TraceContext trace_context(const Accel& accel, const LsLookup& lookup) {
  lsk::TraceContext c;
  c.nodes = accel.nodes.data();
  c.tris = accel.tris.data();
  c.tri_ids = accel.tri_ids.data();
  c.tri_instances = accel.tri_instances.data();
  c.top_nodes = accel.top_nodes.data();
  c.instances = accel.instances.data();
  if (accel.spec.line_space() && !accel.node_ls.empty()) {  // laid out (a 2l-ls:auto plan traces before it has one)
    c.node_ls = accel.node_ls.data();
    c.ls_nodes = accel.ls_nodes.data();
    c.ls_candidates = accel.ls_candidates.data();
    c.ls_records = accel.ls_records.data();
    c.ls_enabled = 1;
    c.ls_cos2 = ls_cos2(lookup);
    c.ls_behind = ls_behind_code(lookup);
    c.ls_leave_reach = lookup.leave_reach;
    c.ls_skip = lookup.skip == LsSkip::RefusedWalks ? lsk::TraceContext::LS_SKIP_REFUSED_WALKS
                : lookup.skip == LsSkip::Lookups    ? lsk::TraceContext::LS_SKIP_LOOKUPS
                                                    : 0u;
  }
  return c;
}

void add_counters(lsk::LsCounters& into, const lsk::LsCounters& from) {
  into.lookups += from.lookups;
  into.empty += from.empty;
  into.accepted += from.accepted;
  into.refused_angle += from.refused_angle;
  into.refused_behind += from.refused_behind;
  into.refused_beyond += from.refused_beyond;
  into.refused_parallel += from.refused_parallel;
  into.refused_no_shaft += from.refused_no_shaft;
}

}  // namespace ls
