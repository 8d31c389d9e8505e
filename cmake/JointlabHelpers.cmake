include(GNUInstallDirs)

# The headers most sources parse (Eigen, fmt and the standard library's containers): precompiled
# once for the libraries (CMakeLists.txt) and once for the fuzzing build (fuzz/CMakeLists.txt).
set(JOINTLAB_PRECOMPILED_HEADERS <Eigen/Dense> <fmt/format.h> <algorithm> <cmath> <filesystem>
    <fstream> <functional> <map> <optional> <string> <vector>)

# Warnings as errors on our own code only (dependencies are SYSTEM includes).
function(jointlab_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Werror)
  if(JOINTLAB_SANITIZE)
    # GCC 12's flow analysis sees through the sanitizers' instrumentation poorly and reports
    # std::regex and std::function internals as maybe uninitialized: kept as a warning here.
    # UBSan stops at its first report, so that a report fails the test instead of scrolling by.
    target_compile_options(${target} PRIVATE -fsanitize=address,undefined -fno-omit-frame-pointer
                                             -fno-sanitize-recover=undefined
                                             -Wno-error=maybe-uninitialized)
    target_link_options(${target} PRIVATE -fsanitize=address,undefined
                                          -fno-sanitize-recover=undefined)
  endif()
endfunction()

# jointlab_add_library(<name> SOURCES ... DEPENDS ... [PRIVATE_DEPENDS ...]
#                      [FOLDER <path>] [INTERNAL_HEADERS ...]):
# one target per folder, exported and aliased as jointlab::<name>. Its headers are
# included as <jointlab/<folder>/<header>.h> in the tree and once installed; every header
# of the folder is installed except the INTERNAL_HEADERS, which only the project's own
# sources include. C++20 is a PUBLIC requirement: the headers use it.
function(jointlab_add_library name)
  cmake_parse_arguments(ARG "" "FOLDER" "SOURCES;DEPENDS;PRIVATE_DEPENDS;INTERNAL_HEADERS" ${ARGN})
  if(NOT ARG_FOLDER)
    set(ARG_FOLDER ${name})
  endif()
  add_library(jointlab_${name} ${ARG_SOURCES})
  add_library(jointlab::${name} ALIAS jointlab_${name})
  set_target_properties(jointlab_${name} PROPERTIES OUTPUT_NAME jointlab_${name}
    EXPORT_NAME ${name} POSITION_INDEPENDENT_CODE ON)
  target_compile_features(jointlab_${name} PUBLIC cxx_std_20)
  target_include_directories(jointlab_${name} PUBLIC
    $<BUILD_INTERFACE:${PROJECT_BINARY_DIR}/include>
    $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
  target_link_libraries(jointlab_${name} PUBLIC ${ARG_DEPENDS} PRIVATE ${ARG_PRIVATE_DEPENDS})
  jointlab_warnings(jointlab_${name})
  target_precompile_headers(jointlab_${name} REUSE_FROM jointlab_lib_pch)
  install(TARGETS jointlab_${name} EXPORT jointlabTargets
    ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR} LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR})
  file(GLOB headers RELATIVE ${CMAKE_CURRENT_SOURCE_DIR} ${CMAKE_CURRENT_SOURCE_DIR}/*.h)
  if(ARG_INTERNAL_HEADERS)
    list(REMOVE_ITEM headers ${ARG_INTERNAL_HEADERS})
  endif()
  install(FILES ${headers} DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/jointlab/${ARG_FOLDER})
endfunction()

# The compile options of a test program: our warnings, and its own code at -O1.
function(jointlab_test_options name)
  jointlab_warnings(${name})
  # A test program's own code drives the library (compiled as configured) on small inputs:
  # at -O1 it compiles in two thirds of -O3's time (modal/ringdown_test.cc 8.7 s against
  # 12.6 s), and its 72 programs were most of CI's build. GCC 12's maybe-uninitialized
  # analysis at -O1 reports Eigen's fixed-size temporaries (correlate/mac_test.cc), which -O3
  # does not: that one warning is off there.
  if(CMAKE_BUILD_TYPE MATCHES "^(Release|RelWithDebInfo)$")
    target_compile_options(${name} PRIVATE -O1 -Wno-maybe-uninitialized)
  endif()
endfunction()

# jointlab_add_test(<name> <source> [libraries...]): one GoogleTest program,
# registered with ctest test by test.
function(jointlab_add_test name source)
  if(NOT JOINTLAB_BUILD_TESTS)
    return()
  endif()
  add_executable(${name} ${source})
  target_link_libraries(${name} PRIVATE ${ARGN} jointlab::testing GTest::gtest_main)
  jointlab_test_options(${name})
  target_precompile_headers(${name} REUSE_FROM jointlab_test_pch)
  set_target_properties(${name} PROPERTIES RUNTIME_OUTPUT_DIRECTORY ${PROJECT_BINARY_DIR}/tests)
  set(env "JOINTLAB_SOURCE_DIR=${PROJECT_SOURCE_DIR};JOINTLAB_BINARY_DIR=${PROJECT_BINARY_DIR}")
  if(JOINTLAB_SANITIZE)  # leaks inside third-party libraries (fontconfig under PLplot) only
    # print_suppressions=0: the statistics would add lines to the commands' one-line errors.
    list(APPEND env "LSAN_OPTIONS=suppressions=${PROJECT_SOURCE_DIR}/fuzz/lsan.supp:print_suppressions=0")
  endif()
  gtest_discover_tests(${name} WORKING_DIRECTORY ${PROJECT_BINARY_DIR} DISCOVERY_TIMEOUT 60)
  # The environment is set by a script ctest reads after the discovered tests. Given to
  # gtest_discover_tests(PROPERTIES ENVIRONMENT ...), the list is split at its ';' on the way
  # to the generated file (CMake 3.25), and only the first variable reaches the tests.
  # Under the sanitizers a test runs 10 to 20 times slower: the longest (the five-sensor
  # linear update, 30 s) took 272 s alone and ran past ctest's 300 s beside the Python test.
  set(timeout "")
  if(JOINTLAB_SANITIZE)
    set(timeout " TIMEOUT 900")
  endif()
  set(env_script "${CMAKE_CURRENT_BINARY_DIR}/${name}_environment.cmake")
  file(WRITE "${env_script}"
    "if(${name}_TESTS)\n"
    "  set_tests_properties(\${${name}_TESTS} PROPERTIES ENVIRONMENT [==[${env}]==]${timeout})\n"
    "endif()\n")
  set_property(DIRECTORY APPEND PROPERTY TEST_INCLUDE_FILES "${env_script}")
endfunction()
