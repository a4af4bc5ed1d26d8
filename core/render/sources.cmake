# Sources of core/render (one .h/.cpp pair per concept).
target_link_libraries(modestack_core PRIVATE embree)
target_sources(modestack_core PRIVATE
  ${CMAKE_CURRENT_LIST_DIR}/sampler.cpp
  ${CMAKE_CURRENT_LIST_DIR}/ray_scene.cpp
  ${CMAKE_CURRENT_LIST_DIR}/path_tracer.cpp
  ${CMAKE_CURRENT_LIST_DIR}/aov.cpp
  ${CMAKE_CURRENT_LIST_DIR}/render.cpp
  ${CMAKE_CURRENT_LIST_DIR}/surface_points.cpp
  ${CMAKE_CURRENT_LIST_DIR}/point_bake.cpp)
