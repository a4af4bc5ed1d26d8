target_sources(modestack_io PRIVATE
  ${CMAKE_CURRENT_LIST_DIR}/sequence.cpp)
