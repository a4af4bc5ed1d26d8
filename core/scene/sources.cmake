# Sources of core/scene (one .h/.cpp pair per concept).
target_sources(modestack_core PRIVATE
  ${CMAKE_CURRENT_LIST_DIR}/scene.cpp
  ${CMAKE_CURRENT_LIST_DIR}/builtin_scenes.cpp)
