target_sources(modestack PRIVATE ${CMAKE_CURRENT_LIST_DIR}/main.cpp)
