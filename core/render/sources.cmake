# Sources of core/render (one .h/.cpp pair per concept).
target_link_libraries(modestack_core PRIVATE embree)
