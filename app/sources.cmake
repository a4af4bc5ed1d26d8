target_sources(modestack PRIVATE
  ${CMAKE_CURRENT_LIST_DIR}/main.cpp
  ${CMAKE_CURRENT_LIST_DIR}/command_line.cpp
  ${CMAKE_CURRENT_LIST_DIR}/run_context.cpp
  ${CMAKE_CURRENT_LIST_DIR}/cmd_info.cpp)
