# RGB -> spectrum tables (src/color, docs/spectral.md): tools/rgb2spec_opt.c
# solves them at build time into the build tree, and haze_color compiles them
# with the colour module. Included from the top-level CMakeLists.txt.

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

haze_subsystem(color haze_scene)
target_sources(haze_color PRIVATE ${HAZE_RGB2SPEC_TABLES})
set_source_files_properties(${HAZE_RGB2SPEC_TABLES} PROPERTIES OBJECT_DEPENDS ${HAZE_RGB2SPEC_BLOB})
