// Structure names and per-bounce schedules (docs/design.md §9): every accepted spelling, the canonical name
// round trip, the repeating last entry of a schedule, and the rejections (InputError).
#include <catch2/catch.hpp>

#include "common/model/scene.h"
#include "common/model/structure_name.h"

#include <string>
#include <vector>

using ls::InputError;
using ls::parse_schedule;
using ls::parse_structure;
using ls::parse_structure_list;
using ls::Schedule;
using ls::StructureKind;
using ls::StructureSpec;

namespace {

StructureSpec spec(StructureKind kind, int depth = 0, int subdivision = 0) {
  StructureSpec s;
  s.kind = kind;
  s.depth = depth;
  s.subdivision = subdivision;
  return s;
}

}  // namespace

TEST_CASE("structure names: every accepted spelling", "[structure_name]") {
  struct Case {
    std::string text;
    StructureSpec expected;
    std::string canonical;
  };
  const std::vector<Case> cases = {
      {"bvh", spec(StructureKind::FlatBvh), "bvh"},
      {"f-bvh", spec(StructureKind::FlatBvh), "bvh"},
      {"BVH", spec(StructureKind::FlatBvh), "bvh"},
      {"F-BVH", spec(StructureKind::FlatBvh), "bvh"},
      {"2l-bvh", spec(StructureKind::TwoLevelBvh), "2l-bvh"},
      {"2L-BVH", spec(StructureKind::TwoLevelBvh), "2l-bvh"},
      {"f-ls:8:6", spec(StructureKind::FlatLs, 8, 6), "f-ls:8:6"},
      {"2l-ls:0:10", spec(StructureKind::TwoLevelLs, 0, 10), "2l-ls:0:10"},
      {"F-LS(8,6)", spec(StructureKind::FlatLs, 8, 6), "f-ls:8:6"},
      {"f-ls(8,6)", spec(StructureKind::FlatLs, 8, 6), "f-ls:8:6"},
      {"2l-ls(4,6)", spec(StructureKind::TwoLevelLs, 4, 6), "2l-ls:4:6"},
      {"2L-LS:4:6", spec(StructureKind::TwoLevelLs, 4, 6), "2l-ls:4:6"},
      // The documented bounds themselves are accepted.
      {"f-ls:0:1", spec(StructureKind::FlatLs, 0, 1), "f-ls:0:1"},
      {"f-ls:" + std::to_string(ls::kMaxLsDepth) + ":" + std::to_string(ls::kMaxLsSubdivision),
       spec(StructureKind::FlatLs, ls::kMaxLsDepth, ls::kMaxLsSubdivision),
       "f-ls:" + std::to_string(ls::kMaxLsDepth) + ":" + std::to_string(ls::kMaxLsSubdivision)},
  };
  for (const Case& c : cases) {
    INFO("text: " << c.text);
    const StructureSpec s = parse_structure(c.text);
    CHECK(s == c.expected);
    CHECK(s.name() == c.canonical);
    // Canonical name round trip: parsing the name gives the same structure, and the name is a fixed point.
    CHECK(parse_structure(s.name()) == s);
    CHECK(parse_structure(s.name()).name() == s.name());
  }
}

TEST_CASE("structure names: kind predicates", "[structure_name]") {
  CHECK_FALSE(parse_structure("bvh").two_level());
  CHECK_FALSE(parse_structure("bvh").line_space());
  CHECK(parse_structure("2l-bvh").two_level());
  CHECK_FALSE(parse_structure("2l-bvh").line_space());
  CHECK_FALSE(parse_structure("f-ls:8:6").two_level());
  CHECK(parse_structure("f-ls:8:6").line_space());
  CHECK(parse_structure("2l-ls:0:10").two_level());
  CHECK(parse_structure("2l-ls:0:10").line_space());
}

