# Project-wide target helpers. Every module uses these so that flags and rules live in one place.

# Eigen: header-only. When cross-compiling the find-root is the target sysroot, which does not
# carry Eigen, so point at the host's headers (they are architecture independent).
if(CMAKE_CROSSCOMPILING)
  if(NOT TARGET Eigen3::Eigen)
    add_library(Eigen3::Eigen INTERFACE IMPORTED)
    set_target_properties(Eigen3::Eigen PROPERTIES INTERFACE_INCLUDE_DIRECTORIES /usr/include/eigen3)
  endif()
else()
  find_package(Eigen3 3.4 REQUIRED NO_MODULE)
endif()

set(SWF_FORBIDDEN_HEADERS_DIR ${CMAKE_CURRENT_LIST_DIR}/forbidden_headers)

# Flight code rules (STYLE.md): warnings are errors, no exceptions, no RTTI, never -ffast-math.
# UBSan's vptr check reads the type information of the object's vtable, which -fno-rtti does not
# emit: without RTTI the check can only fail to link or misreport, so it is off where RTTI is.
set(SWF_FLIGHT_FLAGS -Wall -Wextra -Werror -fno-exceptions -fno-rtti -fno-sanitize=vptr)

# swf_flight_library(<name> ALIAS <ns::name> [SOURCES ...] [FP_CONTRACT_OFF] [POLYMORPHIC])
# Declares a flight library. Its own include directory is include/; it may not see the I/O and
# middleware headers (LCM, V4L2, Aravis): a shadow directory answers those includes with #error.
# POLYMORPHIC: the library defines classes with virtual functions, whose vtables it emits without
# type information. Code with RTTI that calls them would vptr-check them (UBSan): "undefined
# reference to typeinfo" when linking, an "invalid vptr" report at run time. Its consumers
# therefore compile without the vptr check; the rest of UBSan stays on.
function(swf_flight_library name)
  cmake_parse_arguments(ARG "FP_CONTRACT_OFF;HEADER_ONLY;POLYMORPHIC" "ALIAS" "SOURCES" ${ARGN})
  if(ARG_HEADER_ONLY)
    add_library(${name} INTERFACE)
    target_include_directories(${name} INTERFACE ${CMAKE_CURRENT_SOURCE_DIR}/include)
  else()
    add_library(${name} STATIC ${ARG_SOURCES})
    target_include_directories(${name} PUBLIC ${CMAKE_CURRENT_SOURCE_DIR}/include)
    swf_apply_flight_rules(${name} ${ARG_FP_CONTRACT_OFF})
  endif()
  if(ARG_POLYMORPHIC)
    target_compile_options(${name} INTERFACE -fno-sanitize=vptr)
  endif()
  add_library(${ARG_ALIAS} ALIAS ${name})
endfunction()

# Applies the flight rules to any target that compiles flight code: the libraries, and with TEST
# their tests (swf_test FLIGHT), which take the warnings but keep exceptions and RTTI.
function(swf_apply_flight_rules target fp_contract_off)
  cmake_parse_arguments(ARG "TEST" "" "" ${ARGN})
  if(ARG_TEST)
    target_compile_options(${target} PRIVATE -Wall -Wextra -Werror)
  else()
    target_compile_options(${target} PRIVATE ${SWF_FLIGHT_FLAGS})
  endif()
  if(fp_contract_off)
    target_compile_options(${target} PRIVATE -ffp-contract=off)
  endif()
  target_include_directories(${target} BEFORE PRIVATE ${SWF_FORBIDDEN_HEADERS_DIR})
endfunction()

# swf_lcm_member_handlers(<target>): for targets that subscribe to LCM with member-function
# handlers (lcm::LCM::subscribe(channel, &Class::Method, object)). LCM's wrapper calls them as
# (subs->handler->*subs->handlerMethod)(...) on its polymorphic subscription object
# (lcm-cpp-impl.hpp, cb_func), and GCC 12 instruments that call's vptr check on a wrong address:
# a false "invalid vptr" report under ASan, a crash without it, for any such call (ten lines
# without LCM reproduce it; clang checks it correctly). The vptr check is off there with GCC only.
function(swf_lcm_member_handlers target)
  if(CMAKE_CXX_COMPILER_ID STREQUAL "GNU")
    target_compile_options(${target} PRIVATE -fno-sanitize=vptr)
  endif()
endfunction()

