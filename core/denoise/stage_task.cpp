#include "core/denoise/stage_task.h"

#include "core/common/error.h"

#include <fmt/format.h>

namespace modestack::denoise {

const char* stage_name(Stage stage)
{
    switch (stage) {
    case Stage::Statistics: return "stats";
    case Stage::Solve: return "solve";
    case Stage::Survey: return "survey";
    case Stage::Modes: return "modes";
    default: return "write";
    }
}

void check_statistics_rows(int row_begin, int row_end, int height)
{
    if (row_begin < 0 || row_begin >= row_end || row_end > height || row_begin % kStageBlockRows != 0 ||
        (row_end % kStageBlockRows != 0 && row_end != height))
        throw usage_error(fmt::format("--rows {}-{}: a statistics task covers whole blocks of {} rows of the shot's "
                                      "0-{} (Y0 a multiple of {}, Y1 + 1 a multiple or {})",
                                      row_begin, row_end - 1, kStageBlockRows, height - 1, kStageBlockRows, height));
}

void check_task_rows(int row_begin, int row_end, int height)
{
    if (row_begin < 0 || row_begin >= row_end || row_end > height)
        throw usage_error(fmt::format("--rows {}-{}: the shot has rows 0-{}", row_begin, row_end - 1, height - 1));
}

}  // namespace modestack::denoise
