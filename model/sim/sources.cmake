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
