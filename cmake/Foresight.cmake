# Helper functions: one line per library, test or benchmark.

set(FORESIGHT_WARNINGS -Wall -Wextra -Wpedantic -Wshadow -Wnon-virtual-dtor -Wno-unused-parameter)

# foresight_add_library(NAME SOURCES a.cc b.cc DEPS x y)
function(foresight_add_library name)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS" ${ARGN})
  add_library(${name} STATIC ${ARG_SOURCES})
  target_include_directories(${name} PUBLIC ${PROJECT_SOURCE_DIR})
  target_compile_options(${name} PRIVATE ${FORESIGHT_WARNINGS})
  target_link_libraries(${name} PUBLIC ${ARG_DEPS})
  set_target_properties(${name} PROPERTIES POSITION_INDEPENDENT_CODE ON)
endfunction()

# foresight_links_torch(TARGET OUT): OUT is TRUE when TARGET links LibTorch, directly or through
# the libraries it links (a source may include LibTorch only under #ifdef in a torch-free target).
function(foresight_links_torch target out)
  get_property(known GLOBAL PROPERTY "FORESIGHT_LINKS_TORCH:${target}" SET)
  if(known)
    get_property(value GLOBAL PROPERTY "FORESIGHT_LINKS_TORCH:${target}")
    set(${out} ${value} PARENT_SCOPE)
    return()
  endif()
  set_property(GLOBAL PROPERTY "FORESIGHT_LINKS_TORCH:${target}" FALSE)  # link cycles end here
  get_target_property(type ${target} TYPE)
  set(libraries "")
  if(NOT type STREQUAL "INTERFACE_LIBRARY")
    get_target_property(libraries ${target} LINK_LIBRARIES)
  endif()
  get_target_property(interface ${target} INTERFACE_LINK_LIBRARIES)
  foresight_any_links_torch(result ${libraries} ${interface})
  set_property(GLOBAL PROPERTY "FORESIGHT_LINKS_TORCH:${target}" ${result})
  set(${out} ${result} PARENT_SCOPE)
endfunction()

# foresight_any_links_torch(OUT LIBRARY...): OUT is TRUE when one of the link items is LibTorch or
# a project target that links it.
function(foresight_any_links_torch out)
  set(result FALSE)
  foreach(library IN LISTS ARGN)
    if(library STREQUAL "torch" OR library MATCHES "lib(torch|c10)[^/]*$")
      set(result TRUE)
    elseif(TARGET "${library}")
      get_target_property(imported "${library}" IMPORTED)
      if(NOT imported)
        foresight_links_torch("${library}" result)
      endif()
    endif()
    if(result)
      break()
    endif()
  endforeach()
  set(${out} ${result} PARENT_SCOPE)
endfunction()

# foresight_builds_test(OUT DEPS...): whether this build makes a test binary that links
# DEPS. Always, except in a LibTorch build with -DFORESIGHT_TORCH_FREE_TESTS=OFF, for binaries that
# link no LibTorch: scripts/test.sh's sanitizer build (a LibTorch-free build) builds and runs those.
function(foresight_builds_test out)
  set(result TRUE)
  if(FORESIGHT_WITH_TORCH AND NOT FORESIGHT_TORCH_FREE_TESTS)
    foresight_any_links_torch(result ${ARGN})
  endif()
  set(${out} ${result} PARENT_SCOPE)
endfunction()

