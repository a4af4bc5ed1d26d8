#include "core/lowrank/confidence.h"

#include "core/common/avx2_clones.h"
#include "core/common/error.h"
#include "core/common/progress.h"
#include "core/common/scratch_buffer.h"
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
    double* values = nullptr;
    int first_row = 0;
    std::int64_t row_length = 0;
    double operator()(int y, std::int64_t k) const { return values[(y - first_row) * row_length + k]; }
};

// The residual's white-noise part: r minus the mean of its 4-neighbours (clipped
// at the band), squared and divided by the white-noise gain 1 + 1/n, so that its
// expectation is the residual's noise variance σ²(1 − h_t). Lighting the modes miss
// is smooth in space and mostly cancels here, unlike in r² itself. Sample k of row
// y belongs to pixel x (passed, not divided out per sample).
double high_pass_power(const Rows& residual, const ImageBandShape& shape, int x, int y, std::int64_t k)
{
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

// high_pass_power for samples [first, end) of row y whose pixels have all four
// neighbours, with its operations in its order (the same bits); returns end.
std::int64_t inner_high_pass_power(const Rows& residual, int y, std::int64_t first, std::int64_t end,
                                   double* power_row)
{
    const std::int64_t channels_apart = first;  // the run starts at pixel 1
    const double* row = &residual.values[(y - residual.first_row) * residual.row_length];
    const double* above = row - residual.row_length;
    const double* below = row + residual.row_length;
    for (std::int64_t k = first; k < end; ++k) {
        double neighbours = 0;
        neighbours += row[k - channels_apart];
        neighbours += row[k + channels_apart];
        neighbours += above[k];
        neighbours += below[k];
        const double difference = row[k] - neighbours / 4;
        power_row[k] = difference * difference / (1.0 + 1.0 / 4);
    }
    return end;
}

// Visits the pixels of a row `width` long by how their window of `radius` meets
// the row's ends: edge_pixel(x) for each clipped one, inner_run(first, end) once
// for the unclipped ones [first, end), which share a window shape and so can be
// done as one run the compiler vectorises.
template <typename EdgePixel, typename InnerRun>
void for_each_window_shape(int width, int radius, EdgePixel&& edge_pixel, InnerRun&& inner_run)
{
    const int first = std::min(radius, width), end = std::max(first, width - radius);
    for (int x = 0; x < first; ++x)
        edge_pixel(x);
    if (first < end)
        inner_run(first, end);
    for (int x = end; x < width; ++x)
        edge_pixel(x);
}

// The window means of the pixels [inner_first, inner_end) of a row whose windows
// are not clipped in x: all their samples at once, each window summed in the
// order of the edge pixels' loop (the same bits as summing each window alone).
MODESTACK_AVX2_CLONES void inner_window_mean(const double* column_sum, double* window_sum, float* out_row,
                                             int inner_first, int inner_end, int radius, int channels, double count)
{
    const std::int64_t first = static_cast<std::int64_t>(inner_first) * channels;
    const std::int64_t last = static_cast<std::int64_t>(inner_end) * channels;
    std::fill(window_sum + first, window_sum + last, 0.0);
    for (int d = -radius; d <= radius; ++d) {
        const double* source = column_sum + static_cast<std::int64_t>(d) * channels;
        for (std::int64_t k = first; k < last; ++k)
            window_sum[k] += source[k];
    }
    for (std::int64_t k = first; k < last; ++k)
        out_row[k] = static_cast<float>(window_sum[k] / count);
}

// Writes the mean over the (2·radius+1)² window (clipped at the band) of
// sample(y, k) for the output rows of frame t into `out`'s frame t.
MODESTACK_AVX2_CLONES void windowed_mean(const Rows& sample, const ImageBandShape& shape, int radius, int valid_y0,
                                         int valid_y1, float* out_frame, std::vector<double>& column_sum,
                                         std::vector<double>& window_sum)
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
        const auto inner_run = [&](int inner_first, int inner_end) {
            inner_window_mean(column_sum.data(), window_sum.data(), out_row, inner_first, inner_end, radius,
                              shape.channels, static_cast<double>(rows_in_window) * (2 * radius + 1));
        };
        const auto edge_pixel = [&](int x) {
            const int x_first = std::max(0, x - radius);
            const int x_last = std::min(shape.width - 1, x + radius);
            const double count = static_cast<double>(rows_in_window) * (x_last - x_first + 1);
            for (int c = 0; c < shape.channels; ++c) {
                double sum = 0;
                for (int source_x = x_first; source_x <= x_last; ++source_x)
                    sum += column_sum[static_cast<std::size_t>(source_x * shape.channels + c)];
                out_row[x * shape.channels + c] = static_cast<float>(sum / count);
            }
        };
        for_each_window_shape(shape.width, radius, edge_pixel, inner_run);
    }
}

} // namespace

