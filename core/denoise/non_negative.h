// `denoise --non-negative`: light is never negative, but a low-rank rebuild can
// dip below zero where a pixel is dark in some frames (a truncated sum of modes
// rings around the true values). This is a projected correction applied to each
// rebuilt sample (one pixel channel over all frames) before it is written:
// `clamp` sets the negative values to the floor; `keep-sum` does the same and
// takes the removed energy back from the positive frames of that sample in
// proportion to their value, so that the sample's temporal sum (its mean
// light) is kept whenever the positive frames hold enough.
#pragma once

#include "core/lowrank/band.h"

#include <cstdint>
#include <string>

namespace modestack::denoise {

/// What --non-negative does.
enum class NonNegativeMode { Off, Clamp, KeepSum };

/// Parses "clamp" or "keep-sum"; throws a usage error naming --non-negative-mode.
NonNegativeMode parse_non_negative_mode(const std::string& name);
/// "off", "clamp" or "keep-sum".
std::string non_negative_mode_name(NonNegativeMode mode);

/// Values the correction changed.
struct NonNegativeCounts {
    std::int64_t clamped = 0; ///< values below the floor, set to it
    std::int64_t scaled = 0;  ///< positive values lowered to keep the sum (keep-sum)
    std::int64_t samples = 0; ///< samples (pixel channels over time) with at least one clamped value

    NonNegativeCounts& operator+=(const NonNegativeCounts& other)
    {
        clamped += other.clamped;
        scaled += other.scaled;
        samples += other.samples;
        return *this;
    }
};

/// Corrects every row of `band` (one sample over band.frames frames) so that no
/// value is below `floor` (0 for linear light; f(0) under --transform). Rows are
/// independent: the result does not depend on the thread count.
NonNegativeCounts make_non_negative(lowrank::MutableBandView band, NonNegativeMode mode, float floor);

/// Sets the `count` values below `floor` to it, unless `mode` is Off: the
/// estimator choice's values (estimator_choice.h) come from the input too, which
/// the correction of the rebuild never saw. Returns how many it changed.
std::int64_t clamp_chosen_values(float* values, std::int64_t count, NonNegativeMode mode, float floor);

} // namespace modestack::denoise
