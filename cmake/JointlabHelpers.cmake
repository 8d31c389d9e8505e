# Warnings as errors on our own code only (dependencies are SYSTEM includes).
function(jointlab_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Werror)
  if(JOINTLAB_SANITIZE)
    target_compile_options(${target} PRIVATE -fsanitize=address,undefined -fno-omit-frame-pointer)
    target_link_options(${target} PRIVATE -fsanitize=address,undefined)
  endif()
endfunction()

# jointlab_add_library(<folder> SOURCES ... DEPENDS ...): one target per folder,
# alias jointlab::<folder>, headers installed under include/jointlab/<folder>.
function(jointlab_add_library name)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPENDS;PRIVATE_DEPENDS" ${ARGN})
  add_library(jointlab_${name} ${ARG_SOURCES})
  add_library(jointlab::${name} ALIAS jointlab_${name})
  set_target_properties(jointlab_${name} PROPERTIES OUTPUT_NAME jointlab_${name}
    POSITION_INDEPENDENT_CODE ON)
  target_include_directories(jointlab_${name} PUBLIC
    $<BUILD_INTERFACE:${CMAKE_BINARY_DIR}/include>
    $<INSTALL_INTERFACE:include>)
  target_link_libraries(jointlab_${name} PUBLIC ${ARG_DEPENDS} PRIVATE ${ARG_PRIVATE_DEPENDS})
  jointlab_warnings(jointlab_${name})
  install(TARGETS jointlab_${name} EXPORT jointlabTargets
    ARCHIVE DESTINATION lib LIBRARY DESTINATION lib)
  file(GLOB headers RELATIVE ${CMAKE_CURRENT_SOURCE_DIR} ${CMAKE_CURRENT_SOURCE_DIR}/*.h)
  install(FILES ${headers} DESTINATION include/jointlab/${name})
endfunction()

# jointlab_add_test(<name> <source> [libraries...]): one GoogleTest program,
# registered with ctest test by test.
function(jointlab_add_test name source)
  if(NOT JOINTLAB_BUILD_TESTS)
    return()
  endif()
  add_executable(${name} ${source})
  target_link_libraries(${name} PRIVATE ${ARGN} jointlab::testing GTest::gtest_main)
  jointlab_warnings(${name})
  set_target_properties(${name} PROPERTIES RUNTIME_OUTPUT_DIRECTORY ${CMAKE_BINARY_DIR}/tests)
  set(env "JOINTLAB_SOURCE_DIR=${CMAKE_SOURCE_DIR};JOINTLAB_BINARY_DIR=${CMAKE_BINARY_DIR}")
  if(JOINTLAB_SANITIZE)  # leaks inside third-party libraries (fontconfig under PLplot) only
    list(APPEND env "LSAN_OPTIONS=suppressions=${CMAKE_SOURCE_DIR}/fuzz/lsan.supp")
  endif()
  gtest_discover_tests(${name} WORKING_DIRECTORY ${CMAKE_BINARY_DIR}
    PROPERTIES ENVIRONMENT "${env}"
    DISCOVERY_TIMEOUT 60)
endfunction()
