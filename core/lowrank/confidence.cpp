#include "core/lowrank/confidence.h"

#include "core/common/error.h"
#include "core/common/progress.h"
#include "core/lowrank/tiles.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <vector>

namespace modestack::lowrank {
namespace {

// Image rows [first_row, first_row + rows) of one frame's samples, in double:
// each value is computed once, although every window around it reads it.
struct Rows {
    std::vector<double> values;
    int first_row = 0;
    std::int64_t row_length = 0;
    double operator()(int y, std::int64_t k) const
    {
        return values[static_cast<std::size_t>((y - first_row) * row_length + k)];
    }
};

// The residual's white-noise part: r minus the mean of its 4-neighbours (clipped
// at the band), squared and divided by the white-noise gain 1 + 1/n, so that its
// expectation is the residual's noise variance σ²(1 − h_t). Lighting the modes miss
// is smooth in space and mostly cancels here, unlike in r² itself.
double high_pass_power(const Rows& residual, const ImageBandShape& shape, int y, std::int64_t k)
{
    const int x = static_cast<int>(k / shape.channels);
    double neighbours = 0;
    int count = 0;
    if (x > 0)
        neighbours += residual(y, k - shape.channels), ++count;
    if (x + 1 < shape.width)
        neighbours += residual(y, k + shape.channels), ++count;
    if (y > 0)
        neighbours += residual(y - 1, k), ++count;
    if (y + 1 < shape.height)
        neighbours += residual(y + 1, k), ++count;
    if (count == 0)
        return residual(y, k) * residual(y, k);
    const double difference = residual(y, k) - neighbours / count;
    return difference * difference / (1.0 + 1.0 / count);
}

// Writes the mean over the (2·radius+1)² window (clipped at the band) of
// sample(y, k) for the output rows of frame t into `out`'s frame t.
void windowed_mean(const Rows& sample, const ImageBandShape& shape, int radius, int valid_y0, int valid_y1,
                   float* out_frame, std::vector<double>& column_sum)
{
    const std::int64_t row_length = static_cast<std::int64_t>(shape.width) * shape.channels;
    for (int y = valid_y0; y < valid_y1; ++y) {
        const int y_first = std::max(0, y - radius);
        const int y_last = std::min(shape.height - 1, y + radius);
        std::fill(column_sum.begin(), column_sum.end(), 0.0);
        for (int source_y = y_first; source_y <= y_last; ++source_y)
            for (std::int64_t k = 0; k < row_length; ++k)
                column_sum[static_cast<std::size_t>(k)] += sample(source_y, k);
        const int rows_in_window = y_last - y_first + 1;
        float* out_row = out_frame + (y - valid_y0) * row_length;
        for (int x = 0; x < shape.width; ++x) {
            const int x_first = std::max(0, x - radius);
            const int x_last = std::min(shape.width - 1, x + radius);
            const double count = static_cast<double>(rows_in_window) * (x_last - x_first + 1);
            for (int c = 0; c < shape.channels; ++c) {
                double sum = 0;
                for (int source_x = x_first; source_x <= x_last; ++source_x)
                    sum += column_sum[static_cast<std::size_t>(source_x * shape.channels + c)];
                out_row[x * shape.channels + c] = static_cast<float>(sum / count);
            }
        }
    }
}

} // namespace

void confidence_band(const BandView& noisy, const BandView& rebuilt, const ImageBandShape& shape,
                     const Eigen::VectorXd& leverages, int rank, int valid_y0, int valid_y1,
                     const ConfidenceOptions& options, MutableBandView sigma, const BandView* kept_noise)
{
    const int frames = noisy.frames;
    const std::int64_t band_rows = static_cast<std::int64_t>(shape.width) * shape.height * shape.channels;
    const std::int64_t row_length = static_cast<std::int64_t>(shape.width) * shape.channels;
    if (noisy.rows != band_rows || rebuilt.rows != band_rows || rebuilt.frames != frames ||
        sigma.frames != frames || leverages.size() != frames)
        throw internal_error("confidence_band: band shapes do not match");
    if (valid_y0 < 0 || valid_y1 > shape.height || valid_y0 > valid_y1 ||
        sigma.rows != row_length * (valid_y1 - valid_y0))
        throw internal_error("confidence_band: output rows do not match the valid range");
    if (rank < 0 || rank >= frames)
        throw internal_error("confidence_band: rank must be less than the number of frames");
    if (options.radius < 0)
        throw internal_error("confidence_band: negative window radius");
    if (kept_noise && (kept_noise->rows != sigma.rows || kept_noise->frames != frames))
        throw internal_error("confidence_band: kept noise does not match sigma");
    if (sigma.rows == 0)
        return;

    // Stage 1: per frame, the windowed mean residual (into sigma) and the windowed
    // high-pass power (into noise_power), both per pixel and channel.
    throw_if_cancelled();
    std::vector<float> noise_power(static_cast<std::size_t>(sigma.rows) * frames);
    // The windows read rows [window_first, window_last]; the high-pass one row more.
    const int window_first = std::max(0, valid_y0 - options.radius);
    const int window_last = std::min(shape.height - 1, valid_y1 - 1 + options.radius);
    const int residual_first = std::max(0, window_first - 1), residual_last = std::min(shape.height - 1, window_last + 1);
    tbb::parallel_for(tbb::blocked_range<int>(0, frames, 1), [&](const tbb::blocked_range<int>& range) {
        std::vector<double> column_sum(static_cast<std::size_t>(row_length));
        Rows residual{{}, residual_first, row_length}, power{{}, window_first, row_length};
        residual.values.resize(static_cast<std::size_t>((residual_last - residual_first + 1) * row_length));
        power.values.resize(static_cast<std::size_t>((window_last - window_first + 1) * row_length));
        for (int t = range.begin(); t != range.end(); ++t) {
            const float* noisy_frame = noisy.data + t * noisy.frame_stride;
            const float* rebuilt_frame = rebuilt.data + t * rebuilt.frame_stride;
            for (std::int64_t i = residual_first * row_length, j = 0; i < (residual_last + 1) * row_length; ++i, ++j)
                residual.values[static_cast<std::size_t>(j)] = static_cast<double>(noisy_frame[i]) - rebuilt_frame[i];
            for (int y = window_first; y <= window_last; ++y)
                for (std::int64_t k = 0; k < row_length; ++k)
                    power.values[static_cast<std::size_t>((y - window_first) * row_length + k)] =
                        high_pass_power(residual, shape, y, k);
            windowed_mean(residual, shape, options.radius, valid_y0, valid_y1, sigma.data + t * sigma.frame_stride,
                          column_sum);
            windowed_mean(power, shape, options.radius, valid_y0, valid_y1, noise_power.data() + t * sigma.rows,
                          column_sum);
        }
    });

    // Stage 2: s², bias and sigma per sample, summing over frames in frame order.
    const double degrees_of_freedom = frames - rank;
    const int radius = options.radius;
    for_each_tile(sigma.rows, [&](std::int64_t row0, std::int64_t count) {
        for (std::int64_t i = row0; i < row0 + count; ++i) {
            const std::int64_t pixel = i / shape.channels;
            const int x = static_cast<int>(pixel % shape.width);
            const int y = valid_y0 + static_cast<int>(pixel / shape.width);
            const int window_width = std::min(shape.width - 1, x + radius) - std::max(0, x - radius) + 1;
            const int window_height = std::min(shape.height - 1, y + radius) - std::max(0, y - radius) + 1;
            const double window_size = static_cast<double>(window_width) * window_height;
            double energy = 0;
            for (int t = 0; t < frames; ++t)
                energy += noise_power[static_cast<std::size_t>(t * sigma.rows + i)];
            const double noise_variance = energy / degrees_of_freedom;
            for (int t = 0; t < frames; ++t) {
                // The windowed mean of pure noise has variance s²(1 − h_t)/|W|;
                // what the squared mean holds beyond that is coherent missed content.
                const double mean = sigma.at(i, t);
                const double bias =
                    std::max(0.0, mean * mean - options.bias_significance * noise_variance * (1.0 - leverages(t)) / window_size);
                const double kept = kept_noise ? kept_noise->at(i, t) : leverages(t);
                sigma.at(i, t) = static_cast<float>(std::sqrt(noise_variance * kept + bias));
            }
        }
    });
}

} // namespace modestack::lowrank
