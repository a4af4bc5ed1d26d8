// Each frame's noise level as a multiple of the shot's (docs/design.md,
// "Choosing an estimator per pixel"). Sigma's noise level s² is pooled over
// every frame, but a light that moves, switches on or off, or lights a frame by
// a point light alone makes some frames far cleaner than others: in such a
// frame the estimator choice's one-sided test, which asks whether the input
// lies further below the rebuild than noise of level s allows, would wait for
// the noise of the shot's noisiest frames. The level of a frame is the mean
// absolute horizontal high-pass |x − (left + right)/2| of its input as read
// (before firefly cleaning, as the choice judges it; triples with a
// non-finite value skipped): absolute values, not squares, so that a few
// fireflies do not rule it, and along the row only, so that each row's sum is
// made from that row alone. The factor of a frame is its level over the mean
// level of all frames (all 1 when that is 0).
//
// Sums per row, then per block of kStageBlockRows rows, then over the blocks in
// order: the bits do not depend on a run's bands, and a farm's statistics
// tasks hand on their blocks (stage_task.h).
#pragma once

#include "core/lowrank/band.h"

#include <vector>

namespace modestack::denoise {

/// What a row's sum adds up: |d| (the choice's level, a few fireflies do not
/// rule it) or d² (the energy the Gram sums see, of the input cleaned of
/// fireflies: the modes' frame scales, frame_weighting.h).
enum class RowMeasure { Absolute, Squared };

/// Writes, per row r of `band` (`band_rows` image rows of `width` × `channels`
/// samples) and frame t, Σ |d| (or Σ d²), d = x − (left + right)/2, of that row
/// of that frame into row_sums[r * frames + t].
void row_roughness(const lowrank::BandView& band, int width, int channels, int band_rows, double* row_sums,
                   RowMeasure measure = RowMeasure::Absolute);

/// The per-frame sums of each block of kStageBlockRows image rows in rows
/// [row_begin, row_end) (row_begin a block boundary), from their per-row sums
/// (row_sums[(row − row_begin) * frames + t]): [block][frame].
std::vector<double> roughness_blocks(const double* row_sums, int frames, int row_begin, int row_end);

/// Each frame's noise factor from every block's sums of the shot, in row order.
std::vector<double> frame_noise_factors(const std::vector<double>& blocks, int frames);

/// Each frame's noise scale, the root of its energy over the shot's mean, from
/// every block's sums of d² (RowMeasure::Squared) of the cleaned input.
std::vector<double> frame_scale_factors(const std::vector<double>& power_blocks, int frames);

} // namespace modestack::denoise
