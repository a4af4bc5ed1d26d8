// One farm task's share of a denoise (issue 11; README, "Farm jobs and MPI"):
// the engine's run split at the points where everything it carries is small.
//   Statistics: pass 1 over a range of rows → the Gram sums of each fixed block
//               of kStageBlockRows rows in it, and the outlier counts;
//   Solve:      every block's sums, merged in block order (the order one run
//               merges them in, so the bits are the same) → the modes, N and,
//               with the mode filter, its survey pass over the whole shot;
//   Write:      what Solve found → pass 2 (the outputs; the app writes only the
//               frames the task owns).
// The task holds the inputs and receives the outputs; app/stage_files.h moves
// them between machines. Settings::stage null is a whole run.
#pragma once

#include "core/lowrank/gram.h"
#include "core/lowrank/outliers.h"

#include <optional>
#include <vector>

namespace modestack::denoise {

/// Image rows per block of Gram sums. One run merges the blocks in the same
/// order as a farm's solve task, whatever its bands, so a statistics task must
/// start on a block boundary.
inline constexpr int kStageBlockRows = 64;

enum class Stage { Statistics, Solve, Write };

/// "stats", "solve", "write".
const char* stage_name(Stage stage);

/// Blocks of kStageBlockRows rows in `rows` image rows (the last one may be short).
inline int stage_blocks(int rows) { return (rows + kStageBlockRows - 1) / kStageBlockRows; }

/// Throws a usage error unless rows [row_begin, row_end) of a shot of `height`
/// rows are whole blocks: what a statistics task may cover.
void check_statistics_rows(int row_begin, int row_end, int height);

struct StageTask {
    Stage stage = Stage::Statistics;
    /// Statistics: rows [row_begin, row_end) (row_begin a multiple of kStageBlockRows).
    int row_begin = 0;
    int row_end = 0;
    /// Statistics output: the sums of each block of its rows, in row order. Solve
    /// input: every block of the shot, in row order.
    std::vector<lowrank::GramAccumulator> gram_blocks;
    /// Solve output, Write input: the blocks merged in row order.
    std::optional<lowrank::GramAccumulator> gram;
    /// Statistics output, Solve and Write input: what pass 1 cleaned.
    lowrank::OutlierCounts outliers;
    /// Solve output, Write input: the mode filter's survey sums per image row
    /// (SureSurvey::row_sums; empty without the mode filter).
    std::vector<std::vector<double>> survey_rows;
};

}  // namespace modestack::denoise
