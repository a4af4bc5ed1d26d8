// One farm task's share of a denoise (issue 11; README, "Farm jobs and MPI"):
// the engine's run split at the points where everything it carries is small.
//   Statistics: pass 1 over a range of rows → the Gram sums of each fixed block
//               of kStageBlockRows rows in it, the input's roughness per block
//               and frame, and the outlier counts;
//   Solve:      every block's sums, merged in block order (the order one run
//               merges them in, so the bits are the same) → the temporal modes
//               and each frame's noise factor;
//   Survey:     the modes → the mode filter's SURE sums of each image row of a
//               range of rows (one run adds the same rows up in the same order,
//               so every task after it chooses the same filters and N);
//   Modes:      what Solve and Survey found → pass 2 over a range of rows, up to the
//               frames: the coefficient images (the spatial modes scaled by
//               σ, unfiltered for sigma's residual and as the outputs are
//               rebuilt from them), sigma's noise level per sample, the noise
//               each filtered mode keeps per pixel, and the cleaned input values
//               that differ from the files (NaN/Inf, fireflies);
//   Write:      what Solve and Survey found and every band's modes → the outputs of the
//               frames the task owns, reading only those frames.
// farm_tasks.h runs each task on its typed inputs and returns its typed result;
// io/stage_files.h moves them between machines as files.
#pragma once

#include "core/denoise/repeating_noise.h"
#include "core/lowrank/bias_prior.h"
#include "core/lowrank/gram.h"
#include "core/lowrank/outliers.h"

#include <cstdint>
#include <vector>

namespace modestack::denoise {

/// Image rows per block of Gram sums. One run merges the blocks in the same
/// order as a farm's solve task, whatever its bands, so a statistics task must
/// start on a block boundary.
inline constexpr int kStageBlockRows = 64;

enum class Stage { Statistics, Solve, Survey, Modes, Write };

/// "stats", "solve", "survey", "modes", "write".
const char* stage_name(Stage stage);

/// Blocks of kStageBlockRows rows in `rows` image rows (the last one may be short).
inline int stage_blocks(int rows) { return (rows + kStageBlockRows - 1) / kStageBlockRows; }

/// Throws a usage error unless rows [row_begin, row_end) of a shot of `height`
/// rows are whole blocks: what a statistics task may cover.
void check_statistics_rows(int row_begin, int row_end, int height);

/// Throws a usage error unless rows [row_begin, row_end) lie in a shot of
/// `height` rows: what a survey or modes task may cover.
void check_task_rows(int row_begin, int row_end, int height);

/// A modes task's result (the mode images) for rows [row_begin, row_end) of the shot: everything a
/// write task needs of those rows besides the frames it writes. Samples are
/// [row][x][channel] from the band's first row; images of several modes follow
/// each other.
struct ModeImages {
    int row_begin = 0;
    int row_end = 0;
    int residual_modes = 0;  ///< N: unfiltered coefficients, for sigma's residual
    int output_modes = 0;    ///< coefficients the outputs are rebuilt from (0: the residual ones)
    int gain_modes = 0;      ///< per-pixel kept-noise gains (0: no mode filter)
    std::vector<float> residual;        ///< residual_modes images
    std::vector<float> output;          ///< output_modes images (filtered, shrunk)
    std::vector<float> noise_variance;  ///< sigma's s² per sample (lowrank/confidence.h)
    std::vector<float> gains;           ///< gain_modes images of one value per pixel
    std::vector<lowrank::BiasPosterior> bias; ///< sigma's bias posterior per row (lowrank/bias_prior.h)
    /// An input value that outlier cleaning changed: frame, sample in the band, value.
    struct Patch {
        int frame = 0;
        std::int64_t sample = 0;
        float value = 0;
    };
    std::vector<Patch> patches;  ///< in frame order, then sample order
};

/// Pass 1 over rows [row_begin, row_end): the Gram sums of each block of
/// kStageBlockRows rows, in row order, and what cleaning found. A statistics
/// task's result; the solve's input is every block of the shot.
struct Statistics {
    int row_begin = 0;
    int row_end = 0;
    std::vector<lowrank::GramAccumulator> blocks;
    lowrank::OutlierCounts outliers;
    std::vector<double> roughness;         ///< the input's per block and frame (frame_noise.h)
    std::vector<double> cleaned_roughness; ///< Σ d² of the cleaned input, the same way (frame_weighting.h)
};

/// The solve task's result: every block merged in row order, and the shot's outlier counts.
struct SolvedSums {
    lowrank::GramAccumulator gram{1};
    lowrank::OutlierCounts outliers;
    std::vector<double> frame_noise_factors; ///< per frame (frame_noise.h)
    std::vector<double>
        frame_scale_factors; ///< per frame, of the cleaned input: the modes' (frame_weighting.h)
    RepeatingNoise repeating;                ///< measured by the solve task (repeating_noise.h)
};

/// A survey task's result: the mode filter's survey sums of image rows
/// [row_begin, row_end) (SureSurvey::row_sums). Later tasks take every row's.
struct SurveyRows {
    int row_begin = 0;
    int row_end = 0;
    std::vector<std::vector<double>> sums;
};

}  // namespace modestack::denoise