# swf_test(<name> SOURCES ... LIBS ... [FLIGHT] [FP_CONTRACT_OFF] [LABELS ...] [SHARDS n])
# One GoogleTest executable = one CTest entry, or n entries <name>.shard<i>of<n> that each run a
# GoogleTest shard of it (for long suites, so that ctest -j spreads them over the cores). FLIGHT
# compiles the test under the flight rules so the templates it instantiates are checked against
# them too.
function(swf_test name)
  if(NOT SWF_BUILD_TESTS)
    return()
  endif()
  cmake_parse_arguments(ARG "FLIGHT;FP_CONTRACT_OFF" "TIMEOUT;SHARDS" "SOURCES;LIBS;LABELS" ${ARGN})
  add_executable(${name} ${ARG_SOURCES})
  target_link_libraries(${name} PRIVATE ${ARG_LIBS} GTest::gtest_main)
  if(ARG_FLIGHT)
    swf_apply_flight_rules(${name} "${ARG_FP_CONTRACT_OFF}" TEST)
  endif()
  if(NOT ARG_TIMEOUT)
    set(ARG_TIMEOUT 300)
  endif()
  set(environment "SWF_SHARED_DIR=${PROJECT_SOURCE_DIR}/../shared")
  if(NOT ARG_SHARDS)
    add_test(NAME ${name} COMMAND ${name} --gtest_brief=1
             WORKING_DIRECTORY ${PROJECT_SOURCE_DIR})
    set_tests_properties(${name} PROPERTIES TIMEOUT ${ARG_TIMEOUT} LABELS "${ARG_LABELS}"
                         ENVIRONMENT "${environment}")
  else()
    math(EXPR last "${ARG_SHARDS} - 1")
    foreach(index RANGE ${last})
      math(EXPR shard "${index} + 1")
      set(test_name ${name}.shard${shard}of${ARG_SHARDS})
      add_test(NAME ${test_name} COMMAND ${name} --gtest_brief=1
               WORKING_DIRECTORY ${PROJECT_SOURCE_DIR})
      set_tests_properties(${test_name} PROPERTIES TIMEOUT ${ARG_TIMEOUT} LABELS "${ARG_LABELS}"
        ENVIRONMENT "${environment};GTEST_TOTAL_SHARDS=${ARG_SHARDS};GTEST_SHARD_INDEX=${index}")
    endforeach()
  endif()
  swf_scale_test_timeouts()
endfunction()

# `lint`: clang-format over every tracked C++ file and clang-tidy (.clang-tidy) over every source,
# ground tools and tests included (tools/run lint). `lint_flight`: clang-format over every file
# and clang-tidy over the flight code only (cmake/lint.cmake says which). `lint_format`, CI's:
# clang-format alone. clang-tidy parses and instantiates each unit as a compiler does: the flight
# code alone costs as much CPU as the aarch64 tests, more than CI's 30-minute budget leaves.
function(swf_add_lint_target)
  find_program(CLANG_FORMAT NAMES clang-format)
  find_program(CLANG_TIDY NAMES clang-tidy)
  if(NOT CLANG_FORMAT OR NOT CLANG_TIDY OR CMAKE_CROSSCOMPILING)
    return()
  endif()
  foreach(scope IN ITEMS all flight format)
    if(scope STREQUAL "all")
      set(target lint)
    else()
      set(target lint_${scope})
    endif()
    add_custom_target(${target}
      COMMAND ${CMAKE_COMMAND} -DSOURCE_DIR=${PROJECT_SOURCE_DIR} -DBUILD_DIR=${CMAKE_BINARY_DIR}
              -DCLANG_FORMAT=${CLANG_FORMAT} -DCLANG_TIDY=${CLANG_TIDY} -DTIDY_SCOPE=${scope}
              -P ${PROJECT_SOURCE_DIR}/cmake/lint.cmake
      WORKING_DIRECTORY ${PROJECT_SOURCE_DIR}
      COMMENT "lint (${scope})"
      VERBATIM)
  endforeach()
endfunction()

