#include "core/denoise/band_plan.h"

#include "core/common/error.h"

#include <fmt/format.h>

#include <algorithm>

namespace modestack::denoise {
namespace {

// Sigma's scratch per sample of a band's rows: s² (float), its sum over frames
// (double) and the windowed noise power of a group of 16 frames (core/lowrank/confidence.cpp).
constexpr int kSigmaScratchImages = 1 + 2 + 16;

std::int64_t samples_per_row(const ShotShape& shape) { return static_cast<std::int64_t>(shape.width) * shape.channels; }

std::int64_t mebibytes_rounded_up(std::int64_t bytes) { return (bytes + (1 << 20) - 1) >> 20; }

// The largest band height that `fits`: a multiple of kChunkRows, or `limit`
// itself; at least the smallest band (the caller checked that it fits).
template <typename Fits>
int largest_band(int limit, const Fits& fits)
{
    int best = std::min(kChunkRows, limit);
    for (int rows = best; rows < limit;) {
        rows = std::min(rows + kChunkRows, limit);
        if (!fits(rows))
            break;
        best = rows;
    }
    return best;
}

// A choice worker's per-pixel spread (temporal_spread.h) of the band's rows,
// in images of the shot's channels: its spread and terms, 2 floats a pixel
// (its judged samples are one more image of those rows).
std::int64_t spread_images(const ShotShape& shape)
{
    constexpr std::int64_t floats_per_pixel = 2;
    return (floats_per_pixel + shape.channels - 1) / shape.channels;
}

// The spread's terms of every pair of frames of a band's rows (one float a
// pixel and pair), in images of the shot's channels.
std::int64_t spread_pair_images(const ShotShape& shape)
{
    return (std::max<std::int64_t>(shape.frames - 1, 0) + shape.channels - 1) / shape.channels;
}

}  // namespace

std::int64_t input_bytes_per_row(const ShotShape& shape)
{
    return samples_per_row(shape) * static_cast<std::int64_t>(sizeof(float)) * shape.frames;
}

std::int64_t pass_two_bytes(const ShotShape& shape, const PassNeeds& needs, int band_rows, bool sigma_apart)
{
    const std::int64_t frames = shape.frames;
    const std::int64_t halo_band_rows = band_rows + 2 * needs.halo_rows;
    const bool sigma_kept_apart = sigma_apart || needs.choice_rows > 0;
    const std::int64_t computed_rows = band_rows + 2 * needs.choice_rows;
    const std::int64_t pass_two_only =
        frames * (computed_rows + 2 * needs.sigma_halo_rows) +
        (needs.band_images + kSigmaScratchImages) * computed_rows +
        (sigma_kept_apart ? frames * computed_rows : 0) +
        (needs.choice_rows > 0 ? needs.choice_workers * (computed_rows + 2 * needs.choice_rows +
                                                         (1 + spread_images(shape)) * band_rows) +
                                     spread_pair_images(shape) * band_rows
                               : 0);
    const std::int64_t survey_only = static_cast<std::int64_t>(needs.survey_images) * halo_band_rows;
    const std::int64_t images =
        static_cast<std::int64_t>(needs.halo_images) * halo_band_rows + std::max(pass_two_only, survey_only);
    return images * samples_per_row(shape) * static_cast<std::int64_t>(sizeof(float));
}

BandPlan plan_bands(const ShotShape& shape, std::int64_t max_memory_bytes, const PassNeeds& needs)
{
    BandPlan plan;
    plan.halo_rows = needs.halo_rows;
    plan.rolls = !needs.shared_rows;
    plan.budget_bytes = max_memory_bytes;
    const std::int64_t input_row = input_bytes_per_row(shape);
    // Several layers: the rows decoded for all of them, per row of a band with
    // its halo (and while a kept shot is read, a few whole frames of it), and
    // the rebuilt values and sigma of the band's own rows gathered for the write.
    const std::int64_t shared_row = needs.shared_rows ? input_row : 0;
    const std::int64_t shared_read =
        needs.shared_rows
            ? input_row / shape.frames * std::min(shape.frames, needs.shared_frames) * shape.height
            : 0;
    const int smallest_band = std::min(kChunkRows, shape.height);
    const std::int64_t kept = input_row * shape.height;
    const auto kept_bytes = [&](int rows) {
        return kept + std::max(shared_read, shared_row * (3 * rows + 2 * needs.halo_rows)) +
               pass_two_bytes(shape, needs, rows, true);
    };
    // The kept shot: the largest band (a multiple of kChunkRows, at most
    // kMaxKeptBandRows) whose pass 2 fits beside it.
    if (kept_bytes(smallest_band) <= max_memory_bytes) {
        plan.in_memory = true;
        plan.band_rows = largest_band(std::min(kMaxKeptBandRows, shape.height),
                                      [&](int rows) { return kept_bytes(rows) <= max_memory_bytes; });
        plan.estimated_bytes = kept_bytes(plan.band_rows);
        plan.halo_band_rows = plan.band_rows;
        return plan;
    }
    // Streaming: a read band with its halo and the source's rows, pass 2's
    // buffers and the outlier marks.
    const std::int64_t marks = samples_per_row(shape) * shape.height;
    const auto read_bytes = [&](int rows, int halo_rows) {
        return marks + (input_row + shared_row + needs.source_row_bytes) * (rows + 2 * halo_rows) +
               2 * shared_row * rows;
    };
    const auto streamed_bytes = [&](int rows) {
        return read_bytes(rows, needs.halo_rows) + pass_two_bytes(shape, needs, rows, false);
    };
    if (streamed_bytes(smallest_band) <= max_memory_bytes) {
        plan.band_rows =
            largest_band(shape.height, [&](int rows) { return streamed_bytes(rows) <= max_memory_bytes; });
        plan.halo_band_rows = plan.band_rows;
        plan.estimated_bytes = streamed_bytes(plan.band_rows);
        return plan;
    }
    // Shorter bands for the passes with a halo. The statistics still read
    // smallest_band rows, without a halo or pass 2's buffers.
    int rows = smallest_band - 1;
    while (rows > 1 && streamed_bytes(rows) > max_memory_bytes)
        --rows;
    const std::int64_t statistics_bytes = read_bytes(smallest_band, 0);
    if (rows < 1 || streamed_bytes(rows) > max_memory_bytes || statistics_bytes > max_memory_bytes)
        throw usage_error(fmt::format(
            "--max-memory leaves {} MiB for the shot's data, too little for {} frames of "
            "width {}: a band of {} rows needs {} MiB, of 1 row {} MiB",
            max_memory_bytes >> 20, shape.frames, shape.width, smallest_band,
            mebibytes_rounded_up(streamed_bytes(smallest_band)), mebibytes_rounded_up(streamed_bytes(1))));
    plan.band_rows = smallest_band;
    plan.halo_band_rows = rows;
    plan.estimated_bytes = std::max(streamed_bytes(rows), statistics_bytes);
    return plan;
}

}  // namespace modestack::denoise
