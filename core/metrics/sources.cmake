# Sources of core/metrics (one .h/.cpp pair per concept).
target_sources(modestack_core PRIVATE
  ${CMAKE_CURRENT_LIST_DIR}/image_error.cpp
  ${CMAKE_CURRENT_LIST_DIR}/sequence_comparison.cpp
  ${CMAKE_CURRENT_LIST_DIR}/verdict.cpp)