namespace {

// The residual r = x − x̂ of one frame over the rows the windows of the output
// rows [valid_y0, valid_y1) read, and its windowed mean (`mean`, may be null) and
// windowed high-pass power (`power`, may be null) at the output rows. The one
// place both are computed: a whole run, a farm modes task (power only) and a
// farm write task (mean only) agree bit for bit.
class ResidualWindows {
public:
    ResidualWindows(const ImageBandShape& shape, int radius, int valid_y0, int valid_y1)
        : m_shape(shape), m_radius(radius), m_valid_y0(valid_y0), m_valid_y1(valid_y1),
          m_row_length(static_cast<std::int64_t>(shape.width) * shape.channels),
          m_window_first(std::max(0, valid_y0 - radius)), m_window_last(std::min(shape.height - 1, valid_y1 - 1 + radius))
    {
        // The windows read rows [window_first, window_last]; the high-pass one row more.
        m_residual_first = std::max(0, m_window_first - 1);
        m_residual_last = std::min(m_shape.height - 1, m_window_last + 1);
    }

    void compute(const float* noisy_frame, const float* rebuilt_frame, float* mean, float* power)
    {
        // This thread's buffers, reused from frame to frame and band to band (fresh
        // ones cost the kernel's page zeroing every frame); compute() runs nothing
        // in parallel, so no other frame can use them meanwhile.
        static thread_local std::vector<double> residual_buffer, power_buffer, column_sum, window_sum;
        residual_buffer.resize(static_cast<std::size_t>((m_residual_last - m_residual_first + 1) * m_row_length));
        column_sum.resize(static_cast<std::size_t>(m_row_length));
        window_sum.resize(static_cast<std::size_t>(m_row_length));
        const Rows residual{residual_buffer.data(), m_residual_first, m_row_length};
        const std::int64_t first = m_residual_first * m_row_length;
        // The frame's noisy values are not read after this copy: `mean` may be their storage.
        for (std::size_t j = 0; j < residual_buffer.size(); ++j)
            residual_buffer[j] = static_cast<double>(noisy_frame[first + j]) - rebuilt_frame[first + j];
        if (mean)
            windowed_mean(residual, m_shape, m_radius, m_valid_y0, m_valid_y1, mean, column_sum, window_sum);
        if (!power)
            return;
        power_buffer.resize(static_cast<std::size_t>((m_window_last - m_window_first + 1) * m_row_length));
        const Rows power_rows{power_buffer.data(), m_window_first, m_row_length};
        for (int y = m_window_first; y <= m_window_last; ++y) {
            double* power_row = power_buffer.data() + (y - m_window_first) * m_row_length;
            const bool inner_row = y > 0 && y + 1 < m_shape.height && m_shape.width > 2;
            std::int64_t k = 0;
            for (int x = 0; x < m_shape.width; ++x) {
                if (inner_row && x == 1) {  // pixels with all four neighbours, in one vectorised run
                    k = inner_high_pass_power(residual, y, k, m_row_length - m_shape.channels, power_row);
                    x = m_shape.width - 1;
                }
                for (int c = 0; c < m_shape.channels; ++c, ++k)
                    power_row[k] = high_pass_power(residual, m_shape, x, y, k);
            }
        }
        windowed_mean(power_rows, m_shape, m_radius, m_valid_y0, m_valid_y1, power, column_sum, window_sum);
    }

private:
    ImageBandShape m_shape;
    int m_radius, m_valid_y0, m_valid_y1;
    std::int64_t m_row_length;
    int m_window_first, m_window_last, m_residual_first = 0, m_residual_last = 0;
};

void check_band(const BandView& noisy, const BandView& rebuilt, const ImageBandShape& shape, int valid_y0,
                int valid_y1, int radius)
{
    const std::int64_t band_rows = static_cast<std::int64_t>(shape.width) * shape.height * shape.channels;
    if (noisy.rows != band_rows || rebuilt.rows != band_rows || rebuilt.frames != noisy.frames)
        throw internal_error("confidence: band shapes do not match");
    if (valid_y0 < 0 || valid_y1 > shape.height || valid_y0 > valid_y1)
        throw internal_error("confidence: output rows outside the band");
    if (radius < 0)
        throw internal_error("confidence: negative window radius");
}

// Pixels in the window around pixel (x, y) (clipped at the band).
double window_size(const ImageBandShape& shape, int radius, int x, int y)
{
    const int window_width = std::min(shape.width - 1, x + radius) - std::max(0, x - radius) + 1;
    const int window_height = std::min(shape.height - 1, y + radius) - std::max(0, y - radius) + 1;
    return static_cast<double>(window_width) * window_height;
}

} // namespace

