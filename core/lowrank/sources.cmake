# Sources of core/lowrank (one .h/.cpp pair per concept).
target_sources(modestack_core PRIVATE
  ${CMAKE_CURRENT_LIST_DIR}/basis.cpp
  ${CMAKE_CURRENT_LIST_DIR}/bias_prior.cpp
  ${CMAKE_CURRENT_LIST_DIR}/confidence.cpp
  ${CMAKE_CURRENT_LIST_DIR}/gram.cpp
  ${CMAKE_CURRENT_LIST_DIR}/outliers.cpp
  ${CMAKE_CURRENT_LIST_DIR}/projection.cpp
  ${CMAKE_CURRENT_LIST_DIR}/randomized_svd.cpp
  ${CMAKE_CURRENT_LIST_DIR}/rank_rule.cpp
  ${CMAKE_CURRENT_LIST_DIR}/row_median.cpp
  ${CMAKE_CURRENT_LIST_DIR}/tiles.cpp)
target_sources(modestack_core PRIVATE ${CMAKE_CURRENT_LIST_DIR}/shrinkage.cpp)
