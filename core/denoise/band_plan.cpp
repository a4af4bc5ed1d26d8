#include "core/denoise/band_plan.h"

#include "core/common/error.h"

#include <fmt/format.h>

#include <algorithm>

namespace modestack::denoise {

std::int64_t bytes_per_band_row(const ShotShape& shape, int modes)
{
    // Input, rebuilt, sigma and sigma's noise power for every frame, plus the
    // spatial coefficients.
    std::int64_t samples = static_cast<std::int64_t>(shape.width) * shape.channels;
    return samples * sizeof(float) * (4 * static_cast<std::int64_t>(shape.frames) + modes);
}

BandPlan plan_bands(const ShotShape& shape, std::int64_t max_memory_bytes, int halo_rows, int modes)
{
    BandPlan plan;
    plan.halo_rows = halo_rows;
    std::int64_t per_row = bytes_per_band_row(shape, modes);
    std::int64_t whole = per_row * shape.height;
    if (whole <= max_memory_bytes) {
        plan.in_memory = true;
        plan.band_rows = shape.height;
        plan.estimated_bytes = whole;
        return plan;
    }
    std::int64_t rows = max_memory_bytes / per_row - 2 * halo_rows;
    rows = rows / kChunkRows * kChunkRows;
    if (rows < kChunkRows)
        throw usage_error(fmt::format("--max-memory {} MiB is too small for {} frames of width {}: a band of {} rows "
                                      "needs {} MiB",
                                      max_memory_bytes >> 20, shape.frames, shape.width, kChunkRows,
                                      (per_row * (kChunkRows + 2 * halo_rows) + (1 << 20) - 1) >> 20));
    plan.band_rows = static_cast<int>(std::min<std::int64_t>(rows, shape.height));
    plan.estimated_bytes = per_row * (plan.band_rows + 2 * halo_rows);
    return plan;
}

}  // namespace modestack::denoise
