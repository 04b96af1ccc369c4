# Helpers that keep every module's CMakeLists.txt a few lines long.

set(STEREODET_WARNINGS -Wall -Wextra -Wpedantic -Wno-unused-parameter)

# stereodet_add_library(NAME SRCS a.cc b.cc DEPS x y)
#   Adds the static library `stereodet_NAME` (alias stereodet::NAME). Sources are relative to the
#   current directory; headers are included as "stereodet/NAME/foo.h" from src/. DEPS are linked
#   PUBLIC, which is how the layering in DESIGN.md is enforced: a module sees only what it names.
function(stereodet_add_library name)
  cmake_parse_arguments(ARG "" "" "SRCS;DEPS;PRIVATE_DEPS" ${ARGN})
  add_library(stereodet_${name} STATIC ${ARG_SRCS})
  add_library(stereodet::${name} ALIAS stereodet_${name})
  target_include_directories(stereodet_${name} PUBLIC ${PROJECT_SOURCE_DIR}/src)
  target_link_libraries(stereodet_${name} PUBLIC ${ARG_DEPS} PRIVATE ${ARG_PRIVATE_DEPS})
  target_compile_options(stereodet_${name} PRIVATE ${STEREODET_WARNINGS})
endfunction()

# stereodet_add_test(NAME SRCS a_test.cc DEPS stereodet::x [TIMEOUT seconds] [WHOLE_PROGRAM ctest])
#   Adds a GoogleTest executable NAME and registers each TEST with CTest (discovered at build time,
#   run from the source directory so tests can read checked-in data by relative path). TIMEOUT is
#   per CTest test (default 300 s). WHOLE_PROGRAM registers the program instead as the one CTest
#   test `ctest`, for programs whose every start is costly (LibTorch takes ~0.5-1 s to load, which
#   made 40 discovered tests take 40 s instead of 2).
function(stereodet_add_test name)
  if(NOT STEREODET_BUILD_TESTS)
    return()
  endif()
  cmake_parse_arguments(ARG "" "TIMEOUT;WHOLE_PROGRAM" "SRCS;DEPS" ${ARGN})
  if(NOT ARG_TIMEOUT)
    set(ARG_TIMEOUT 300)
  endif()
  add_executable(${name} ${ARG_SRCS})
  target_link_libraries(${name} PRIVATE ${ARG_DEPS} stereodet::test_paths
    GTest::gtest GTest::gtest_main GTest::gmock)
  target_compile_options(${name} PRIVATE ${STEREODET_WARNINGS})
  if(ARG_WHOLE_PROGRAM)
    add_test(NAME ${ARG_WHOLE_PROGRAM} COMMAND ${name} WORKING_DIRECTORY ${PROJECT_SOURCE_DIR})
    set_tests_properties(${ARG_WHOLE_PROGRAM} PROPERTIES TIMEOUT ${ARG_TIMEOUT})
  else()
    gtest_discover_tests(${name} WORKING_DIRECTORY ${PROJECT_SOURCE_DIR}
      PROPERTIES TIMEOUT ${ARG_TIMEOUT} DISCOVERY_TIMEOUT 60)
  endif()
endfunction()

# stereodet_add_benchmark(NAME SRCS a_benchmark.cc DEPS stereodet::x)
function(stereodet_add_benchmark name)
  if(NOT STEREODET_BUILD_BENCHMARKS)
    return()
  endif()
  cmake_parse_arguments(ARG "" "" "SRCS;DEPS" ${ARGN})
  add_executable(${name} ${ARG_SRCS})
  target_link_libraries(${name} PRIVATE ${ARG_DEPS} benchmark::benchmark)
  target_compile_options(${name} PRIVATE ${STEREODET_WARNINGS})
endfunction()
