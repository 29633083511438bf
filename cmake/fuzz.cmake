# libFuzzer targets (HAZE_FUZZ=ON, clang only): fuzz_scene feeds bytes to the
# scene parser (and the render-scene factories), fuzz_exr to the EXR reader,
# fuzz_nvdb to the .nvdb loader, the majorant build and grid lookups,
# fuzz_bsdf to the measured-BRDF (.bsdf) loader and the BRDF it builds.
# Run them with `make fuzz`; see docs/fuzzing.md. Included from CMakeLists.txt.
option(HAZE_FUZZ "Build the libFuzzer targets (needs clang)" OFF)
if(NOT HAZE_FUZZ)
  return()
endif()
if(NOT CMAKE_C_COMPILER_ID STREQUAL "Clang" OR NOT CMAKE_CXX_COMPILER_ID STREQUAL "Clang")
  message(FATAL_ERROR "HAZE_FUZZ needs clang (libFuzzer): configure with "
    "CC=clang CXX=clang++ (C compiler is ${CMAKE_C_COMPILER_ID}, C++ is ${CMAKE_CXX_COMPILER_ID})")
endif()

# Every library is instrumented for coverage and checked by ASan + UBSan; the
# fuzzer's main() comes only with the fuzz executables.
set(HAZE_FUZZ_FLAGS -fsanitize=fuzzer-no-link,address,undefined -fno-sanitize-recover=all
  -fno-omit-frame-pointer -g)
add_compile_options(${HAZE_FUZZ_FLAGS})
add_link_options(-fsanitize=address,undefined)

function(haze_fuzzer name)
  add_executable(${name} ${CMAKE_SOURCE_DIR}/fuzz/${name}.c)
  target_compile_options(${name} PRIVATE ${HAZE_WARNINGS} -fsanitize=fuzzer)
  target_link_options(${name} PRIVATE -fsanitize=fuzzer,address,undefined)
  target_link_libraries(${name} PRIVATE ${ARGN})
endfunction()

haze_fuzzer(fuzz_scene haze_render)
haze_fuzzer(fuzz_exr haze_film)
haze_fuzzer(fuzz_nvdb haze_media)
haze_fuzzer(fuzz_bsdf haze_materials)
