// A farm write task's view of the modes tasks' results (stage_task.h): their
// bands of rows joined into whole-image arrays, and the cleaned input values
// sorted by frame, so that each frame can be rebuilt on its own.
#pragma once

#include "core/denoise/frame_stream.h"
#include "core/denoise/stage_task.h"

#include <vector>

namespace modestack::denoise {

/// ModeImages's arrays for the whole image (samples [y][x][channel] from row 0).
struct ShotModes {
    int residual_modes = 0;
    int output_modes = 0;
    int gain_modes = 0;
    std::vector<float> residual;
    std::vector<float> output;
    std::vector<float> noise_variance;
    std::vector<float> gains;
    std::vector<lowrank::BiasPosterior> bias;             ///< per row
    std::vector<std::vector<ModeImages::Patch>> patches;  ///< per frame, samples counted from row 0
};

/// Joins `bands` (row order, every row of `shape` once, as io/stage_files.h
/// checks) made with the given mode counts; throws an internal error otherwise.
ShotModes join_modes_bands(const std::vector<ModeImages>& bands, const ShotShape& shape, int residual_modes,
                           int output_modes, int gain_modes);

}  // namespace modestack::denoise
