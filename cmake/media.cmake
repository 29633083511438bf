# Participating media from OpenVDB grids: the haze_media library (C, plus the one
# C++17 bridge to OpenVDB), the volume generator and the `volumes` target.
# Included from the top-level CMakeLists.txt.

# OpenVDB ships only a find-module (no package config) on Debian.
list(APPEND CMAKE_MODULE_PATH /usr/lib/x86_64-linux-gnu/cmake/OpenVDB)
find_package(OpenVDB REQUIRED COMPONENTS openvdb nanovdb)
find_package(ZLIB REQUIRED)

file(GLOB haze_media_c CONFIGURE_DEPENDS ${CMAKE_SOURCE_DIR}/src/media/*.c)
add_library(haze_media STATIC ${haze_media_c} ${CMAKE_SOURCE_DIR}/src/media/vdb_load.cpp)
target_include_directories(haze_media PUBLIC ${CMAKE_SOURCE_DIR}/src)
target_compile_definitions(haze_media PUBLIC HAZE_VERSION="${PROJECT_VERSION}")
set_target_properties(haze_media PROPERTIES
  CXX_STANDARD 17 CXX_STANDARD_REQUIRED ON CXX_EXTENSIONS OFF
  # Anything linking this static library needs the C++ driver (libstdc++, and the
  # OpenVDB/TBB/Imath shared libraries it pulls in). CMake propagates the C++ link
  # language from a static library to the executables that link it, so C test
  # programs link with c++ without further setup.
  LINKER_LANGUAGE CXX)
# The OpenVDB and NanoVDB headers come from imported targets, hence are SYSTEM
# includes, so the C++ bridge builds with the same warnings as our C.
target_compile_options(haze_media PRIVATE ${HAZE_WARNINGS})
target_link_libraries(haze_media
  PUBLIC haze_core haze_scene
  PRIVATE OpenVDB::openvdb OpenVDB::nanovdb ZLIB::ZLIB)
# .nvdb files may be ZIP-compressed (NanoVDB's Codec::ZIP, zlib: already an
# OpenVDB dependency); the small vector test volumes are.
target_compile_definitions(haze_media PRIVATE NANOVDB_USE_ZIP)

# The generator of the small test/demo volumes in volumes/.
add_executable(haze_volumes ${CMAKE_SOURCE_DIR}/volumes/generate.cpp)
set_target_properties(haze_volumes PROPERTIES CXX_STANDARD 17 CXX_STANDARD_REQUIRED ON
  CXX_EXTENSIONS OFF)
target_compile_options(haze_volumes PRIVATE ${HAZE_WARNINGS})
target_link_libraries(haze_volumes PRIVATE OpenVDB::openvdb OpenVDB::nanovdb ZLIB::ZLIB)
target_compile_definitions(haze_volumes PRIVATE NANOVDB_USE_ZIP)

add_custom_target(volumes
  COMMAND haze_volumes ${CMAKE_SOURCE_DIR}/volumes
  DEPENDS haze_volumes
  COMMENT "Writing the generated volumes into ${CMAKE_SOURCE_DIR}/volumes"
  VERBATIM)
