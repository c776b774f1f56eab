cmake_minimum_required(VERSION 3.25)  # a -P script sets no policies (IN_LIST below)
# Run by the `lint`, `lint_flight` and `lint_format` targets: clang-format must leave every tracked
# C++ file unchanged and clang-tidy (rules in .clang-tidy) must pass on every tracked .cpp in the
# compile database (TIDY_SCOPE=all) or on the flight code's (TIDY_SCOPE=flight: the modules under
# fsw/, estimator/, messages/ and drivers/ without their tests, benchmarks and fuzz entry points;
# their headers are checked in every unit that includes them); TIDY_SCOPE=format: no clang-tidy.
execute_process(COMMAND git ls-files "*.cpp" "*.hpp" WORKING_DIRECTORY ${SOURCE_DIR}
                OUTPUT_VARIABLE files OUTPUT_STRIP_TRAILING_WHITESPACE RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "lint: git ls-files failed; run inside the repository")
endif()
string(REPLACE "\n" ";" files "${files}")
execute_process(COMMAND ${CLANG_FORMAT} --dry-run --Werror ${files}
                WORKING_DIRECTORY ${SOURCE_DIR} RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "lint: clang-format found unformatted files (fix: clang-format -i <file>)")
endif()
if(TIDY_SCOPE STREQUAL "format")
  list(LENGTH files nfiles)
  message(STATUS "lint: clang-format clean on ${nfiles} files (clang-tidy: tools/run lint)")
  return()
endif()
# The flight estimator's instantiations: these files hold nothing but an explicit instantiation of
# the filter, whose code is the headers', checked in every file that includes them; checking the
# instantiations once more costs a minute of CI for no finding of their own.
set(instantiation_only
  fsw/app/src/flight_swf.cpp
  fsw/app/src/inertial_flight_swf.cpp)
set(sources)
set(left_out 0)
foreach(f IN LISTS files)
  # tests/layering holds deliberate include violations that must not compile.
  if(f MATCHES "\\.cpp$" AND NOT f MATCHES "^tests/layering/" AND NOT f IN_LIST instantiation_only)
    if(TIDY_SCOPE STREQUAL "all" OR (f MATCHES "^(fsw|estimator|messages|drivers)/" AND
                                     NOT f MATCHES "/(test|bench|fuzz)/"))
      list(APPEND sources ${f})
    else()
      math(EXPR left_out "${left_out} + 1")
    endif()
  endif()
endforeach()
find_program(RUN_CLANG_TIDY NAMES run-clang-tidy run-clang-tidy-14)
if(RUN_CLANG_TIDY)
  # run-clang-tidy takes regexes; anchor each file so only tracked sources are checked.
  set(patterns)
  foreach(f IN LISTS sources)
    string(REPLACE "." "\\." f_re "${f}")
    list(APPEND patterns "${SOURCE_DIR}/${f_re}$")
  endforeach()
  # The compile database is GCC's; clang must not fail on GCC-only warning flags.
  execute_process(COMMAND ${RUN_CLANG_TIDY} -quiet -p ${BUILD_DIR} -clang-tidy-binary ${CLANG_TIDY}
                          -extra-arg=-Wno-unknown-warning-option
                          ${patterns}
                  WORKING_DIRECTORY ${SOURCE_DIR} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
else()
  execute_process(COMMAND ${CLANG_TIDY} --quiet -p ${BUILD_DIR} --extra-arg=-Wno-unknown-warning-option ${sources}
                  WORKING_DIRECTORY ${SOURCE_DIR} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
endif()
if(NOT rc EQUAL 0)
  message("${out}")
  message(FATAL_ERROR "lint: clang-tidy reported problems (see above)")
endif()
list(LENGTH files nfiles)
list(LENGTH sources nsources)
if(TIDY_SCOPE STREQUAL "all")
  message(STATUS "lint: clang-format clean on ${nfiles} files; clang-tidy clean on ${nsources} sources")
else()
  message(STATUS "lint: clang-format clean on ${nfiles} files; clang-tidy clean on ${nsources} "
                 "flight sources (${left_out} ground, test and benchmark units: `lint` does them)")
endif()
