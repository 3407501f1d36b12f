# Compiles tests/glsl/kernels_compile.comp with glslang and requires NoContraction decorations in the
# SPIR-V (the `precise` of the deciding arithmetic; lavapipe could never notice them missing).
execute_process(COMMAND ${GLSLANG} -V --target-env vulkan1.2 -I${INCLUDE} ${SOURCE} -o ${OUTPUT}
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "glslang failed on the shared kernels:\n${out}${err}")
endif()
execute_process(COMMAND ${SPIRV_DIS} ${OUTPUT} RESULT_VARIABLE rc OUTPUT_VARIABLE dis)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "spirv-dis failed")
endif()
string(REGEX MATCHALL "NoContraction" hits "${dis}")
list(LENGTH hits count)
if(count LESS 20)
  message(FATAL_ERROR "only ${count} NoContraction decorations: `precise` is being lost")
endif()
message(STATUS "shared kernels compile as GLSL; ${count} NoContraction decorations")
