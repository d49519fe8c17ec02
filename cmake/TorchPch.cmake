# One precompiled <torch/torch.h> shared by every translation unit that includes it.
#
# Parsing torch/torch.h costs ~17 s per translation unit; loading the precompiled header ~7 s. The
# header is compiled once (foresight_torch_pch) and reused (REUSE_FROM) by each target that has a
# LibTorch source; that target's torch-free sources skip it, since loading the 0.5 GB header costs
# more than they take to compile. GCC only accepts a precompiled header built with the same -fPIC
# setting, so every consumer compiles position-independent code, as the libraries already do.
#
# A source counts as LibTorch when its target links LibTorch and it, or a project header it includes (recursively, quoted
# includes resolved from the project root or the including file's folder), includes <torch/...>.
# The scan runs at configure time; a wrong answer only costs compile time, never correctness.

# _foresight_includes_torch(FILE OUT): OUT is TRUE when FILE reaches an #include <torch/...>.
function(_foresight_includes_torch file out)
  get_property(known GLOBAL PROPERTY "FORESIGHT_TORCH:${file}" SET)
  if(known)
    get_property(value GLOBAL PROPERTY "FORESIGHT_TORCH:${file}")
    set(${out} ${value} PARENT_SCOPE)
    return()
  endif()
  set_property(GLOBAL PROPERTY "FORESIGHT_TORCH:${file}" FALSE)  # include cycles end here
  set(result FALSE)
  if(EXISTS "${file}")
    get_filename_component(folder "${file}" DIRECTORY)
    file(STRINGS "${file}" lines REGEX "^[ \t]*#[ \t]*include[ \t]*[<\"]")
    foreach(line IN LISTS lines)
      if(line MATCHES "include[ \t]*<torch/")
        set(result TRUE)
        break()
      elseif(line MATCHES "include[ \t]*\"([^\"]+)\"")
        set(name "${CMAKE_MATCH_1}")
        set(included "${PROJECT_SOURCE_DIR}/${name}")
        if(NOT EXISTS "${included}")
          set(included "${folder}/${name}")
        endif()
        _foresight_includes_torch("${included}" nested)
        if(nested)
          set(result TRUE)
          break()
        endif()
      endif()
    endforeach()
  endif()
  set_property(GLOBAL PROPERTY "FORESIGHT_TORCH:${file}" ${result})
  set(${out} ${result} PARENT_SCOPE)
endfunction()

# _foresight_targets_in(DIR OUT): every build-system target defined in DIR and below.
function(_foresight_targets_in dir out)
  get_property(targets DIRECTORY "${dir}" PROPERTY BUILDSYSTEM_TARGETS)
  get_property(subdirs DIRECTORY "${dir}" PROPERTY SUBDIRECTORIES)
  foreach(sub IN LISTS subdirs)
    _foresight_targets_in("${sub}" nested)
    list(APPEND targets ${nested})
  endforeach()
  set(${out} ${targets} PARENT_SCOPE)
endfunction()

# foresight_use_torch_pch(): call once, after every target is defined.
function(foresight_use_torch_pch)
  add_library(foresight_torch_pch STATIC ${PROJECT_SOURCE_DIR}/cmake/torch_pch.cc)
  target_link_libraries(foresight_torch_pch PUBLIC ${TORCH_LIBRARIES})
  set_target_properties(foresight_torch_pch PROPERTIES POSITION_INDEPENDENT_CODE ON)
  target_compile_options(foresight_torch_pch PRIVATE ${FORESIGHT_WARNINGS})  # -Wpedantic changes macros
  target_precompile_headers(foresight_torch_pch PRIVATE <torch/torch.h>)

  _foresight_targets_in("${PROJECT_SOURCE_DIR}" targets)
  foreach(target IN LISTS targets)
    get_target_property(type ${target} TYPE)
    if(NOT type MATCHES "^(STATIC_LIBRARY|SHARED_LIBRARY|OBJECT_LIBRARY|EXECUTABLE)$"
       OR target STREQUAL "foresight_torch_pch")
      continue()
    endif()
    get_target_property(sources ${target} SOURCES)
    get_target_property(source_dir ${target} SOURCE_DIR)
    set(torch_free "")
    set(torch_sources "")
    set(uses_torch FALSE)
    foreach(source IN LISTS sources)
      if(NOT source MATCHES "\\.(cc|cpp)$")
        continue()
      endif()
      get_filename_component(path "${source}" ABSOLUTE BASE_DIR "${source_dir}")
      _foresight_includes_torch("${path}" includes_torch)
      if(includes_torch)
        set(uses_torch TRUE)
        list(APPEND torch_sources "${path}")
      else()
        list(APPEND torch_free "${path}")
      endif()
    endforeach()
    if(uses_torch)
      foresight_links_torch(${target} uses_torch)
    endif()
    if(NOT uses_torch)
      continue()
    endif()
    target_precompile_headers(${target} REUSE_FROM foresight_torch_pch)
    target_compile_options(${target} PRIVATE -Winvalid-pch)  # a rejected header becomes a warning
    if(type STREQUAL "EXECUTABLE")
      target_compile_options(${target} PRIVATE -fPIC)  # the PIC property gives executables -fPIE
    else()
      set_target_properties(${target} PROPERTIES POSITION_INDEPENDENT_CODE ON)
    endif()
    if(torch_free)
      set_source_files_properties(${torch_free} DIRECTORY "${source_dir}"
        PROPERTIES SKIP_PRECOMPILE_HEADERS ON)
    endif()
    if(FORESIGHT_UNITY_BUILD AND type STREQUAL "STATIC_LIBRARY" AND NOT source_dir MATCHES "/tests(/|$)")
      _foresight_unity_groups(${target} "${source_dir}" "${torch_sources}" "${torch_free}")
    endif()
  endforeach()
endfunction()

# _foresight_unity_groups(TARGET DIR TORCH_SOURCES TORCH_FREE_SOURCES): builds a LibTorch library
# as unity translation units of one kind each (CMake's UNITY_BUILD_MODE GROUP): LibTorch sources in
# groups of 4, which instantiate LibTorch's templates once per group (three training/gfcs sources
# compiled in 55 s together against 113 s apart), torch-free sources in groups of 8 (CMake gives a
# group the precompiled header too; loading it costs about a second). A kind with one source stays
# alone.
function(_foresight_unity_groups target dir torch_sources torch_free)
  _foresight_assign_groups(torch 4 "${dir}" "${torch_sources}" torch_grouped)
  _foresight_assign_groups(plain 8 "${dir}" "${torch_free}" plain_grouped)
  if(torch_grouped OR plain_grouped)
    set_target_properties(${target} PROPERTIES UNITY_BUILD ON UNITY_BUILD_MODE GROUP)
  endif()
endfunction()

# _foresight_assign_groups(KIND SIZE DIR SOURCES OUT): puts SOURCES (two or more) in UNITY_GROUPs
# KIND_0, KIND_1, ... of SIZE each; OUT tells whether it did.
function(_foresight_assign_groups kind size dir sources out)
  list(LENGTH sources count)
  set(${out} FALSE PARENT_SCOPE)
  if(count LESS 2)
    return()
  endif()
  set(index 0)
  foreach(source IN LISTS sources)
    math(EXPR group "${index} / ${size}")
    set_source_files_properties(${source} DIRECTORY "${dir}" PROPERTIES UNITY_GROUP "${kind}_${group}")
    math(EXPR index "${index} + 1")
  endforeach()
  set(${out} TRUE PARENT_SCOPE)
endfunction()
