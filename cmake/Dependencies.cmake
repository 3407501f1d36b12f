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

# OpenImageIO 2.4 lists /usr/include/opencv4 as an include directory even when OpenCV is absent.
find_package(OpenImageIO REQUIRED)
foreach(prop INTERFACE_INCLUDE_DIRECTORIES INTERFACE_SYSTEM_INCLUDE_DIRECTORIES)
  get_target_property(dirs OpenImageIO::OpenImageIO ${prop})
  if(dirs)
    list(FILTER dirs EXCLUDE REGEX "opencv")
    set_target_properties(OpenImageIO::OpenImageIO PROPERTIES ${prop} "${dirs}")
  endif()
endforeach()
