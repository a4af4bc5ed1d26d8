# Sources of core/refine (one .h/.cpp pair per concept).
target_sources(modestack_core PRIVATE
  ${CMAKE_CURRENT_LIST_DIR}/selection.cpp
  ${CMAKE_CURRENT_LIST_DIR}/feather.cpp
  ${CMAKE_CURRENT_LIST_DIR}/blend.cpp
  ${CMAKE_CURRENT_LIST_DIR}/equal_quality.cpp
  ${CMAKE_CURRENT_LIST_DIR}/refine_frame.cpp
  ${CMAKE_CURRENT_LIST_DIR}/crop_windows.cpp)
