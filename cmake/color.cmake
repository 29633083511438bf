# RGB -> spectrum tables (src/color, docs/spectral.md): tools/rgb2spec_opt.c
# solves them at build time into the build tree, and they are built into a
# data module, libhaze_rgb2spec.so next to haze, that haze_color loads when a
# render needs them (src/color/rgb2spec_module.h). Included from the
# top-level CMakeLists.txt.

set(HAZE_RGB2SPEC_RES 64 CACHE STRING "Nodes per axis of the RGB -> spectrum tables")

# The generator is built from the few sources it needs (the CIE 1931 observer,
# the colour spaces and their illuminants), not from the libraries, so it can
# run while the rest of haze compiles.
add_executable(rgb2spec_opt ${CMAKE_SOURCE_DIR}/tools/rgb2spec_opt.c
  ${CMAKE_SOURCE_DIR}/src/scene/spectrum.c ${CMAKE_SOURCE_DIR}/src/scene/cie1931.c
  ${CMAKE_SOURCE_DIR}/src/core/color_space.c ${CMAKE_SOURCE_DIR}/src/color/illuminant.c
  ${CMAKE_SOURCE_DIR}/src/color/illuminant_table.c)
target_include_directories(rgb2spec_opt PRIVATE ${CMAKE_SOURCE_DIR}/src)
target_compile_options(rgb2spec_opt PRIVATE ${HAZE_WARNINGS})
target_link_libraries(rgb2spec_opt PRIVATE m Threads::Threads)
# Always optimised and never instrumented: the tables are the same bytes
# either way, and in a Debug build with sanitizers (make test-asan) solving
# them takes 8 times the CPU (16.5 s against 2.1 s at RES 24).
target_compile_options(rgb2spec_opt PRIVATE -O2)
if(HAZE_SANITIZE OR HAZE_FUZZ)
  target_compile_options(rgb2spec_opt PRIVATE -fno-sanitize=all)
  target_link_options(rgb2spec_opt PRIVATE -fno-sanitize=all)
endif()

# The tables' floats go to a binary file that the small generated C source
# assembles in (.incbin): as a C initialiser they would take gcc 30 s and 2 GB.
set(HAZE_RGB2SPEC_TABLES ${CMAKE_BINARY_DIR}/generated/rgb2spec_tables.c)
set(HAZE_RGB2SPEC_BLOB ${CMAKE_BINARY_DIR}/generated/rgb2spec_tables.bin)
add_custom_command(OUTPUT ${HAZE_RGB2SPEC_TABLES} ${HAZE_RGB2SPEC_BLOB}
  COMMAND ${CMAKE_COMMAND} -E make_directory ${CMAKE_BINARY_DIR}/generated
  COMMAND rgb2spec_opt ${HAZE_RGB2SPEC_RES} ${HAZE_RGB2SPEC_TABLES} ${HAZE_RGB2SPEC_BLOB}
  DEPENDS rgb2spec_opt
  COMMENT "Solving the RGB -> spectrum tables (${HAZE_RGB2SPEC_RES}^3 per colour space)"
  VERBATIM)

# The module: the generated source (included by the module's one source
# file) and the entry table. It exports that table only: the blob's symbol and
# the solutions stay local.
add_library(haze_rgb2spec MODULE ${CMAKE_SOURCE_DIR}/src/color/module/rgb2spec_module.c)
target_include_directories(haze_rgb2spec PRIVATE ${CMAKE_SOURCE_DIR}/src ${CMAKE_BINARY_DIR}/generated)
target_compile_options(haze_rgb2spec PRIVATE ${HAZE_WARNINGS})
set_target_properties(haze_rgb2spec PROPERTIES LIBRARY_OUTPUT_DIRECTORY ${CMAKE_BINARY_DIR}
  C_VISIBILITY_PRESET hidden)
set_source_files_properties(${CMAKE_SOURCE_DIR}/src/color/module/rgb2spec_module.c
  PROPERTIES OBJECT_DEPENDS "${HAZE_RGB2SPEC_TABLES};${HAZE_RGB2SPEC_BLOB}")
target_link_options(haze_rgb2spec PRIVATE
  -Wl,--version-script=${CMAKE_SOURCE_DIR}/src/color/module/rgb2spec_module.map)
set_property(TARGET haze_rgb2spec APPEND PROPERTY LINK_DEPENDS
  ${CMAKE_SOURCE_DIR}/src/color/module/rgb2spec_module.map)
add_custom_target(haze_rgb2spec_tables DEPENDS ${HAZE_RGB2SPEC_TABLES} ${HAZE_RGB2SPEC_BLOB})
add_dependencies(haze_rgb2spec haze_rgb2spec_tables)

# haze_color finds the module next to the executable or in the build tree;
# whatever links it gets the module built.
haze_subsystem(color haze_scene)
target_compile_definitions(haze_color PRIVATE
  HAZE_RGB2SPEC_MODULE_NAME="$<TARGET_FILE_NAME:haze_rgb2spec>"
  HAZE_RGB2SPEC_MODULE_BUILD_PATH="$<TARGET_FILE:haze_rgb2spec>")
add_dependencies(haze_color haze_rgb2spec)