# swf_fuzz_target(<name> SOURCES ... LIBS ... CORPUS <dir>)
# One decoder's fuzz entry point (LLVMFuzzerTestOneInput in SOURCES). Always builds <name>, a
# replay program over the committed corpus <dir> (seeds and former crashers; a relative <dir> is
# taken from the calling CMakeLists' directory), registered as the CTest entry <name>. With
# SWF_FUZZ=ON and clang it also builds <name>_libfuzzer with -fsanitize=fuzzer,address,undefined
# for the coverage-guided search. Every target is listed as "<name> <absolute corpus dir>" in
# <build>/fuzz_targets.txt, the list `tools/run fuzz` runs.
option(SWF_FUZZ "Build libFuzzer programs (needs clang)" OFF)
function(swf_fuzz_target name)
  if(NOT SWF_BUILD_TESTS)
    return()
  endif()
  cmake_parse_arguments(ARG "" "CORPUS" "SOURCES;LIBS" ${ARGN})
  set(corpus ${ARG_CORPUS})
  if(NOT IS_ABSOLUTE ${corpus})
    if(EXISTS ${CMAKE_CURRENT_SOURCE_DIR}/${corpus})
      set(corpus ${CMAKE_CURRENT_SOURCE_DIR}/${corpus})
    else()
      set(corpus ${PROJECT_SOURCE_DIR}/${corpus})
    endif()
  endif()
  add_executable(${name} ${ARG_SOURCES} ${PROJECT_SOURCE_DIR}/tests/support/src/fuzz_replay_main.cpp)
  target_link_libraries(${name} PRIVATE ${ARG_LIBS})
  add_test(NAME ${name} COMMAND ${name} ${corpus} WORKING_DIRECTORY ${PROJECT_SOURCE_DIR})
  set_tests_properties(${name} PROPERTIES TIMEOUT 300 LABELS fuzz)
  swf_scale_test_timeouts()
  set_property(GLOBAL APPEND PROPERTY SWF_FUZZ_TARGET_LIST "${name} ${corpus}")
  if(SWF_FUZZ AND CMAKE_CXX_COMPILER_ID STREQUAL "Clang")
    add_executable(${name}_libfuzzer ${ARG_SOURCES})
    target_link_libraries(${name}_libfuzzer PRIVATE ${ARG_LIBS})
    target_compile_options(${name}_libfuzzer PRIVATE -fsanitize=fuzzer,address,undefined)
    target_link_options(${name}_libfuzzer PRIVATE -fsanitize=fuzzer,address,undefined)
  endif()
endfunction()

# Time limits are set for the release build. A sanitizer build runs the same tests several times
# slower (ASan + UBSan, the numerical tests the most), so its preset scales every TIMEOUT by
# SWF_TEST_TIMEOUT_SCALE instead of raising the limits of every build. swf_test and
# swf_fuzz_target scale their directory's tests, once all of them are declared (raw add_test
# entries included); a directory with only raw add_test entries calls swf_scale_test_timeouts().
set(SWF_TEST_TIMEOUT_SCALE 1 CACHE STRING "Multiplier for every test's TIMEOUT (sanitizer builds)")

function(swf_scale_test_timeouts)
  get_directory_property(registered SWF_TIMEOUTS_SCALED)
  if(registered OR SWF_TEST_TIMEOUT_SCALE EQUAL 1)
    return()
  endif()
  set_directory_properties(PROPERTIES SWF_TIMEOUTS_SCALED ON)
  cmake_language(DEFER CALL swf_scale_directory_timeouts_now)
endfunction()

function(swf_scale_directory_timeouts_now)
  get_directory_property(tests TESTS)
  foreach(test IN LISTS tests)
    get_test_property(${test} TIMEOUT timeout)
    if(timeout)
      math(EXPR timeout "${timeout} * ${SWF_TEST_TIMEOUT_SCALE}")
      set_tests_properties(${test} PROPERTIES TIMEOUT ${timeout})
    endif()
  endforeach()
endfunction()

# The list of fuzz targets, written once every CMakeLists has declared its own.
function(swf_write_fuzz_target_list)
  get_property(fuzz_targets GLOBAL PROPERTY SWF_FUZZ_TARGET_LIST)
  list(JOIN fuzz_targets "\n" lines)
  file(CONFIGURE OUTPUT ${CMAKE_BINARY_DIR}/fuzz_targets.txt CONTENT "${lines}\n" @ONLY)
endfunction()
cmake_language(DEFER DIRECTORY ${CMAKE_SOURCE_DIR} CALL swf_write_fuzz_target_list)

# Every program of the build (an executable target named swf-*) with its path, one "name=path" a
# line in <build>/swf_programs.txt: the command-line convention test (tests/cli) runs them all, so
# a new program cannot escape it.
function(swf_collect_programs dir out_var)
  set(programs ${${out_var}})
  get_property(targets DIRECTORY ${dir} PROPERTY BUILDSYSTEM_TARGETS)
  foreach(target IN LISTS targets)
    get_target_property(type ${target} TYPE)
    if(type STREQUAL "EXECUTABLE" AND target MATCHES "^swf-")
      list(APPEND programs "${target}=$<TARGET_FILE:${target}>")
    endif()
  endforeach()
  get_property(subdirs DIRECTORY ${dir} PROPERTY SUBDIRECTORIES)
  foreach(subdir IN LISTS subdirs)
    swf_collect_programs(${subdir} programs)
  endforeach()
  set(${out_var} ${programs} PARENT_SCOPE)
endfunction()

function(swf_write_program_list)
  set(programs)
  swf_collect_programs(${CMAKE_SOURCE_DIR} programs)
  list(JOIN programs "\n" lines)
  file(GENERATE OUTPUT ${CMAKE_BINARY_DIR}/swf_programs.txt CONTENT "${lines}\n")
endfunction()
cmake_language(DEFER DIRECTORY ${CMAKE_SOURCE_DIR} CALL swf_write_program_list)
