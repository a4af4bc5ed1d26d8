# Sources of core/objectspace: denoising at fixed surface points (moving cameras
# and objects), from the points × frames matrix to the pixels rebuilt from it.
target_sources(modestack_core PRIVATE
  ${CMAKE_CURRENT_LIST_DIR}/leverage.cpp
  ${CMAKE_CURRENT_LIST_DIR}/point_denoise.cpp
  ${CMAKE_CURRENT_LIST_DIR}/point_rebuild.cpp
  ${CMAKE_CURRENT_LIST_DIR}/point_store.cpp
  ${CMAKE_CURRENT_LIST_DIR}/surface_cells.cpp
  ${CMAKE_CURRENT_LIST_DIR}/surface_filter.cpp
  ${CMAKE_CURRENT_LIST_DIR}/surface_kernel.cpp
  ${CMAKE_CURRENT_LIST_DIR}/surface_modes.cpp
  ${CMAKE_CURRENT_LIST_DIR}/surface_neighbours.cpp
  ${CMAKE_CURRENT_LIST_DIR}/surface_noise.cpp
  ${CMAKE_CURRENT_LIST_DIR}/surface_sure.cpp)