# foresight_test_compile_options(TARGET): how a test source is compiled (also the tests' precompiled
# header, cmake/TestPch.cmake, which must match).
function(foresight_test_compile_options target)
  target_compile_options(${target} PRIVATE ${FORESIGHT_WARNINGS})
  # Test sources at -O1 in optimised builds (the code under test is in the libraries, built as
  # configured): a LibTorch test source compiles in 49 s instead of 67 s at -O3, and GCC still
  # accepts the -O3 precompiled <torch/torch.h> (it rejects it only at -O0).
  if(CMAKE_BUILD_TYPE MATCHES "^(Release|RelWithDebInfo)$")
    target_compile_options(${target} PRIVATE -O1)
  endif()
  # Sanitizer builds: UBSan instruments the libraries, apps and fuzz targets, ASan everything; test
  # sources (with the header templates and inline code they compile) skip UBSan's instrumentation,
  # which took 5 of the 12 s a test source needs under Clang 14 (core/rbf_test.cc: 12.0 s -> 6.9 s;
  # -O0 instead would compile in 7 s but made the sanitizer tests run 1460 s instead of 433 s).
  if(FORESIGHT_SANITIZE AND NOT FORESIGHT_FUZZ)
    target_compile_options(${target} PRIVATE -fno-sanitize=undefined)
  endif()
endfunction()

# foresight_add_test(NAME SOURCES a_test.cc DEPS lib [PREFIX p.])
# PREFIX is prepended to the discovered ctest names (so `ctest -R p` selects the binary's tests).
# A binary this build leaves to another (foresight_builds_test) is defined but neither built by
# default nor run.
function(foresight_add_test name)
  cmake_parse_arguments(ARG "" "PREFIX" "SOURCES;DEPS" ${ARGN})
  foresight_builds_test(builds ${ARG_DEPS})
  set(exclude "")
  if(NOT builds)
    set(exclude EXCLUDE_FROM_ALL)
  endif()
  add_executable(${name} ${exclude} ${ARG_SOURCES})
  foresight_test_compile_options(${name})
  target_link_libraries(${name} PRIVATE ${ARG_DEPS} GTest::gtest GTest::gtest_main)
  set_target_properties(${name} PROPERTIES RUNTIME_OUTPUT_DIRECTORY ${CMAKE_BINARY_DIR}/tests)
  if(NOT builds)
    # scripts/test.sh checks that the LibTorch-free build defines each of these.
    file(APPEND ${CMAKE_BINARY_DIR}/tests_left_to_torch_free_build.txt "${name}\n")
    return()
  endif()
  set_property(GLOBAL APPEND PROPERTY FORESIGHT_BUILT_TESTS ${name})
  gtest_discover_tests(${name}
    WORKING_DIRECTORY ${PROJECT_SOURCE_DIR}
    TEST_PREFIX "${ARG_PREFIX}"
    PROPERTIES ENVIRONMENT "FORESIGHT_SOURCE_DIR=${PROJECT_SOURCE_DIR}"
    DISCOVERY_TIMEOUT 60)
endfunction()

# foresight_unity_torch_free_libraries(): builds each torch-free library with more than one source
# as unity translation units (CMake's UNITY_BUILD, batches of 8): its sources share one parse of
# Eigen and the standard headers. Both builds of scripts/test.sh compile these libraries, so this
# is where a unity build saves most. LibTorch libraries are grouped by kind instead (cmake/
# TorchPch.cmake) and tests keep one unit per source (each test file is read on its own). -DFORESIGHT_UNITY_BUILD=OFF builds every source alone (the fuzz build does: it checks that
# each source includes what it uses). Call once, after every target is defined.
function(foresight_unity_torch_free_libraries)
  if(NOT FORESIGHT_UNITY_BUILD)
    return()
  endif()
  _foresight_targets_in("${PROJECT_SOURCE_DIR}" targets)
  foreach(target IN LISTS targets)
    get_target_property(type ${target} TYPE)
    get_target_property(source_dir ${target} SOURCE_DIR)
    if(NOT type STREQUAL "STATIC_LIBRARY" OR source_dir MATCHES "/tests(/|$)")
      continue()
    endif()
    get_target_property(sources ${target} SOURCES)
    list(FILTER sources INCLUDE REGEX "\\.(cc|cpp)$")
    list(LENGTH sources count)
    foresight_links_torch(${target} uses_torch)
    if(count GREATER 1 AND NOT uses_torch)
      set_target_properties(${target} PROPERTIES UNITY_BUILD ON UNITY_BUILD_BATCH_SIZE 8)
    endif()
  endforeach()
endfunction()