void residual_noise_variance(const BandView& noisy, const BandView& rebuilt, const ImageBandShape& shape,
                             int kept_modes, int valid_y0, int valid_y1, const ConfidenceOptions& options,
                             float* noise_variance, float* means, std::int64_t means_stride,
                             const Eigen::VectorXd& frame_scales)
{
    check_band(noisy, rebuilt, shape, valid_y0, valid_y1, options.radius);
    const int frames = noisy.frames;
    if (kept_modes < 0 || kept_modes >= frames)
        throw internal_error("confidence: rank must be less than the number of frames");
    if (frame_scales.size() != 0 && frame_scales.size() != frames)
        throw internal_error("residual_noise_variance: a scale per frame is needed");
    const std::int64_t samples = static_cast<std::int64_t>(shape.width) * shape.channels * (valid_y1 - valid_y0);
    if (samples == 0)
        return;
    if (means_stride == 0)
        means_stride = samples;
    throw_if_cancelled();
    // Per frame, the windowed high-pass power, a group of frames at a time so that
    // the scratch does not grow with F; s² sums it over frames in frame order. The
    // scratch is this thread's, reused from band to band (fresh band-sized buffers
    // cost the kernel's page clearing every band).
    constexpr int kFrameGroup = 16;
    // (The workers below must use this thread's buffers: a thread_local named in
    // their lambdas would be their own.)
    static thread_local ScratchBuffer<float> this_thread_noise_power;
    static thread_local ScratchBuffer<double> this_thread_energy;
    ScratchBuffer<float>& noise_power = this_thread_noise_power;
    ScratchBuffer<double>& energy = this_thread_energy;
    noise_power.resize(static_cast<std::size_t>(samples) * std::min(frames, kFrameGroup));
    energy.resize(static_cast<std::size_t>(samples));
    std::fill(energy.begin(), energy.end(), 0.0);
    for (int group = 0; group < frames; group += kFrameGroup) {
        const int group_end = std::min(frames, group + kFrameGroup);
        tbb::parallel_for(tbb::blocked_range<int>(group, group_end, 1), [&](const tbb::blocked_range<int>& range) {
            ResidualWindows windows(shape, options.radius, valid_y0, valid_y1);
            for (int t = range.begin(); t != range.end(); ++t)
                windows.compute(noisy.data + t * noisy.frame_stride, rebuilt.data + t * rebuilt.frame_stride,
                                means ? means + t * means_stride : nullptr, noise_power.data() + (t - group) * samples);
        });
        for_each_tile(samples, [&](std::int64_t row0, std::int64_t count) {
            for (int t = group; t < group_end; ++t) {
                const float* power = noise_power.data() + (t - group) * samples;
                if (frame_scales.size() == 0) {
                    for (std::int64_t i = row0; i < row0 + count; ++i)
                        energy[static_cast<std::size_t>(i)] += power[i];
                    continue;
                }
                const double weight = 1.0 / frame_noise_variance(frame_scales, t); // the residual r_t / D_t
                for (std::int64_t i = row0; i < row0 + count; ++i)
                    energy[static_cast<std::size_t>(i)] += power[i] * weight;
            }
        });
    }
    const double degrees_of_freedom = frames - kept_modes;
    for (std::int64_t i = 0; i < samples; ++i)
        noise_variance[i] = static_cast<float>(energy[static_cast<std::size_t>(i)] / degrees_of_freedom);
}

