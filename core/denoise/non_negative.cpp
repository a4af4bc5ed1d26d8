#include "core/denoise/non_negative.h"

#include "core/common/error.h"
#include "core/lowrank/tiles.h"

#include <fmt/format.h>

#include <algorithm>
#include <atomic>

namespace modestack::denoise {

NonNegativeMode parse_non_negative_mode(const std::string& name)
{
    if (name == "clamp")
        return NonNegativeMode::Clamp;
    if (name == "keep-sum")
        return NonNegativeMode::KeepSum;
    throw usage_error(fmt::format("--non-negative-mode '{}' is not one of clamp, keep-sum", name));
}

std::string non_negative_mode_name(NonNegativeMode mode)
{
    switch (mode) {
    case NonNegativeMode::Clamp:
        return "clamp";
    case NonNegativeMode::KeepSum:
        return "keep-sum";
    default:
        return "off";
    }
}

NonNegativeCounts make_non_negative(lowrank::MutableBandView band, NonNegativeMode mode, float floor)
{
    NonNegativeCounts total;
    if (mode == NonNegativeMode::Off)
        return total;
    // Integer counts: their sum does not depend on the order the tiles finish in.
    std::atomic<std::int64_t> clamped{0}, scaled{0}, samples{0};
    lowrank::for_each_tile(band.rows, [&](std::int64_t row0, std::int64_t count) {
        std::int64_t tile_clamped = 0, tile_scaled = 0, tile_samples = 0;
        for (std::int64_t i = row0; i < row0 + count; ++i) {
            double below = 0, above = 0;
            int negatives = 0, positives = 0;
            for (int t = 0; t < band.frames; ++t) {
                const double excess = double(band.at(i, t)) - floor;
                if (excess < 0) {
                    below -= excess;
                    ++negatives;
                } else if (excess > 0) {
                    above += excess;
                    ++positives;
                }
            }
            if (negatives == 0)
                continue;
            ++tile_samples;
            tile_clamped += negatives;
            // keep-sum: every positive excess shrinks by the same factor so that the
            // excesses still add up to the old sum (0 when the deficit is larger).
            const double factor =
                mode == NonNegativeMode::KeepSum && above > 0 ? std::max(0.0, above - below) / above : 1.0;
            if (mode == NonNegativeMode::KeepSum)
                tile_scaled += positives;
            for (int t = 0; t < band.frames; ++t) {
                float& value = band.at(i, t);
                const double excess = double(value) - floor;
                if (excess < 0)
                    value = floor;
                else if (factor != 1.0)
                    value = static_cast<float>(floor + excess * factor);
            }
        }
        clamped += tile_clamped;
        scaled += tile_scaled;
        samples += tile_samples;
    });
    total.clamped = clamped;
    total.scaled = scaled;
    total.samples = samples;
    return total;
}

std::int64_t clamp_chosen_values(float* values, std::int64_t count, NonNegativeMode mode, float floor)
{
    if (mode == NonNegativeMode::Off)
        return 0;
    std::int64_t changed = 0;
    for (std::int64_t i = 0; i < count; ++i)
        if (values[i] < floor)
            values[i] = floor, ++changed;
    return changed;
}

} // namespace modestack::denoise