TEST_CASE("structure names: rejections throw InputError", "[structure_name]") {
  const std::vector<std::string> bad = {
      "",            "bvh,,bvh",    "f-ls:8",      "f-ls:a:6",     "f-ls:-1:6",     "f-ls:8:0",
      "f-ls:99:6",   "f-ls:8:6:1",  "octree",      "f-ls(8,6",     "bvh,",          "f-ls",
      "f-ls:",       "f-ls::6",     "f-ls:8:",     "f-ls(8)",      "f-ls(8,6,1)",   "f-ls(8,6)x",
      "f-ls:8:65",   "f-ls:61:6",   "f-ls:8:-6",   "f-ls:8.5:6",   "f-ls:8:6 x",    "2l-ls:1e1:6",
      "bvh2",        "l2-bvh",      "f-ls:8;6",    ",bvh",         "2l-ls(4,6",     "2l-ls4:6",
      "f-ls:99999999999:6"};
  for (const std::string& text : bad) {
    INFO("schedule text: '" << text << "'");
    CHECK_THROWS_AS(parse_schedule(text), InputError);
    CHECK_THROWS_AS(parse_structure_list(text), InputError);
  }
  // Single structures: the same texts (those without a list separator) are refused by parse_structure.
  for (const std::string& text : bad) {
    if (text.find(',') != std::string::npos && text.find('(') == std::string::npos) continue;
    INFO("structure text: '" << text << "'");
    CHECK_THROWS_AS(parse_structure(text), InputError);
  }
  // A number past int says so, as one inside int but outside the range does (it said "not an integer").
  CHECK_THROWS_WITH(parse_structure("f-ls:4294967297:2"), Catch::Contains("depth D 4294967297 is outside [0, 60]"));
  CHECK_THROWS_WITH(parse_structure("f-ls:4:99999999999"), Catch::Contains("is outside [1, 64]"));
  // A list is not one structure.
  CHECK_THROWS_AS(parse_structure("bvh,bvh"), InputError);
  CHECK_THROWS_AS(parse_structure("bvh,"), InputError);
}

TEST_CASE("schedules: per bounce, last entry repeats", "[structure_name]") {
  const Schedule s = parse_schedule("bvh,bvh,2l-ls:4:6,2l-ls:0:10");
  REQUIRE(s.per_bounce.size() == 4);
  CHECK(s.at(0) == spec(StructureKind::FlatBvh));
  CHECK(s.at(1) == spec(StructureKind::FlatBvh));
  CHECK(s.at(2) == spec(StructureKind::TwoLevelLs, 4, 6));
  CHECK(s.at(3) == spec(StructureKind::TwoLevelLs, 0, 10));
  for (int bounce : {4, 5, 17, 1000, 1 << 30}) {
    INFO("bounce " << bounce);
    CHECK(s.at(bounce) == spec(StructureKind::TwoLevelLs, 0, 10));
  }
  CHECK(s.name() == "bvh,bvh,2l-ls:4:6,2l-ls:0:10");
  CHECK(parse_schedule(s.name()).per_bounce == s.per_bounce);

  // One entry repeats for every bounce.
  const Schedule one = parse_schedule("2l-bvh");
  REQUIRE(one.per_bounce.size() == 1);
  for (int bounce : {0, 1, 2, 63}) CHECK(one.at(bounce) == spec(StructureKind::TwoLevelBvh));
  CHECK(one.name() == "2l-bvh");

  // Parenthesised entries keep their comma; aliases and case are canonicalised in name().
  const Schedule mixed = parse_schedule("F-BVH,f-ls(8,6),2l-ls(4,6),2L-BVH");
  REQUIRE(mixed.per_bounce.size() == 4);
  CHECK(mixed.at(0) == spec(StructureKind::FlatBvh));
  CHECK(mixed.at(1) == spec(StructureKind::FlatLs, 8, 6));
  CHECK(mixed.at(2) == spec(StructureKind::TwoLevelLs, 4, 6));
  CHECK(mixed.at(3) == spec(StructureKind::TwoLevelBvh));
  CHECK(mixed.at(9) == spec(StructureKind::TwoLevelBvh));
  CHECK(mixed.name() == "bvh,f-ls:8:6,2l-ls:4:6,2l-bvh");
  CHECK(parse_schedule(mixed.name()).name() == mixed.name());
}

TEST_CASE("structure lists split like schedules", "[structure_name]") {
  const std::vector<StructureSpec> list = parse_structure_list("bvh,2l-bvh,f-ls(8,6),2l-ls:0:10");
  REQUIRE(list.size() == 4);
  CHECK(list[0] == spec(StructureKind::FlatBvh));
  CHECK(list[1] == spec(StructureKind::TwoLevelBvh));
  CHECK(list[2] == spec(StructureKind::FlatLs, 8, 6));
  CHECK(list[3] == spec(StructureKind::TwoLevelLs, 0, 10));
}