void frame_sigma(const float* noisy_frame, const float* rebuilt_frame, const ImageBandShape& shape,
                 int valid_y0, int valid_y1, const ConfidenceOptions& options, const float* noise_variance,
                 double leverage, const float* kept_noise, const BiasPosterior* posteriors, float* sigma,
                 SigmaExtraTerm extra, double frame_variance)
{
    if (valid_y0 < 0 || valid_y1 > shape.height || valid_y0 > valid_y1 || options.radius < 0)
        throw internal_error("frame_sigma: output rows outside the band");
    ResidualWindows windows(shape, options.radius, valid_y0, valid_y1);
    windows.compute(noisy_frame, rebuilt_frame, sigma, nullptr);
    sigma_from_mean(shape, valid_y0, valid_y1, options, noise_variance, leverage, kept_noise, posteriors,
                    sigma, extra, frame_variance);
}

namespace {

// Calls visit(first, last, noise_share) for runs of samples [first, last) of
// the output rows (counted from valid_y0) that share a window size, where
// noise_share · s² is the noise variance τ² of their windowed mean.
template <typename Visit>
void for_each_window_run(const ImageBandShape& shape, int valid_y0, int valid_y1,
                         const ConfidenceOptions& options, double leverage, double frame_variance,
                         Visit&& visit)
{
    const std::int64_t row_length = static_cast<std::int64_t>(shape.width) * shape.channels;
    const auto share = [&](double window) {
        return options.bias_significance * (1.0 - leverage) / window * frame_variance;
    };
    for (int y = valid_y0; y < valid_y1; ++y) {
        const std::int64_t row = (y - valid_y0) * row_length;
        for_each_window_shape(
            shape.width, options.radius,
            [&](int x) {
                const std::int64_t first = row + static_cast<std::int64_t>(x) * shape.channels;
                visit(y, first, first + shape.channels, share(window_size(shape, options.radius, x, y)));
            },
            [&](int inner_first, int inner_end) {
                visit(y, row + static_cast<std::int64_t>(inner_first) * shape.channels,
                      row + static_cast<std::int64_t>(inner_end) * shape.channels,
                      share(window_size(shape, options.radius, inner_first, y)));
            });
    }
}

} // namespace

void count_bias_ratios(const ImageBandShape& shape, int valid_y0, int valid_y1,
                       const ConfidenceOptions& options, const float* noise_variance, double leverage,
                       const float* means, BiasRatioCounts* counts, double frame_variance)
{
    for_each_window_run(
        shape, valid_y0, valid_y1, options, leverage, frame_variance,
        [&](int y, std::int64_t first, std::int64_t last, double noise_share) {
            BiasRatioCounts& row = counts[y - valid_y0];
            for (std::int64_t i = first; i < last; ++i) {
                const double mean = means[i];
                ++row[static_cast<std::size_t>(bias_bin(mean * mean / (noise_variance[i] * noise_share)))];
            }
        });
}

