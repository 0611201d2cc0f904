# Adds samples/common (blvd_sample_logs, blvd_sample_png) once, from whichever
# sample asks first: in-tree samples/CMakeLists.txt has added it already.
if(NOT TARGET blvd_sample_logs)
  add_subdirectory(${CMAKE_CURRENT_LIST_DIR} ${CMAKE_BINARY_DIR}/samples-common)
endif()
