target_sources(modestack PRIVATE
  ${CMAKE_CURRENT_LIST_DIR}/main.cpp
  ${CMAKE_CURRENT_LIST_DIR}/command_line.cpp
  ${CMAKE_CURRENT_LIST_DIR}/run_context.cpp
  ${CMAKE_CURRENT_LIST_DIR}/cmd_info.cpp
  ${CMAKE_CURRENT_LIST_DIR}/cmd_denoise.cpp
  ${CMAKE_CURRENT_LIST_DIR}/cmd_render.cpp
  ${CMAKE_CURRENT_LIST_DIR}/cmd_refine.cpp
  ${CMAKE_CURRENT_LIST_DIR}/cmd_run.cpp
  ${CMAKE_CURRENT_LIST_DIR}/cmd_compare.cpp
  ${CMAKE_CURRENT_LIST_DIR}/sequence_adapters.cpp
  ${CMAKE_CURRENT_LIST_DIR}/color_adapters.cpp
  ${CMAKE_CURRENT_LIST_DIR}/memory_budget.cpp
  ${CMAKE_CURRENT_LIST_DIR}/method_options.cpp
  ${CMAKE_CURRENT_LIST_DIR}/option_values.cpp)
