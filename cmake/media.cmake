# Participating media from OpenVDB grids: the haze_media library (C, plus the
# C++17 NanoVDB reader), the OpenVDB module haze loads for .vdb files, the volume
# generator and the `volumes` target.
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
  # Anything linking this static library needs the C++ driver (libstdc++ for
  # the NanoVDB reader). CMake propagates the C++ link language from a static
  # library to the executables that link it, so C test programs link with c++
  # without further setup.
  LINKER_LANGUAGE CXX)
# haze reads .nvdb itself with NanoVDB's header-only IO: only NanoVDB's headers
# (not OpenVDB::nanovdb, which drags in libopenvdb), SYSTEM so the bridge builds
# with the same warnings as our C. .nvdb files may be ZIP-compressed (NanoVDB's
# Codec::ZIP, zlib); the small vector test volumes are.
get_target_property(haze_nanovdb_include OpenVDB::nanovdb INTERFACE_INCLUDE_DIRECTORIES)
target_include_directories(haze_media SYSTEM PRIVATE ${haze_nanovdb_include})
target_compile_options(haze_media PRIVATE ${HAZE_WARNINGS})
target_compile_definitions(haze_media PRIVATE NANOVDB_USE_ZIP
  HAZE_OPENVDB_MODULE_NAME="$<TARGET_FILE_NAME:haze_openvdb>"
  HAZE_OPENVDB_MODULE_BUILD_PATH="$<TARGET_FILE:haze_openvdb>"
  HAZE_VDB_READER_BUILD_PATH="$<TARGET_FILE_DIR:haze_openvdb>/haze_vdb_reader")
target_link_libraries(haze_media
  PUBLIC haze_core haze_scene haze_color
  PRIVATE ZLIB::ZLIB Threads::Threads ${CMAKE_DL_LIBS})

# Everything that needs OpenVDB (.vdb files) is a module that haze dlopens on
# the first .vdb file (src/media/vdb_module.h), next to the haze executable.
# Whatever links haze_media gets it built.
add_library(haze_openvdb MODULE ${CMAKE_SOURCE_DIR}/src/media/openvdb_module.cpp)
target_include_directories(haze_openvdb PRIVATE ${CMAKE_SOURCE_DIR}/src)
target_compile_options(haze_openvdb PRIVATE ${HAZE_WARNINGS})
set_target_properties(haze_openvdb PROPERTIES
  CXX_STANDARD 17 CXX_STANDARD_REQUIRED ON CXX_EXTENSIONS OFF)
target_link_libraries(haze_openvdb PRIVATE OpenVDB::openvdb OpenVDB::nanovdb)
# The conversion to NanoVDB runs on TBB's threads (OpenVDB's own pool);
# without it NanoVDB's fallback starts half the cores' worth of std::threads,
# one on a two-core machine.
target_compile_definitions(haze_openvdb PRIVATE NANOVDB_USE_TBB)
# Only the entry table is exported: the module's own copies of OpenVDB's
# templates bind at link time instead of by symbol lookup when it is loaded.
target_link_options(haze_openvdb PRIVATE
  -Wl,--version-script=${CMAKE_SOURCE_DIR}/src/media/openvdb_module.map)
set_property(TARGET haze_openvdb APPEND PROPERTY LINK_DEPENDS
  ${CMAKE_SOURCE_DIR}/src/media/openvdb_module.map)
add_dependencies(haze_media haze_openvdb)

# The process that reads .vdb grids with the module (vdb_module_load_grid_isolated):
# next to haze and the module.
add_executable(haze_vdb_reader ${CMAKE_SOURCE_DIR}/src/vdb_reader.c)
target_compile_options(haze_vdb_reader PRIVATE ${HAZE_WARNINGS})
target_link_libraries(haze_vdb_reader PRIVATE haze_media)
set_target_properties(haze_vdb_reader PROPERTIES LINKER_LANGUAGE CXX)

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
