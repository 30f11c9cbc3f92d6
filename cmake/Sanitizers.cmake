# Sanitizer and fuzzing builds (README, "Sanitizers and fuzzing").
#   -DMCRECON_SANITIZE=address,undefined   every target (core, CLI, tests, plugin, Python module)
#                                          built with those sanitizers, -O1 -g; tests run under them
#   -DMCRECON_FUZZ=ON                      clang only: adds fuzzer-no-link coverage to the same build
#                                          and the libFuzzer targets of fuzz/ (implies address,undefined)
# Use a build directory of its own per configuration (ccache keys on the flags, but the
# compiler choice is fixed per build directory).
set(MCRECON_SANITIZE "" CACHE STRING "Comma-separated sanitizers for every target, e.g. address,undefined")
option(MCRECON_FUZZ "Build the libFuzzer targets in fuzz/ (clang; the core gets fuzzer-no-link)" OFF)

# The environment tests run in (empty in a normal build):
#   OWN      tests that start only programs we built (the CLI): their options
#   FOREIGN  python3 / oiiotool loading our module or plugin: the ASan runtime preloaded, no
#            leak check (python3 and oiiotool do not free everything at exit)
set(MCRECON_SANITIZER_ENV "")
set(MCRECON_SANITIZER_FOREIGN_ENV "")
# For gtest_discover_tests(... ${MCRECON_GTEST_PROPERTIES}): one ENVIRONMENT entry only (it
# splits lists); the executables' own ASan defaults (leak check on) do the rest.
set(MCRECON_GTEST_PROPERTIES "")

# Adds the OWN or FOREIGN environment to every test registered so far in the calling
# directory (call it at the end of a tests CMakeLists.txt). No-op in a normal build.
function(mcrecon_sanitizer_env kind)
  if(kind STREQUAL "OWN")
    set(env ${MCRECON_SANITIZER_ENV})
  elseif(kind STREQUAL "FOREIGN")
    set(env ${MCRECON_SANITIZER_FOREIGN_ENV})
  else()
    message(FATAL_ERROR "mcrecon_sanitizer_env: OWN or FOREIGN, got '${kind}'")
  endif()
  if(NOT env)
    return()
  endif()
  get_property(tests DIRECTORY PROPERTY TESTS)
  foreach(t IN LISTS tests)
    set_property(TEST ${t} APPEND PROPERTY ENVIRONMENT ${env})
  endforeach()
endfunction()

if(MCRECON_FUZZ)
  if(NOT CMAKE_CXX_COMPILER_ID STREQUAL "Clang")
    message(FATAL_ERROR "MCRECON_FUZZ=ON needs clang (libFuzzer): configure a fresh build directory with "
                        "-DCMAKE_CXX_COMPILER=clang++")
  endif()
  if(MCRECON_SANITIZE STREQUAL "")
    set(MCRECON_SANITIZE "address,undefined" CACHE STRING "" FORCE)
  endif()
endif()

if(MCRECON_SANITIZE STREQUAL "")
  return()
endif()

string(REPLACE "," ";" _mcr_san_list "${MCRECON_SANITIZE}")
message(STATUS "mcrecon: sanitizers ${MCRECON_SANITIZE} (MCRECON_FUZZ=${MCRECON_FUZZ})")

# -O1 -g after CMAKE_CXX_FLAGS_<CONFIG> (the last -O wins): quick to build, usable stacks.
add_compile_options(-fsanitize=${MCRECON_SANITIZE} -fno-omit-frame-pointer -O1 -g)
add_link_options(-fsanitize=${MCRECON_SANITIZE})
if("undefined" IN_LIST _mcr_san_list)
  # A UBSan finding ends the process: tests fail instead of printing and passing.
  add_compile_options(-fno-sanitize-recover=undefined)
endif()
if(MCRECON_FUZZ)
  add_compile_options(-fsanitize=fuzzer-no-link)
endif()
# pybind11 would add -flto in Release: not with sanitizers.
set(CMAKE_INTERPROCEDURAL_OPTIMIZATION OFF)

# The ASan runtime a foreign process (python3, oiiotool) must preload to load our module or
# plugin. clang links it statically into executables by default, which then clashes with the
# preloaded copy in the CLI that the Python tests start: link the shared one everywhere.
set(MCRECON_ASAN_RUNTIME "")
if("address" IN_LIST _mcr_san_list)
  if(CMAKE_CXX_COMPILER_ID STREQUAL "Clang")
    execute_process(COMMAND ${CMAKE_CXX_COMPILER} --print-runtime-dir
                    OUTPUT_VARIABLE _mcr_rt_dir OUTPUT_STRIP_TRAILING_WHITESPACE)
    set(MCRECON_ASAN_RUNTIME "${_mcr_rt_dir}/libclang_rt.asan-${CMAKE_SYSTEM_PROCESSOR}.so")
    add_link_options(-shared-libasan "-Wl,-rpath,${_mcr_rt_dir}")
  else()
    execute_process(COMMAND ${CMAKE_CXX_COMPILER} -print-file-name=libasan.so
                    OUTPUT_VARIABLE MCRECON_ASAN_RUNTIME OUTPUT_STRIP_TRAILING_WHITESPACE)
  endif()
  if(NOT EXISTS "${MCRECON_ASAN_RUNTIME}")
    message(FATAL_ERROR "mcrecon: the ASan runtime '${MCRECON_ASAN_RUNTIME}' does not exist")
  endif()
  message(STATUS "mcrecon: ASan runtime for foreign processes: ${MCRECON_ASAN_RUNTIME}")
endif()

find_program(MCRECON_SYMBOLIZER NAMES llvm-symbolizer llvm-symbolizer-14 PATHS /usr/lib/llvm-14/bin)
set(_mcr_sym "")
if(MCRECON_SYMBOLIZER)
  set(_mcr_sym "ASAN_SYMBOLIZER_PATH=${MCRECON_SYMBOLIZER}")
endif()
set(_mcr_ubsan "UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1")
set(MCRECON_GTEST_PROPERTIES PROPERTIES ENVIRONMENT "${_mcr_ubsan}")
set(MCRECON_SANITIZER_ENV "ASAN_OPTIONS=detect_leaks=1" ${_mcr_ubsan} ${_mcr_sym})
# python3 and oiiotool leak by design at exit: no leak check there (nor in the CLI they start).
set(MCRECON_SANITIZER_FOREIGN_ENV "ASAN_OPTIONS=detect_leaks=0" ${_mcr_ubsan} ${_mcr_sym})
if(MCRECON_ASAN_RUNTIME)
  list(APPEND MCRECON_SANITIZER_FOREIGN_ENV "LD_PRELOAD=${MCRECON_ASAN_RUNTIME}")
endif()
