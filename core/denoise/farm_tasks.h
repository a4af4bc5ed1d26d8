// The farm tasks of a denoise (stage_task.h says what each computes and why the
// bits equal one run's): each runs one pass over its share of the shot, from
// the typed results of the tasks before it, and returns its own with the report
// of what it did. io/stage_files.h carries the results between machines.
#pragma once

#include "core/denoise/passes.h"

#include <vector>

namespace modestack::denoise {

/// A task's result and its report (for the JSON summary).
template <typename Output> struct TaskResult {
    Output output;
    Report report;
};

/// Pass 1 over rows [row_begin, row_end) (whole blocks of kStageBlockRows rows).
TaskResult<Statistics> statistics_task(const PassContext& context, int row_begin, int row_end);

/// Every block of the shot (`shot`: rows 0 to the height, blocks in row order)
/// merged as one run merges them, and the temporal modes and N.
TaskResult<SolvedSums> solve_task(const PassContext& context, const Statistics& shot);

/// The mode filter's survey of rows [row_begin, row_end).
TaskResult<SurveyRows> survey_task(const PassContext& context, const SolvedSums& solved, int row_begin,
                                   int row_end);

/// Pass 2 over rows [row_begin, row_end) up to the frames: their mode images.
/// `survey`: every row's sums (empty without the mode filter).
TaskResult<ModeImages> modes_task(const PassContext& context, const SolvedSums& solved,
                                  const SurveyRows& survey, int row_begin, int row_end);

/// The outputs of the frames the sink writes, each read alone and rebuilt from
/// every band's mode images (`bands`, row order).
Report write_task(const PassContext& context, const SolvedSums& solved, const SurveyRows& survey,
                  const std::vector<ModeImages>& bands);

} // namespace modestack::denoise
