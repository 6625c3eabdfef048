# LibTorch's headers, precompiled once for the whole build. <torch/torch.h> takes GCC ~15 s to
# parse, before any of a file's own code; ~70 of the build's files include it. Here one object
# library (retarget_torch_pch) compiles <torch/torch.h> and <torch/script.h> into a precompiled
# header, and the targets whose sources use LibTorch reuse it (retarget_torch_pch(<target>)):
# their LibTorch files load the parsed headers instead of parsing them again.
#
# A precompiled header is only used with the flags it was made with (otherwise GCC parses the
# headers again, silently but for -Winvalid-pch, which CMake adds), so the owner links what its
# users link for their flags: LibTorch's defines and ABI, OpenMP, fmt's and core's defines.
# Targets built without OpenMP (core and its tests: one LibTorch file each) parse the headers
# themselves. The fuzz build (clang, sanitizers) turns RETARGET_PCH off.
#
# The tests are compiled with RETARGET_TEST_OPTIMISATION (-O1 in a Release build; the code they
# test stays at -O3): most of a test file's time is GCC generating and optimising the code of
# every Catch assertion and inlined LibTorch call, which -O1 does in ~40% less time (a batch of
# the inference tests: 32 s -> 20 s). Their LibTorch files get a second precompiled header made
# with that flag (retarget_test_torch_pch), since the first one's -O3 would not be used.
# Empty (no second header) in other build types or with RETARGET_FAST_TEST_BUILD off.
set(RETARGET_TEST_OPTIMISATION "")
if(RETARGET_FAST_TEST_BUILD AND CMAKE_BUILD_TYPE STREQUAL "Release")
  set(RETARGET_TEST_OPTIMISATION -O1)
endif()
# An object library `name` that owns a LibTorch precompiled header made with `ARGN` added to
# the flags.
function(retarget_add_torch_pch name)
  add_library(${name} OBJECT ${CMAKE_CURRENT_FUNCTION_LIST_DIR}/torch_pch.cpp)
  target_link_libraries(${name} PRIVATE retarget_core Eigen3::Eigen OpenMP::OpenMP_CXX ${TORCH_LIBRARIES})
  target_compile_options(${name} PRIVATE ${ARGN})
  target_precompile_headers(${name} PRIVATE <torch/torch.h> <torch/script.h>)
endfunction()
if(RETARGET_PCH)
  retarget_add_torch_pch(retarget_torch_pch)
  if(RETARGET_TEST_OPTIMISATION)
    retarget_add_torch_pch(retarget_test_torch_pch ${RETARGET_TEST_OPTIMISATION})
  endif()
endif()

# Sets `result` to ON when `file` includes <torch/...> or <ATen/...>, itself or through the
# project's own headers (quoted includes, looked up next to the file, at the top of the tree and
# in tests/). Remembered per file for the configure run.
function(retarget_includes_torch file result)
  get_property(known GLOBAL PROPERTY "retarget_includes_torch:${file}" SET)
  if(known)
    get_property(value GLOBAL PROPERTY "retarget_includes_torch:${file}")
    set(${result} ${value} PARENT_SCOPE)
    return()
  endif()
  set_property(GLOBAL PROPERTY "retarget_includes_torch:${file}" OFF)  # an include cycle reads as no
  file(STRINGS ${file} includes REGEX "^[ \t]*#[ \t]*include[ \t]*[<\"]")
  get_filename_component(dir ${file} DIRECTORY)
  set(value OFF)
  foreach(line IN LISTS includes)
    if(line MATCHES "<(torch|ATen)/")
      set(value ON)
    elseif(line MATCHES "\"([^\"]+)\"")
      set(header ${CMAKE_MATCH_1})
      foreach(candidate ${dir}/${header} ${PROJECT_SOURCE_DIR}/${header} ${PROJECT_SOURCE_DIR}/tests/${header})
        if(EXISTS ${candidate})
          get_filename_component(candidate ${candidate} ABSOLUTE)
          retarget_includes_torch(${candidate} value)
          break()
        endif()
      endforeach()
    endif()
    if(value)
      break()
    endif()
  endforeach()
  set_property(GLOBAL PROPERTY "retarget_includes_torch:${file}" ${value})
  set(${result} ${value} PARENT_SCOPE)
endfunction()

# Compiles `target`'s LibTorch files with the shared precompiled header (`retarget_torch_pch(t
# TEST)`: the tests' one, for targets compiled with RETARGET_TEST_OPTIMISATION); a target without
# any is left alone. Its other files are left out (SKIP_PRECOMPILE_HEADERS): with LibTorch's headers
# forced in, GCC instantiates their templates in every file, which made a file that does not use
# LibTorch ~1.8x slower. Call it in the target's folder, after the target's sources are given.
# Which files use LibTorch is read when CMake configures; after changing that, re-run CMake (a
# stale answer costs only time).
function(retarget_torch_pch target)
  if(NOT RETARGET_PCH)
    return()
  endif()
  get_target_property(sources ${target} SOURCES)
  get_target_property(source_dir ${target} SOURCE_DIR)
  set(with_torch "")
  set(without_torch "")
  foreach(source IN LISTS sources)
    get_filename_component(path ${source} ABSOLUTE BASE_DIR ${source_dir})
    if(path MATCHES "\\.cpp$" AND EXISTS ${path})
      retarget_includes_torch(${path} uses_torch)
      if(uses_torch)
        list(APPEND with_torch ${source})
      else()
        list(APPEND without_torch ${source})
      endif()
    endif()
  endforeach()
  if(with_torch)
    if("TEST" IN_LIST ARGN AND TARGET retarget_test_torch_pch)
      target_precompile_headers(${target} REUSE_FROM retarget_test_torch_pch)
    else()
      target_precompile_headers(${target} REUSE_FROM retarget_torch_pch)
    endif()
    if(without_torch)
      set_source_files_properties(${without_torch} PROPERTIES SKIP_PRECOMPILE_HEADERS ON)
    endif()
  endif()
endfunction()