std::vector<BiasPosterior> row_bias_posteriors(const ImageBandShape& shape, int valid_y0, int valid_y1,
                                               const ConfidenceOptions& options, const float* noise_variance,
                                               const Eigen::VectorXd& leverages, const float* means,
                                               std::int64_t means_stride, const Eigen::VectorXd& frame_scales)
{
    if (frame_scales.size() != 0 && frame_scales.size() != leverages.size())
        throw internal_error("row_bias_posteriors: a scale per frame is needed");
    const int rows = valid_y1 - valid_y0;
    const std::int64_t row_length = static_cast<std::int64_t>(shape.width) * shape.channels;
    std::vector<BiasPosterior> posteriors(static_cast<std::size_t>(std::max(rows, 0)));
    tbb::parallel_for(0, std::max(rows, 0), [&](int r) {
        BiasRatioCounts counts{};
        const std::int64_t offset = r * row_length;
        for (Eigen::Index t = 0; t < leverages.size(); ++t)
            count_bias_ratios(shape, valid_y0 + r, valid_y0 + r + 1, options, noise_variance + offset,
                              leverages(t), means + t * means_stride + offset, &counts,
                              frame_noise_variance(frame_scales, t));
        posteriors[static_cast<std::size_t>(r)] = fit_bias_posterior(counts);
    });
    return posteriors;
}

void sigma_from_mean(const ImageBandShape& shape, int valid_y0, int valid_y1,
                     const ConfidenceOptions& options, const float* noise_variance, double leverage,
                     const float* kept_noise, const BiasPosterior* posteriors, float* sigma,
                     SigmaExtraTerm extra, double frame_variance)
{
    // The windowed mean of pure noise has variance τ² = f_t s²(1 − h_t)/|W|;
    // the bias is the posterior mean of b² under the row's prior (bias_prior.h).
    for_each_window_run(shape, valid_y0, valid_y1, options, leverage, frame_variance,
                        [&](int y, std::int64_t first, std::int64_t last, double noise_share) {
                            const BiasPosterior& posterior = posteriors[y - valid_y0];
                            for (std::int64_t i = first; i < last; ++i) {
                                const double mean = sigma[i], variance = noise_variance[i];
                                const double null = variance * noise_share, squared = mean * mean;
                                const auto bin = static_cast<std::size_t>(bias_bin(squared / null));
                                // τ² = 0 (no noise) lands in the top bin, slope 1: the bias is μ².
                                const double bias =
                                    posterior.slope[bin] * squared + posterior.offset[bin] * null;
                                const double kept = kept_noise ? static_cast<double>(kept_noise[i])
                                                               : leverage * frame_variance;
                                const double further =
                                    extra.values ? extra.weight * static_cast<double>(extra.values[i]) : 0.0;
                                sigma[i] = static_cast<float>(std::sqrt(variance * kept + bias + further));
                            }
                        });
}

void confidence_band(const BandView& noisy, const BandView& rebuilt, const ImageBandShape& shape,
                     const Eigen::VectorXd& leverages, int kept_modes, int valid_y0, int valid_y1,
                     const ConfidenceOptions& options, MutableBandView sigma, const BandView* kept_noise)
{
    const int frames = noisy.frames;
    check_band(noisy, rebuilt, shape, valid_y0, valid_y1, options.radius);
    const std::int64_t row_length = static_cast<std::int64_t>(shape.width) * shape.channels;
    if (sigma.frames != frames || leverages.size() != frames || sigma.rows != row_length * (valid_y1 - valid_y0))
        throw internal_error("confidence_band: output rows do not match the valid range");
    if (kept_noise && (kept_noise->rows != sigma.rows || kept_noise->frames != frames))
        throw internal_error("confidence_band: kept noise does not match sigma");
    if (sigma.rows == 0)
        return;
    // s² and every frame's windowed residual mean (left in sigma), the rows'
    // bias priors from all frames, then sigma frame by frame: a whole run's steps.
    std::vector<float> noise_variance(static_cast<std::size_t>(sigma.rows));
    residual_noise_variance(noisy, rebuilt, shape, kept_modes, valid_y0, valid_y1, options,
                            noise_variance.data(), sigma.data, sigma.frame_stride);
    const std::vector<BiasPosterior> posteriors = row_bias_posteriors(
        shape, valid_y0, valid_y1, options, noise_variance.data(), leverages, sigma.data, sigma.frame_stride);
    tbb::parallel_for(0, frames, [&](int t) {
        sigma_from_mean(shape, valid_y0, valid_y1, options, noise_variance.data(), leverages(t),
                        kept_noise ? kept_noise->data + t * kept_noise->frame_stride : nullptr,
                        posteriors.data(), sigma.data + t * sigma.frame_stride);
    });
}

} // namespace modestack::lowrank
