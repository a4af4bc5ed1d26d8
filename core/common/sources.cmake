target_sources(modestack_core PRIVATE ${CMAKE_CURRENT_LIST_DIR}/error.cpp ${CMAKE_CURRENT_LIST_DIR}/progress.cpp)
