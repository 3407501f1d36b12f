# Writes OUTPUT, a C++ source defining the SPIR-V words of INPUT as ls::gpu::spirv_NAME, so the
# programs and tests carry their shaders wherever they run from.
file(READ ${INPUT} hex HEX)
string(LENGTH "${hex}" n)
math(EXPR rem "${n} % 8")
if(n EQUAL 0 OR NOT rem EQUAL 0)
  message(FATAL_ERROR "${INPUT} is not SPIR-V (${n} hex digits)")
endif()
# Little-endian bytes b0 b1 b2 b3 -> word 0xb3b2b1b0.
string(REGEX REPLACE "([0-9a-f][0-9a-f])([0-9a-f][0-9a-f])([0-9a-f][0-9a-f])([0-9a-f][0-9a-f])" "0x\\4\\3\\2\\1u," words "${hex}")
file(WRITE ${OUTPUT} "// Generated from ${INPUT} by gpu/embed_spirv.cmake.\n#include \"gpu/shaders.h\"\n"
     "namespace ls::gpu {\nconst std::vector<uint32_t>& spirv_${NAME}() {\n  static const std::vector<uint32_t> words{${words}};\n  return words;\n}\n}  // namespace ls::gpu\n")
