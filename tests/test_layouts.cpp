// The std430 structs that cross the bus (common/kernels/layouts.h), push constants and the shading
// constants included: their C++ sizes and member offsets are the ones glslang gives them.  The
// static_asserts are generated from glslang's SPIR-V (tests/glsl/layouts_offsets.cmake), so this file
// does not compile when the two disagree; the case below makes sure the check covered every struct.
#include <layouts_std430.h>  // generated in the build tree from glslang's SPIR-V

#include <catch2/catch.hpp>

#include <fstream>
#include <regex>
#include <sstream>
#include <string>

TEST_CASE("every std430 struct of layouts.h has glslang's size and member offsets in C++", "[layouts]") {
  std::ifstream in(LINESPACE_LAYOUTS_H);
  REQUIRE(in);
  std::stringstream text;
  text << in.rdbuf();
  const std::string s = text.str();
  const std::regex declaration("\\nstruct (LS_[A-Z_]+ )?[A-Za-z0-9_]+ \\{");  // LS_CACHE_LINE: host alignment
  const auto structs = std::distance(std::sregex_iterator(s.begin(), s.end(), declaration), std::sregex_iterator());
  CHECK(kLayoutStructs == structs);
  CHECK(kLayoutMembers >= kLayoutStructs * 2);
}
