#include "core/denoise/frame_noise.h"

#include "core/common/error.h"
#include "core/denoise/stage_task.h"

#include <tbb/parallel_for.h>

#include <cmath>
#include <cstdint>

namespace modestack::denoise {

void row_roughness(const lowrank::BandView& band, int width, int channels, int band_rows, double* row_sums,
                   RowMeasure measure)
{
    const std::int64_t row_samples = static_cast<std::int64_t>(width) * channels;
    tbb::parallel_for(0, band.frames, [&](int t) { // each frame its own sums
        for (int r = 0; r < band_rows; ++r) {
            const float* row = band.data + t * band.frame_stride + r * row_samples;
            double sum = 0;
            for (std::int64_t i = channels; i + channels < row_samples; ++i) {
                const double left = row[i - channels], here = row[i], right = row[i + channels];
                const double difference = here - (left + right) / 2;
                if (std::isfinite(difference)) // any non-finite of the three makes it so
                    sum += measure == RowMeasure::Absolute ? std::abs(difference) : difference * difference;
            }
            row_sums[static_cast<std::int64_t>(r) * band.frames + t] = sum;
        }
    });
}

std::vector<double> roughness_blocks(const double* row_sums, int frames, int row_begin, int row_end)
{
    if (row_begin % kStageBlockRows != 0 || row_end < row_begin)
        throw internal_error("roughness_blocks: rows do not start on a block");
    std::vector<double> blocks(static_cast<size_t>(stage_blocks(row_end - row_begin)) * frames, 0.0);
    for (int row = row_begin; row < row_end; ++row) {
        const size_t block = static_cast<size_t>((row - row_begin) / kStageBlockRows);
        for (int t = 0; t < frames; ++t)
            blocks[block * frames + t] += row_sums[static_cast<size_t>(row - row_begin) * frames + t];
    }
    return blocks;
}

std::vector<double> frame_noise_factors(const std::vector<double>& blocks, int frames)
{
    if (frames < 1 || blocks.size() % static_cast<size_t>(frames) != 0)
        throw internal_error("frame_noise_factors: block sums do not match the frames");
    std::vector<double> levels(static_cast<size_t>(frames), 0.0);
    for (size_t block = 0; block < blocks.size() / frames; ++block)
        for (int t = 0; t < frames; ++t)
            levels[static_cast<size_t>(t)] += blocks[block * frames + t];
    double mean = 0;
    for (double level : levels)
        mean += level;
    mean /= frames;
    std::vector<double> factors(static_cast<size_t>(frames), 1.0);
    if (mean > 0 && std::isfinite(mean))
        for (int t = 0; t < frames; ++t)
            factors[static_cast<size_t>(t)] = levels[static_cast<size_t>(t)] / mean;
    return factors;
}

std::vector<double> frame_scale_factors(const std::vector<double>& power_blocks, int frames)
{
    std::vector<double> factors = frame_noise_factors(power_blocks, frames);
    for (double& factor : factors)
        factor = std::sqrt(factor);
    return factors;
}

} // namespace modestack::denoise
