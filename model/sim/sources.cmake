# Time simulation of the jointed model: exact Iwan memory for implicit integration,
# Newmark integration condensed to the joint coordinates, impact ring-downs written as
# test records. Included by model/CMakeLists.txt.
list(APPEND JOINTLAB_MODEL_SOURCES
  ${CMAKE_CURRENT_SOURCE_DIR}/sim/iwan_history.cc
  ${CMAKE_CURRENT_SOURCE_DIR}/sim/ringdown_simulation.cc
  ${CMAKE_CURRENT_SOURCE_DIR}/sim/simulated_record.cc)
list(APPEND JOINTLAB_MODEL_TESTS
  ${CMAKE_CURRENT_SOURCE_DIR}/sim/iwan_history_test.cc
  ${CMAKE_CURRENT_SOURCE_DIR}/sim/ringdown_simulation_test.cc
  ${CMAKE_CURRENT_SOURCE_DIR}/sim/simulated_record_test.cc)
# End to end: a simulated ring-down through the test-side pipeline (needs jointlab::modal).
jointlab_add_test(model_simulate_process_test ${CMAKE_CURRENT_SOURCE_DIR}/sim/simulate_process_test.cc
  jointlab::model jointlab::modal fmt::fmt)
# The jointlab simulate command, run as a program.
jointlab_add_test(model_simulate_cli_test ${CMAKE_CURRENT_SOURCE_DIR}/sim/simulate_cli_test.cc
  jointlab::data fmt::fmt)
if(TARGET model_simulate_cli_test)
  add_dependencies(model_simulate_cli_test jointlab)
endif()
