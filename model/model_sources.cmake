# Model files, Iwan joints, linear modes and QSMA (issue 3).
list(APPEND JOINTLAB_MODEL_SOURCES
  ${CMAKE_CURRENT_LIST_DIR}/iwan.cc
  ${CMAKE_CURRENT_LIST_DIR}/sparse_cholesky.cc
  ${CMAKE_CURRENT_LIST_DIR}/sparse_eigen.cc
  ${CMAKE_CURRENT_LIST_DIR}/iwan_hysteresis.cc
  ${CMAKE_CURRENT_LIST_DIR}/iwan_cycle.cc
  ${CMAKE_CURRENT_LIST_DIR}/model_file.cc
  ${CMAKE_CURRENT_LIST_DIR}/linear_modes.cc
  ${CMAKE_CURRENT_LIST_DIR}/joint_condensation.cc
  ${CMAKE_CURRENT_LIST_DIR}/iwan_set_model.cc
  ${CMAKE_CURRENT_LIST_DIR}/qsma.cc
  ${CMAKE_CURRENT_LIST_DIR}/qsma_output.cc
)
list(APPEND JOINTLAB_MODEL_TESTS
  ${CMAKE_CURRENT_LIST_DIR}/iwan_test.cc
  ${CMAKE_CURRENT_LIST_DIR}/iwan_hysteresis_test.cc
  ${CMAKE_CURRENT_LIST_DIR}/iwan_cycle_test.cc
  ${CMAKE_CURRENT_LIST_DIR}/model_file_test.cc
  ${CMAKE_CURRENT_LIST_DIR}/linear_modes_test.cc
  ${CMAKE_CURRENT_LIST_DIR}/qsma_test.cc
  ${CMAKE_CURRENT_LIST_DIR}/iwan_set_model_test.cc
  ${CMAKE_CURRENT_LIST_DIR}/model_commands_test.cc
)
