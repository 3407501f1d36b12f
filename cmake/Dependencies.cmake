# Every dependency is a Debian package (scripts/setup.sh installs them).  Their traps: docs/design.md §11.
find_package(Threads REQUIRED)           # before glslang: its targets use Threads::Threads
find_package(TBB REQUIRED)
find_package(glm REQUIRED)
find_package(TinyGLTF REQUIRED)
find_package(nlohmann_json 3 REQUIRED)
find_package(CLI11 REQUIRED)
find_package(embree 3 REQUIRED)

# xsimd 8.1 links a target `xtl` that nothing defines.
find_package(xsimd REQUIRED)
if(NOT TARGET xtl)
  add_library(xtl INTERFACE IMPORTED)
endif()

# Images: OpenEXR 3 for the linear EXRs (zip, custom header attributes), libpng for the PNGs.
find_package(OpenEXR 3 REQUIRED)
find_package(PNG REQUIRED)
