target_sources(modestack_core PRIVATE
  ${CMAKE_CURRENT_LIST_DIR}/band_plan.cpp
  ${CMAKE_CURRENT_LIST_DIR}/block_gram.cpp
  ${CMAKE_CURRENT_LIST_DIR}/engine.cpp
  ${CMAKE_CURRENT_LIST_DIR}/estimator_choice.cpp
  ${CMAKE_CURRENT_LIST_DIR}/feature_guide.cpp
  ${CMAKE_CURRENT_LIST_DIR}/frame_noise.cpp
  ${CMAKE_CURRENT_LIST_DIR}/frame_weighting.cpp
  ${CMAKE_CURRENT_LIST_DIR}/filter_weights.cpp
  ${CMAKE_CURRENT_LIST_DIR}/guided_filter.cpp
  ${CMAKE_CURRENT_LIST_DIR}/mode_filter.cpp
  ${CMAKE_CURRENT_LIST_DIR}/non_local_means.cpp)
target_sources(modestack_core PRIVATE
  ${CMAKE_CURRENT_LIST_DIR}/non_negative.cpp
  ${CMAKE_CURRENT_LIST_DIR}/rank_map.cpp
  ${CMAKE_CURRENT_LIST_DIR}/repeating_noise.cpp
  ${CMAKE_CURRENT_LIST_DIR}/segments.cpp
  ${CMAKE_CURRENT_LIST_DIR}/stage_modes.cpp
  ${CMAKE_CURRENT_LIST_DIR}/stage_task.cpp
  ${CMAKE_CURRENT_LIST_DIR}/temporal_misfit.cpp
  ${CMAKE_CURRENT_LIST_DIR}/temporal_spread.cpp
  ${CMAKE_CURRENT_LIST_DIR}/training.cpp
  ${CMAKE_CURRENT_LIST_DIR}/transform.cpp
  ${CMAKE_CURRENT_LIST_DIR}/weight_smoothing.cpp
  ${CMAKE_CURRENT_LIST_DIR}/whitening.cpp)
# The filter weights' exp clamps with a compare-and-select, which GCC evaluates on
# every vector lane only without trapping maths (floating-point exceptions are
# never enabled here; each operation still rounds as IEEE says). Not project-wide:
# it made row_median's partition loop 1.5x slower.
set_source_files_properties(
  ${CMAKE_CURRENT_LIST_DIR}/filter_weights.cpp
  ${CMAKE_CURRENT_LIST_DIR}/guided_filter.cpp
  PROPERTIES COMPILE_OPTIONS -fno-trapping-math)
target_sources(modestack_core PRIVATE
  ${CMAKE_CURRENT_LIST_DIR}/band_rebuild.cpp
  ${CMAKE_CURRENT_LIST_DIR}/farm_tasks.cpp
  ${CMAKE_CURRENT_LIST_DIR}/layer_runs.cpp
  ${CMAKE_CURRENT_LIST_DIR}/layer_views.cpp
  ${CMAKE_CURRENT_LIST_DIR}/rebuild_pass.cpp
  ${CMAKE_CURRENT_LIST_DIR}/run_plan.cpp
  ${CMAKE_CURRENT_LIST_DIR}/shot_stream.cpp
  ${CMAKE_CURRENT_LIST_DIR}/statistics_pass.cpp
  ${CMAKE_CURRENT_LIST_DIR}/survey_pass.cpp)
