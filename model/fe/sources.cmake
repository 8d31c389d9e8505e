# Finite elements (Timoshenko beam, MITC4 shell), couplings, sparse eigen-solve,
# Craig-Bampton reduction and the riveted beam generator. Included by model/CMakeLists.txt.
list(APPEND JOINTLAB_MODEL_SOURCES
  ${CMAKE_CURRENT_SOURCE_DIR}/fe/beam_element.cc
  ${CMAKE_CURRENT_SOURCE_DIR}/fe/shell_element.cc
  ${CMAKE_CURRENT_SOURCE_DIR}/fe/couplings.cc
  ${CMAKE_CURRENT_SOURCE_DIR}/fe/strip_mesh.cc
  ${CMAKE_CURRENT_SOURCE_DIR}/fe/fe_model.cc
  ${CMAKE_CURRENT_SOURCE_DIR}/fe/sparse_cholesky.cc
  ${CMAKE_CURRENT_SOURCE_DIR}/fe/sparse_eigen.cc
  ${CMAKE_CURRENT_SOURCE_DIR}/fe/hcb.cc
  ${CMAKE_CURRENT_SOURCE_DIR}/fe/riveted_beam.cc
  ${CMAKE_CURRENT_SOURCE_DIR}/fe/model_builder.cc)
list(APPEND JOINTLAB_MODEL_TESTS
  ${CMAKE_CURRENT_SOURCE_DIR}/fe/beam_element_test.cc
  ${CMAKE_CURRENT_SOURCE_DIR}/fe/shell_element_test.cc
  ${CMAKE_CURRENT_SOURCE_DIR}/fe/couplings_test.cc
  ${CMAKE_CURRENT_SOURCE_DIR}/fe/hcb_test.cc
  ${CMAKE_CURRENT_SOURCE_DIR}/fe/riveted_beam_test.cc
  ${CMAKE_CURRENT_SOURCE_DIR}/fe/model_builder_test.cc)
