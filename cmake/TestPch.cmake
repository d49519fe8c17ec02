# One precompiled header of what the LibTorch-free tests share: GoogleTest, Eigen and the standard
# headers they include most (cmake/test_pch.h). Parsing those is most of a test source's compile.
# Tests that link LibTorch keep what cmake/TorchPch.cmake gives them. The header is included into
# every test source, so a test that forgets a standard include still compiles here; a build with
# -DFORESIGHT_UNITY_BUILD=OFF compiles the tests without it (no CI build does that today).
#
# The header's target is compiled exactly as foresight_add_test compiles a test source (warnings,
# -O1, the sanitizer build's -fno-sanitize=undefined), so GCC and Clang accept it in every test.

# foresight_use_test_pch(): call once, after every target is defined (and after
# foresight_use_torch_pch, whose reuse a test keeps).
function(foresight_use_test_pch)
  get_property(tests GLOBAL PROPERTY FORESIGHT_BUILT_TESTS)
  if(NOT FORESIGHT_UNITY_BUILD OR NOT tests)
    return()
  endif()
  add_library(foresight_test_pch OBJECT EXCLUDE_FROM_ALL ${PROJECT_SOURCE_DIR}/cmake/test_pch.cc)
  target_link_libraries(foresight_test_pch PRIVATE GTest::gtest Eigen3::Eigen)
  foresight_test_compile_options(foresight_test_pch)
  target_precompile_headers(foresight_test_pch PRIVATE ${PROJECT_SOURCE_DIR}/cmake/test_pch.h)
  foreach(test IN LISTS tests)
    # A test linking LibTorch inherits its -D_GLIBCXX_USE_CXX11_ABI, which GCC's header must match.
    foresight_links_torch(${test} links_torch)
    get_target_property(reuses ${test} PRECOMPILE_HEADERS_REUSE_FROM)
    if(NOT reuses AND NOT links_torch)
      target_precompile_headers(${test} REUSE_FROM foresight_test_pch)
      target_compile_options(${test} PRIVATE -Winvalid-pch)  # GCC: say when it rejects the header
    endif()
  endforeach()
endfunction()
