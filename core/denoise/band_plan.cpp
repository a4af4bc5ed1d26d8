#include "core/denoise/band_plan.h"

#include "core/common/error.h"

#include <fmt/format.h>

#include <algorithm>

namespace modestack::denoise {
namespace {

std::int64_t samples_per_row(const ShotShape& shape) { return static_cast<std::int64_t>(shape.width) * shape.channels; }

std::int64_t mebibytes_rounded_up(std::int64_t bytes) { return (bytes + (1 << 20) - 1) >> 20; }

}  // namespace

std::int64_t input_bytes_per_row(const ShotShape& shape)
{
    return samples_per_row(shape) * static_cast<std::int64_t>(sizeof(float)) * shape.frames;
}

std::int64_t work_bytes_per_row(const ShotShape& shape, int modes)
{
    return samples_per_row(shape) * static_cast<std::int64_t>(sizeof(float)) *
           (3 * static_cast<std::int64_t>(shape.frames) + modes);
}

BandPlan plan_bands(const ShotShape& shape, std::int64_t max_memory_bytes, int halo_rows, int modes,
                    std::int64_t source_row_bytes)
{
    BandPlan plan;
    plan.halo_rows = halo_rows;
    plan.budget_bytes = max_memory_bytes;
    const std::int64_t input_row = input_bytes_per_row(shape), work_row = work_bytes_per_row(shape, modes);
    const std::int64_t kept = input_row * shape.height;
    const std::int64_t smallest_work = work_row * (std::min(kChunkRows, shape.height) + 2 * halo_rows);
    if (kept + smallest_work <= max_memory_bytes) {
        plan.in_memory = true;
        std::int64_t rows = (max_memory_bytes - kept) / work_row - 2 * halo_rows;
        rows = std::min<std::int64_t>({rows / kChunkRows * kChunkRows, kMaxKeptBandRows, shape.height});
        plan.band_rows = static_cast<int>(std::max<std::int64_t>(rows, std::min(kChunkRows, shape.height)));
        plan.estimated_bytes = kept + work_row * (plan.band_rows + 2 * halo_rows);
        return plan;
    }
    // Streaming: a read band, pass 2's buffers and the source's rows, and the outlier marks.
    const std::int64_t per_row = input_row + work_row + source_row_bytes;
    const std::int64_t marks = samples_per_row(shape) * shape.height;
    std::int64_t rows = (max_memory_bytes - marks) / per_row - 2 * halo_rows;
    rows = rows / kChunkRows * kChunkRows;
    if (rows < kChunkRows)
        throw usage_error(fmt::format("--max-memory leaves {} MiB for the shot's data, too little for {} frames of "
                                      "width {}: a band of {} rows needs {} MiB",
                                      max_memory_bytes >> 20, shape.frames, shape.width, kChunkRows,
                                      mebibytes_rounded_up(per_row * (kChunkRows + 2 * halo_rows) + marks)));
    plan.band_rows = static_cast<int>(std::min<std::int64_t>(rows, shape.height));
    plan.estimated_bytes = marks + per_row * (plan.band_rows + 2 * halo_rows);
    return plan;
}

}  // namespace modestack::denoise
