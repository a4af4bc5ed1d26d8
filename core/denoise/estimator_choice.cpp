#include "core/denoise/estimator_choice.h"

#include "core/common/avx2_clones.h"
#include "core/common/error.h"
#include "core/denoise/non_local_means.h"
#include "core/denoise/temporal_misfit.h"
#include "core/denoise/temporal_spread.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <tuple>

namespace modestack::denoise {
namespace {

constexpr std::array<double, 2> kGaussWidths{1.0, 2.0}; // pixels
constexpr std::array<int, 2> kGaussReaches{3, 6};       // ⌈3 × width⌉
constexpr int kGaussReach = 6;                          // the widest
constexpr int kStripRows = 64; // rows chosen at once: bounds the planes, whatever the frame's height

// A plane of `depth` floats per pixel over image rows [begin, end).
struct Plane {
    int begin = 0, end = 0, width = 0, depth = 1;
    std::vector<float> values;
    void reset(int first, int last, int plane_width, int plane_depth)
    {
        begin = first, end = last, width = plane_width, depth = plane_depth;
        values.resize(static_cast<size_t>(end - begin) * width * depth); // every producer writes every value
    }
    float* row(int y) { return values.data() + static_cast<std::int64_t>(y - begin) * width * depth; }
    const float* row(int y) const
    {
        return values.data() + static_cast<std::int64_t>(y - begin) * width * depth;
    }
};

// The mean over the (2r+1)² window around each pixel of rows [first, last),
// clipped to the image (the source must hold every image row the window reads).
// Along a row each value sums its window directly (independent sums that
// vectorise; a running sum is one long chain of dependent additions); down the
// columns running sums. In double, in a fixed order: the same bits on every run.
MODESTACK_AVX2_CLONES void box_mean(const Plane& source, int height, int radius, int first, int last,
                                    Plane& result, std::vector<float>& horizontal,
                                    std::vector<double>& column)
{
    const int width = source.width, depth = source.depth;
    const std::int64_t row_values = static_cast<std::int64_t>(width) * depth;
    const int top = std::max(0, first - radius), bottom = std::min(height, last + radius);
    horizontal.resize(static_cast<size_t>((bottom - top) * row_values)); // every value written below
    column.resize(static_cast<size_t>(row_values));
    // Pixels [inner_begin, inner_end) see the whole window along the row.
    const int inner_begin = std::min(radius, width), inner_end = std::max(inner_begin, width - radius);
    // Reciprocals, not divisions: a division per value was most of the box's time.
    const double inner_scale = 1.0 / (2 * radius + 1);
    for (int y = top; y < bottom; ++y) {
        const float* in = source.row(y);
        float* out = horizontal.data() + (y - top) * row_values;
        const std::int64_t begin = static_cast<std::int64_t>(inner_begin) * depth,
                           end = static_cast<std::int64_t>(inner_end) * depth;
        std::fill(column.begin() + begin, column.begin() + end, 0.0);
        for (int k = -radius; k <= radius; ++k) {
            const float* shifted = in + static_cast<std::int64_t>(k) * depth;
            for (std::int64_t i = begin; i < end; ++i)
                column[static_cast<size_t>(i)] += shifted[i];
        }
        for (std::int64_t i = begin; i < end; ++i)
            out[i] = static_cast<float>(column[static_cast<size_t>(i)] * inner_scale);
        for (int x = 0; x < width; ++x) {
            if (x == inner_begin && inner_end > inner_begin)
                x = inner_end;
            if (x >= width)
                break;
            const int x0 = std::max(0, x - radius), x1 = std::min(width - 1, x + radius);
            for (int c = 0; c < depth; ++c) {
                double sum = 0;
                for (int q = x0; q <= x1; ++q)
                    sum += in[q * depth + c];
                out[x * depth + c] = static_cast<float>(sum / (x1 - x0 + 1));
            }
        }
    }
    result.reset(first, last, width, depth);
    std::fill(column.begin(), column.end(), 0.0);
    for (int q = top; q <= std::min(height - 1, first + radius); ++q)
        for (std::int64_t i = 0; i < row_values; ++i)
            column[static_cast<size_t>(i)] += horizontal[static_cast<size_t>((q - top) * row_values + i)];
    for (int y = first; y < last; ++y) {
        const double scale = 1.0 / (std::min(height - 1, y + radius) - std::max(0, y - radius) + 1);
        float* out = result.row(y);
        for (std::int64_t i = 0; i < row_values; ++i)
            out[i] = static_cast<float>(column[static_cast<size_t>(i)] * scale);
        if (y + 1 == last)
            break;
        if (y + radius + 1 < height) {
            const float* entering = horizontal.data() + (y + radius + 1 - top) * row_values;
            for (std::int64_t i = 0; i < row_values; ++i)
                column[static_cast<size_t>(i)] += entering[i];
        }
        if (y - radius >= 0) {
            const float* leaving = horizontal.data() + (y - radius - top) * row_values;
            for (std::int64_t i = 0; i < row_values; ++i)
                column[static_cast<size_t>(i)] -= leaving[i];
        }
    }
}

// A Gaussian of width `s` truncated at `reach` and renormalised inside the
// image along one axis: per position, the weights' sum, the centre weight and
// the sum of squared weights (each over the weights inside).
struct AxisKernel {
    int reach = 0;
    std::vector<double> taps; // taps[k + reach]
    std::vector<double> sum, centre, squares;
};

AxisKernel axis_kernel(double s, int reach, int size)
{
    AxisKernel kernel;
    kernel.reach = reach;
    for (int k = -reach; k <= reach; ++k)
        kernel.taps.push_back(std::exp(-0.5 * k * k / (s * s)));
    kernel.sum.resize(size), kernel.centre.resize(size), kernel.squares.resize(size);
    for (int i = 0; i < size; ++i) {
        double sum = 0, squares = 0;
        for (int k = std::max(-reach, -i); k <= std::min(reach, size - 1 - i); ++k)
            sum += kernel.taps[k + reach], squares += kernel.taps[k + reach] * kernel.taps[k + reach];
        kernel.sum[i] = sum;
        kernel.centre[i] = kernel.taps[reach] / sum;
        kernel.squares[i] = squares / (sum * sum);
    }
    return kernel;
}

// The Gaussian blur of the input over rows [first, last), in float (8 lanes a
// step; a blur's rounding is far below the noise it averages). Each value sums
// its taps in the same order whether it lies inside or at the edge (the inner
// loops run over contiguous samples, so that they vectorise).
MODESTACK_AVX2_CLONES void gauss_blur(const ChoiceFrame& frame, const AxisKernel& along_x,
                                      const AxisKernel& along_y, int first, int last, Plane& result,
                                      std::vector<float>& scratch, std::vector<float>& sums)
{
    const int width = frame.image.width, height = frame.image.height, channels = frame.image.channels;
    const int reach = along_y.reach;
    const int top = std::max(0, first - reach), bottom = std::min(height, last + reach);
    const std::int64_t row_samples = static_cast<std::int64_t>(width) * channels;
    scratch.resize(static_cast<size_t>((bottom - top) * row_samples)); // every value written below
    sums.resize(static_cast<size_t>(row_samples));
    for (int y = top; y < bottom; ++y) {
        const float* in = frame.input + (y - frame.input_begin) * row_samples;
        float* out = scratch.data() + (y - top) * row_samples;
        // Pixels [reach, width − reach) see every tap.
        const int inner_begin = std::min(reach, width), inner_end = std::max(inner_begin, width - reach);
        const std::int64_t begin = static_cast<std::int64_t>(inner_begin) * channels,
                           end = static_cast<std::int64_t>(inner_end) * channels;
        std::fill(sums.begin() + begin, sums.begin() + end, 0.0f);
        for (int k = -reach; k <= reach; ++k) {
            const float tap = static_cast<float>(along_x.taps[k + reach]);
            const std::int64_t shift = static_cast<std::int64_t>(k) * channels;
            for (std::int64_t i = begin; i < end; ++i)
                sums[static_cast<size_t>(i)] += tap * in[i + shift];
        }
        for (int x = inner_begin; x < inner_end; ++x)
            for (int c = 0; c < channels; ++c)
                out[x * channels + c] = static_cast<float>(sums[static_cast<size_t>(x * channels + c)] /
                                                           static_cast<float>(along_x.sum[x]));
        for (int x = 0; x < width; ++x) {
            if (x == inner_begin && inner_end > inner_begin)
                x = inner_end;
            if (x >= width)
                break;
            for (int c = 0; c < channels; ++c) {
                float sum = 0;
                for (int k = std::max(-reach, -x); k <= std::min(reach, width - 1 - x); ++k)
                    sum += static_cast<float>(along_x.taps[k + reach]) * in[(x + k) * channels + c];
                out[x * channels + c] = sum / static_cast<float>(along_x.sum[x]);
            }
        }
    }
    result.reset(first, last, width, channels);
    for (int y = first; y < last; ++y) {
        std::fill(sums.begin(), sums.end(), 0.0f);
        for (int k = std::max(-reach, -y); k <= std::min(reach, height - 1 - y); ++k) {
            const float tap = static_cast<float>(along_y.taps[k + reach]);
            const float* in = scratch.data() + (y + k - top) * row_samples;
            for (std::int64_t i = 0; i < row_samples; ++i)
                sums[static_cast<size_t>(i)] += tap * in[i];
        }
        float* out = result.row(y);
        for (std::int64_t i = 0; i < row_samples; ++i)
            out[i] = sums[static_cast<size_t>(i)] / static_cast<float>(along_y.sum[y]);
    }
}

} // namespace

std::string estimator_name(Estimator estimator)
{
    switch (estimator) {
    case Estimator::Rebuild:
        return "rebuild";
    case Estimator::Input:
        return "input";
    case Estimator::Gauss1:
        return "gauss1";
    case Estimator::Gauss2:
        return "gauss2";
    case Estimator::NonLocal:
        return "nlmeans";
    }
    return "?";
}

EstimatorOptions parse_estimators(const std::string& list)
{
    EstimatorOptions options;
    std::stringstream entries(list);
    std::string entry;
    while (std::getline(entries, entry, ',')) {
        if (entry == "input")
            options.input = true;
        else if (entry == "spatial")
            options.spatial = true;
        else if (entry == "nlmeans")
            options.non_local = true;
        else if (entry != "rebuild")
            throw usage_error("--estimators: unknown estimator '" + entry +
                              "' (write rebuild, input, spatial, nlmeans)");
    }
    return options;
}

int estimator_rebuilt_reach(const EstimatorOptions& options)
{
    return options.enabled() ? 2 * options.radius + 1 : 0; // the window of v's window, and the high-pass
}

int estimator_frame_reach(const EstimatorOptions& options)
{
    return options.input ? std::max(kSpreadFrames, kMisfitFrames) : 0;
}

int estimator_input_reach(const EstimatorOptions& options)
{
    // The blurs' reach over the risk window; the non-local means' over its 3×3.
    return options.enabled() ? std::max({estimator_rebuilt_reach(options), options.radius + kGaussReach,
                                         1 + kNonLocalReach})
                             : 0;
}

void ChoiceCounts::add(const ChoiceCounts& other)
{
    for (int k = 0; k < kEstimators; ++k)
        pixels[k] += other.pixels[k], squared_error[k] += other.squared_error[k];
}

namespace {

// One sample's SURE for an estimate with derivative `slope` at the sample (the
// file comment of estimator_choice.h): (f − y)² − v + 2·v·w.
inline double sample_sure(double estimate, double sample, double v, double slope)
{
    return (estimate - sample) * (estimate - sample) - v + 2 * v * slope;
}

// Pixels of the (2·radius + 1)² window around (x, y), clipped to the image.
int clipped_window(int width, int height, int x, int y, int radius)
{
    return (std::min(height - 1, y + radius) - std::max(0, y - radius) + 1) *
           (std::min(width - 1, x + radius) - std::max(0, x - radius) + 1);
}

// Every plane of one strip's choice, kept per thread from strip to strip (fresh
// pages would cost the kernel's zeroing every time).
struct Workspace {
    Plane residual, high_pass, variance, below, below_mean, noise_scale, noise_scale_mean;
    Plane input_rows, input_high_pass, input_power, total_variance;
    std::array<Plane, 2> blurred;
    std::array<Plane, kEstimators> sure, sure_squared, difference, difference_squared;
    std::array<Plane, kEstimators> sure_mean, sure_square_mean, difference_mean, difference_square_mean,
        local_sure;
    std::vector<float> scratch, blur_sums;
    std::vector<double> column;
    // The non-local means around the pixels it may take: those pixels (`biased`),
    // the pixels that need the filter, its values and per-pixel SURE, each pixel's
    // sigma² sum (to move it in the counts).
    std::vector<std::uint8_t> biased, needed;
    Plane non_local, non_local_sure;
    std::vector<float> divergence;
    std::vector<double> non_local_scratch, pixel_squared;
};

// At the pixels of rows [row, end) where it may (work.biased: the rebuild was
// rejected and the candidate taken is biased), the non-local means takes the
// candidate's place if its SURE over the 3×3 pixels around is lower (the
// candidate's is in local_sure; the rebuild's is never compared: a rejected
// pixel with no linear candidate takes it). Sigma stays the displaced
// candidate's. The filter runs only on those pixels and their neighbours.
void replace_by_non_local(const ChoiceFrame& frame, const Plane& variance, int row, int end, float* values,
                          std::uint8_t* chosen_of_pixel, ChoiceCounts& counts, Workspace& work)
{
    const int width = frame.image.width, height = frame.image.height, channels = frame.image.channels;
    const std::int64_t row_samples = static_cast<std::int64_t>(width) * channels;
    const int first = std::max(0, row - 1), last = std::min(height, end + 1);
    auto& needed = work.needed;
    needed.assign(static_cast<size_t>(last - first) * width, 0);
    bool any = false;
    for (int y = row; y < end; ++y)
        for (int x = 0; x < width; ++x)
            if (work.biased[static_cast<size_t>(y - row) * width + x]) {
                any = true;
                for (int ny = std::max(first, y - 1); ny <= std::min(last - 1, y + 1); ++ny)
                    for (int nx = std::max(0, x - 1); nx <= std::min(width - 1, x + 1); ++nx)
                        needed[static_cast<size_t>(ny - first) * width + nx] = 1;
            }
    if (!any)
        return;
    const NonLocalInput input{width, height, channels, frame.input, frame.input_begin};
    work.non_local.reset(first, last, width, channels), work.non_local_sure.reset(first, last, width, 1);
    work.divergence.resize(static_cast<size_t>(channels));
    for (int y = first; y < last; ++y) {
        const float* noisy = frame.input + (y - frame.input_begin) * row_samples;
        for (int x = 0; x < width; ++x) {
            if (!needed[static_cast<size_t>(y - first) * width + x])
                continue;
            const float* v = variance.row(y) + static_cast<std::int64_t>(x) * channels;
            float* value = work.non_local.row(y) + static_cast<std::int64_t>(x) * channels;
            non_local_means(input, x, y, v, value, work.divergence.data(), work.non_local_scratch);
            double sure = 0;
            for (int c = 0; c < channels; ++c)
                sure += sample_sure(value[c], noisy[x * channels + c], v[c],
                                    work.divergence[static_cast<size_t>(c)]);
            work.non_local_sure.row(y)[x] = static_cast<float>(sure / channels);
        }
    }
    const auto& local_sure = work.local_sure;
    for (int y = row; y < end; ++y)
        for (int x = 0; x < width; ++x) {
            const size_t pixel = static_cast<size_t>(y - row) * width + x;
            if (!work.biased[pixel])
                continue;
            double sum = 0;
            int count = 0;
            for (int ny = std::max(first, y - 1); ny <= std::min(last - 1, y + 1); ++ny)
                for (int nx = std::max(0, x - 1); nx <= std::min(width - 1, x + 1); ++nx, ++count)
                    sum += work.non_local_sure.row(ny)[nx];
            const int displaced = chosen_of_pixel[pixel];
            if (displaced != 0 && sum / count >= local_sure[static_cast<size_t>(displaced)].row(y)[x])
                continue;
            const float* value = work.non_local.row(y) + static_cast<std::int64_t>(x) * channels;
            std::copy(value, value + channels,
                      values + (y - row) * row_samples + static_cast<std::int64_t>(x) * channels);
            chosen_of_pixel[pixel] = static_cast<std::uint8_t>(Estimator::NonLocal);
            --counts.pixels[static_cast<size_t>(displaced)];
            ++counts.pixels[static_cast<size_t>(Estimator::NonLocal)];
            counts.squared_error[static_cast<size_t>(displaced)] -= work.pixel_squared[pixel];
            counts.squared_error[static_cast<size_t>(Estimator::NonLocal)] += work.pixel_squared[pixel];
        }
}

// The squared 4-neighbour high-pass of `source` over rows [pass_begin,
// pass_end), over 1 + 1/k for k neighbours (the noise variance, for white
// noise); `source` holds one row more on each side (clipped to the image).
MODESTACK_AVX2_CLONES void squared_high_pass(const Plane& source, int height, int pass_begin, int pass_end,
                                             Plane& high_pass)
{
    const int width = source.width, channels = source.depth;
    const std::int64_t row_samples = static_cast<std::int64_t>(width) * channels;
    high_pass.reset(pass_begin, pass_end, width, channels);
    for (int y = pass_begin; y < pass_end; ++y) {
        const float* here = source.row(y);
        const float* above = y > 0 ? source.row(y - 1) : nullptr;
        const float* below = y + 1 < height ? source.row(y + 1) : nullptr;
        float* out = high_pass.row(y);
        if (above && below) // the pixels with all four neighbours, in a loop that vectorises
            for (std::int64_t i = channels; i < row_samples - channels; ++i) {
                const double neighbours =
                    static_cast<double>(here[i - channels]) + here[i + channels] + above[i] + below[i];
                const double d = here[i] - neighbours / 4;
                out[i] = static_cast<float>(d * d / 1.25);
            }
        for (int x = 0; x < width; ++x) {
            if (above && below && x == 1 && width > 2)
                x = width - 1;
            for (int c = 0; c < channels; ++c) {
                const std::int64_t i = static_cast<std::int64_t>(x) * channels + c;
                double neighbours = 0;
                int count = 0;
                if (x > 0)
                    neighbours += here[i - channels], ++count;
                if (x + 1 < width)
                    neighbours += here[i + channels], ++count;
                if (above)
                    neighbours += above[i], ++count;
                if (below)
                    neighbours += below[i], ++count;
                const double d = count ? here[i] - neighbours / count : 0.0;
                out[i] = count ? static_cast<float>(d * d / (1.0 + 1.0 / count)) : 0.0f;
            }
        }
    }
}

// choose_estimators for rows [row, end), one strip.
MODESTACK_AVX2_CLONES ChoiceCounts choose_strip(const EstimatorOptions& options, const ChoiceFrame& frame,
                                                int row, int end, float* values, float* sigma,
                                                std::uint8_t* chosen_of_pixel, Workspace& work)
{
    const int width = frame.image.width, height = frame.image.height, channels = frame.image.channels;
    const int radius = options.radius;
    const int window_begin = std::max(0, row - radius), window_end = std::min(height, end + radius);
    const int pass_begin = std::max(0, window_begin - radius),
              pass_end = std::min(height, window_end + radius);
    const std::int64_t row_samples = static_cast<std::int64_t>(width) * channels;
    auto input_at = [&](int y) { return frame.input + (y - frame.input_begin) * row_samples; };
    auto rebuilt_at = [&](int y) { return frame.rebuilt + (y - frame.rebuilt_begin) * row_samples; };
    auto kept_at = [&](int y, std::int64_t i) {
        return frame.kept_noise ? frame.kept_noise[(y - frame.rebuilt_begin) * row_samples + i]
                                : frame.leverage;
    };

    // v: the windowed mean of the residual's squared high-pass.
    // The residual over the rows the high-pass reads, then the high-pass itself.
    const int residual_begin = std::max(0, pass_begin - 1), residual_end = std::min(height, pass_end + 1);
    Plane& residual = work.residual;
    residual.reset(residual_begin, residual_end, width, channels);
    for (int y = residual_begin; y < residual_end; ++y) {
        const float *input = input_at(y), *rebuilt = rebuilt_at(y);
        float* out = residual.row(y);
        for (std::int64_t i = 0; i < row_samples; ++i)
            out[i] = input[i] - rebuilt[i];
    }
    squared_high_pass(residual, height, pass_begin, pass_end, work.high_pass);
    const Plane& high_pass = work.high_pass;
    Plane& variance = work.variance;
    box_mean(high_pass, height, radius, window_begin, window_end, variance, work.scratch, work.column);
    // The input's own windowed high-pass power (the same high-pass and window).
    // Both it and v are the noise plus something: the input's edges, or the
    // rebuild's misfit, which a rebuild far off puts in the residual, raising v
    // where it matters most (a larger v lowers a wrong rebuild's SURE and a
    // blur's, and raises the input's). v is the smaller of the two.
    Plane& rows = work.input_rows;
    rows.reset(residual_begin, residual_end, width, channels);
    for (int y = residual_begin; y < residual_end; ++y)
        std::copy(input_at(y), input_at(y) + row_samples, rows.row(y));
    squared_high_pass(rows, height, pass_begin, pass_end, work.input_high_pass);
    box_mean(work.input_high_pass, height, radius, window_begin, window_end, work.input_power, work.scratch,
             work.column);
    for (int y = window_begin; y < window_end; ++y) {
        float* v = variance.row(y);
        const float* power = work.input_power.row(y);
        for (std::int64_t i = 0; i < row_samples; ++i)
            v[i] = std::min(v[i], power[i]);
    }
    // Noise that repeats from frame to frame: the rebuild keeps it and the
    // residual does not show it. Its variance per sample is the share that
    // repeats times the input's windowed high-pass power; every candidate's
    // noise is v plus that.
    const bool repeating = frame.repeating_share > 0;
    const Plane& total = repeating ? work.total_variance : variance;
    // Noise that repeats where the risks do not count it: sigma still does
    // (every candidate carries it), the same share of the input's power (left
    // as it is: it becomes the counted part only where the risks count one).
    const bool uncounted = frame.uncounted_share > 0 && !repeating;
    if (repeating) {
        work.total_variance.reset(window_begin, window_end, width, channels);
        for (int y = window_begin; y < window_end; ++y)
            for (std::int64_t i = 0; i < row_samples; ++i) {
                float& part = work.input_power.row(y)[i]; // the input's power, then the share of it
                part = static_cast<float>(frame.repeating_share * part);
                work.total_variance.row(y)[i] = variance.row(y)[i] + part;
            }
    }
    const Plane& repeating_part = work.input_power;

    // Each candidate's value and per-pixel SURE (channel mean) over the window rows.
    std::array<bool, kEstimators> used{true, options.input, options.spatial, options.spatial};
    std::array<Plane, 2>& blurred = work.blurred;
    std::array<AxisKernel, 2> kernel_x, kernel_y;
    for (int g = 0; g < 2 && options.spatial; ++g) {
        kernel_x[g] = axis_kernel(kGaussWidths[g], kGaussReaches[g], width);
        kernel_y[g] = axis_kernel(kGaussWidths[g], kGaussReaches[g], height);
        gauss_blur(frame, kernel_x[g], kernel_y[g], window_begin, window_end, blurred[g], work.scratch,
                   work.blur_sums);
    }
    // Per pixel: each candidate's SURE and its gain over the rebuild, with their
    // squares for the tests (channel means by a reciprocal: divisions were the
    // choice's slowest steps).
    const double per_channel = 1.0 / channels;
    auto [sure, sure_squared, difference, difference_squared] =
        std::tie(work.sure, work.sure_squared, work.difference, work.difference_squared);
    for (int k = 0; k < kEstimators; ++k)
        if (used[k])
            for (Plane* plane : {&sure[k], &sure_squared[k], &difference[k], &difference_squared[k]})
                plane->reset(window_begin, window_end, width, 1);
    for (int y = window_begin; y < window_end; ++y)
        for (int x = 0; x < width; ++x) {
            std::array<double, kEstimators> pixel_sure{};
            for (int c = 0; c < channels; ++c) {
                const std::int64_t i = static_cast<std::int64_t>(x) * channels + c;
                const double input = input_at(y)[i], v = total.row(y)[i];
                const double rebuilt = rebuilt_at(y)[i];
                if (repeating) { // the rebuild keeps the repeating part whole: its slope there is 1
                    const double part = repeating_part.row(y)[i];
                    pixel_sure[0] +=
                        (rebuilt - input) * (rebuilt - input) - v + 2 * (v - part) * kept_at(y, i) + 2 * part;
                } else {
                    pixel_sure[0] += sample_sure(rebuilt, input, v, kept_at(y, i));
                }
                pixel_sure[1] += v;
                for (int g = 0; g < 2 && options.spatial; ++g) {
                    const double blur = blurred[g].row(y)[i];
                    const double centre = kernel_x[g].centre[x] * kernel_y[g].centre[y];
                    pixel_sure[2 + g] += sample_sure(blur, input, v, centre);
                }
            }
            for (int k = 0; k < kEstimators; ++k)
                if (used[k]) {
                    const double s = pixel_sure[k] * per_channel,
                                 d = (pixel_sure[0] - pixel_sure[k]) * per_channel;
                    sure[k].row(y)[x] = static_cast<float>(s),
                    sure_squared[k].row(y)[x] = static_cast<float>(s * s);
                    difference[k].row(y)[x] = static_cast<float>(d);
                    difference_squared[k].row(y)[x] = static_cast<float>(d * d);
                }
        }
    auto [sure_mean, sure_square_mean, difference_mean, difference_square_mean, local_sure] =
        std::tie(work.sure_mean, work.sure_square_mean, work.difference_mean, work.difference_square_mean,
                 work.local_sure);
    auto box = [&](const Plane& source, int reach, Plane& result) {
        box_mean(source, height, reach, row, end, result, work.scratch, work.column);
    };
    // The rebuild's local SURE is never compared, and another's pooled SURE is
    // the rebuild's less its pooled gain.
    box(sure[0], radius, sure_mean[0]);
    box(sure_squared[0], radius, sure_square_mean[0]);
    for (int k = 1; k < kEstimators; ++k)
        if (used[k]) {
            box(sure[k], 1, local_sure[k]);
            box(sure_squared[k], radius, sure_square_mean[k]);
            box(difference[k], radius, difference_mean[k]);
            box(difference_squared[k], radius, difference_square_mean[k]);
        }

    // The one-sided test's planes: per pixel the channel mean of min(input −
    // rebuild, 0), and the noise scale; then their 3×3 means.
    const bool below_test = frame.noise_scale != nullptr && options.enabled();
    if (below_test) {
        Plane &below = work.below, &noise_scale = work.noise_scale;
        const int first = std::max(0, row - 1), last = std::min(height, end + 1);
        below.reset(first, last, width, 1), noise_scale.reset(first, last, width, 1);
        for (int y = first; y < last; ++y) {
            const float *input = input_at(y), *rebuilt = rebuilt_at(y);
            for (int x = 0; x < width; ++x) {
                double negative = 0;
                for (int c = 0; c < channels; ++c) {
                    const std::int64_t i = static_cast<std::int64_t>(x) * channels + c;
                    negative += std::min(static_cast<double>(input[i]) - rebuilt[i], 0.0);
                }
                below.row(y)[x] = static_cast<float>(negative / channels);
            }
            const float* scale =
                frame.noise_scale + static_cast<std::int64_t>(y - frame.rebuilt_begin) * width;
            std::copy(scale, scale + width, noise_scale.row(y));
        }
        box(below, 1, work.below_mean);
        box(noise_scale, 1, work.noise_scale_mean);
    }
    // Half-normal moments: E[min(n, 0)] = −s/√(2π), sd = s·√(1/2 − 1/(2π)).
    constexpr double kBelowMean = 0.3989422804014327, kBelowDeviation = 0.5838126822018446;

    // The choice and its sigma at the band's own rows.
    ChoiceCounts counts;
    const double z_squared = options.significance * options.significance;
    const double below_limit = options.below_significance * options.below_significance * kBelowDeviation *
                               kBelowDeviation; // × scale², as one product in the same order
    const bool spread_test = estimator_frame_reach(options) > 0 && frame.spread != nullptr;
    // The per-pixel test's reach in spreads by the spread's estimate and number
    // of terms n (at most kMostSpreadTerms): below z·√b(n); above, a lone
    // sample's reach more.
    std::array<std::array<double, kMostSpreadTerms + 1>, kSpreadEstimates> below_reach{}, above_reach{};
    for (int e = 0; spread_test && e < kSpreadEstimates; ++e)
        for (int n = 1; n <= kMostSpreadTerms; ++n) {
            const auto i = static_cast<size_t>(e), k = static_cast<size_t>(n);
            below_reach[i][k] = options.below_significance * std::sqrt(spread_bound(n));
            above_reach[i][k] = lone_sample_reach(static_cast<SpreadEstimate>(e), n) + below_reach[i][k];
        }
    std::vector<double> floor(static_cast<size_t>(channels));
    if (options.non_local) {
        work.biased.assign(static_cast<size_t>(end - row) * width, 0);
        work.pixel_squared.resize(work.biased.size());
    }
    for (int y = row; y < end; ++y) {
        // This row of every plane the choice reads (the pixel loop is the choice's hot spot).
        std::array<const float*, kEstimators> gain_mean{}, gain_square_mean{}, near_sure{}, square_mean{};
        for (int k = 0; k < kEstimators; ++k)
            if (used[k]) {
                square_mean[k] = sure_square_mean[k].row(y);
                if (k > 0)
                    gain_mean[k] = difference_mean[k].row(y),
                    gain_square_mean[k] = difference_square_mean[k].row(y),
                    near_sure[k] = local_sure[k].row(y);
            }
        const float *pooled_sure = sure_mean[0].row(y), *variance_row = total.row(y);
        const float* repeating_row = repeating ? repeating_part.row(y) : nullptr;
        const float* uncounted_power = uncounted ? work.input_power.row(y) : nullptr;
        const float* engine_sigma = frame.sigma + (y - frame.rebuilt_begin) * row_samples;
        const float* below_row = below_test ? work.below_mean.row(y) : nullptr;
        const float* scale_row = below_test ? work.noise_scale_mean.row(y) : nullptr;
        const std::int64_t spread_offset =
            static_cast<std::int64_t>(y - frame.spread_begin) * width * kSpreadEstimates;
        const float* spread_row = spread_test ? frame.spread + spread_offset : nullptr;
        const float* terms_row = spread_test ? frame.spread_terms + spread_offset : nullptr;
        const float* misfit_row =
            frame.misfit != nullptr && options.input
                ? frame.misfit + static_cast<std::int64_t>(y - frame.misfit_begin) * width * kMisfitValues
                : nullptr;
        const double kernel_y_squares[2] = {kernel_y[0].squares.empty() ? 0.0 : kernel_y[0].squares[y],
                                            kernel_y[1].squares.empty() ? 0.0 : kernel_y[1].squares[y]};
        for (int x = 0; x < width; ++x) {
            const int window = clipped_window(width, height, x, y, radius);
            // gain > z · its standard error over the window, squared (no root
            // and no division per pixel).
            auto significant = [&](double gain, double mean, double square) {
                return gain > 0 && gain * gain * window > z_squared * std::max(square - mean * mean, 0.0);
            };
            // The rebuild unless others beat it by z standard errors over the
            // window. Of the blurs that do, the one with the larger gain over
            // the window: their risks are close, and the least SURE over nine
            // pixels picked between them by chance (on a fixed-seed shot's
            // indirect light, 2.4× the error of the wider blur alone). Then the
            // input, if it passed, where its SURE over the 3×3 pixels around is
            // lower than that blur's: the narrow window sees a blur's bias at an
            // edge that the wide one averages away (bench/results/estimators.md,
            // section 25). Not the input as the null: heavy-tailed noise makes
            // the rebuild's evidence against a firefly-ridden input weak, and
            // taking the input there cost the indirect light 10×.
            constexpr int input_estimator = static_cast<int>(Estimator::Input);
            int chosen = 0;
            double largest = 0;
            bool input_passed = false;
            for (int k = 1; k < kEstimators; ++k) {
                if (!used[k])
                    continue;
                const double mean = gain_mean[k][x];
                if (!significant(mean, mean, gain_square_mean[k][x]))
                    continue;
                if (k == input_estimator)
                    input_passed = true;
                else if (chosen == 0 || mean > largest)
                    chosen = k, largest = mean;
            }
            if (input_passed && (chosen == 0 || near_sure[input_estimator][x] < near_sure[chosen][x]))
                chosen = input_estimator;
            // Noise that repeats: the rebuild keeps that part, so its gain over
            // the input is at most the new part's; it must show it (the input is
            // the null there; on a fixed-seed shot's direct light the rebuild
            // kept where it could not was above the input in 44 % of its frames).
            if (chosen == 0 && frame.noise_repeats && used[input_estimator] &&
                !significant(-gain_mean[input_estimator][x], -gain_mean[input_estimator][x],
                             gain_square_mean[input_estimator][x]))
                chosen = input_estimator;
            // The rebuild: by a candidate's gain, by the one-sided test, or by the per-pixel test.
            bool rejected = chosen != 0;
            if (chosen == 0 && below_test) {
                const int near = clipped_window(width, height, x, y, 1);
                const double scale = scale_row[x] * frame.noise_factor;
                const double excess = below_row[x] + kBelowMean * scale;
                rejected = excess < 0 && excess * excess * near > below_limit * scale * scale;
            }
            if (rejected && chosen == 0) { // the candidate with the least SURE over the 3×3 pixels around
                double least = 0;
                for (int k = 1; k < kEstimators; ++k)
                    if (used[k] && (chosen == 0 || near_sure[k][x] < least))
                        chosen = k, least = near_sure[k][x];
            }
            // The input steady in time where the value taken, the rebuild or a
            // blur, is far from it: the input is taken (its risk is that small
            // spread; a blur's SURE at a bright edge can fall far below its true
            // error, and a blur wins the window test there as readily as anywhere).
            if (spread_row != nullptr && chosen != static_cast<int>(Estimator::Input)) {
                const float* taken = chosen == 0 ? rebuilt_at(y) : blurred[chosen - 2].row(y);
                const float* input = input_at(y) + static_cast<std::int64_t>(x) * channels;
                taken += static_cast<std::int64_t>(x) * channels;
                double distance = 0;
                for (int c = 0; c < channels; ++c)
                    distance += static_cast<double>(input[c]) - taken[c];
                distance *= per_channel;
                // z spreads' upper bound below; above, beyond what a lone bright
                // sample reaches (lone_sample_reach) by its neighbours' own z.
                // Noise that repeats is not in the spread: z of its part is added.
                double repeating_limit = 0;
                if (repeating) {
                    for (int c = 0; c < channels; ++c)
                        repeating_limit += repeating_row[static_cast<std::int64_t>(x) * channels + c];
                    repeating_limit *= per_channel * options.below_significance * options.below_significance;
                }
                for (int e = 0; e < kSpreadEstimates; ++e) { // either spread's test
                    const std::int64_t i = static_cast<std::int64_t>(x) * kSpreadEstimates + e;
                    const auto terms = static_cast<size_t>(terms_row[i]);
                    if (terms == 0)
                        continue;
                    const auto& reaches = distance < 0 ? below_reach[static_cast<size_t>(e)]
                                                       : above_reach[static_cast<size_t>(e)];
                    const double reach = reaches.at(terms);
                    if (distance * distance > reach * reach * spread_row[i] + repeating_limit)
                        rejected = true, chosen = static_cast<int>(Estimator::Input);
                }
            }
            // The rebuild's lasting misfit (temporal_misfit.h), where the rebuild
            // rates itself no better than the input's scatter: the input.
            if (misfit_row != nullptr && chosen == 0) {
                double rebuilt_variance = 0;
                for (int c = 0; c < channels; ++c) {
                    const double engine = engine_sigma[static_cast<std::int64_t>(x) * channels + c];
                    rebuilt_variance += engine * engine;
                }
                if (lasting_misfit(misfit_row + static_cast<std::int64_t>(x) * kMisfitValues,
                                   rebuilt_variance * per_channel))
                    rejected = true, chosen = static_cast<int>(Estimator::Input);
            }
            // Sigma: the chosen one's variance part, plus its pooled SURE's excess
            // (the bias the variance part does not see).
            double floor_sum = 0;
            for (int c = 0; c < channels; ++c) {
                const std::int64_t i = static_cast<std::int64_t>(x) * channels + c;
                const double v = variance_row[i];
                const double engine = engine_sigma[i];
                const double unseen = // repeating, not in the risks
                    uncounted ? static_cast<float>(frame.uncounted_share * uncounted_power[i]) : 0.0;
                floor[c] = chosen == 0   ? engine * engine + (repeating ? repeating_row[i] : 0.0) + unseen
                           : chosen == 1 ? v + unseen
                                         : (v + unseen) * kernel_x[chosen - 2].squares[x] *
                                               kernel_y_squares[chosen - 2];
                floor_sum += floor[c];
            }
            const double floor_mean = floor_sum * per_channel;
            const double risk = pooled_sure[x] - (chosen == 0 ? 0.0 : gain_mean[chosen][x]);
            const bool biased = significant(risk - floor_mean, risk, square_mean[chosen][x]);
            // In sigma, the rebuild's excess counts where significant: its risk is
            // about a hundredth of the noise and the pooled SURE's own noise a tenth,
            // so a positive part would be that noise (on indirect light it made
            // sigma 4–10× too wide). A blur's bias is of the order of that noise,
            // and cut at z standard errors it left the blurs' sigma short (DiffDir:
            // 5 % of the blurs' values beyond 3σ, median |err|/σ 1.2 on the
            // Cycles sweep_room); its positive part, an estimate of bias² on the
            // safe side, counts whole (bench/results/estimators.md, section 16).
            const bool blur = chosen >= static_cast<int>(Estimator::Gauss1);
            const double excess = blur ? std::max(risk - floor_mean, 0.0) : biased ? risk - floor_mean : 0;
            // The non-local means may displace the candidate taken only where that
            // candidate's own risk shows a bias its variance part does not explain
            // (a blur across an edge), or where no linear candidate could be taken.
            if (options.non_local && rejected && (chosen == 0 || biased))
                work.biased[static_cast<size_t>(y - row) * width + x] = 1;
            const float* source = chosen == 0   ? rebuilt_at(y)
                                  : chosen == 1 ? input_at(y)
                                                : blurred[chosen - 2].row(y);
            const std::int64_t out = (y - row) * row_samples + static_cast<std::int64_t>(x) * channels;
            double pixel_squared =
                0; // one addition to the count per pixel, not a chain through it per channel
            for (int c = 0; c < channels; ++c) {
                values[out + c] = source[static_cast<std::int64_t>(x) * channels + c];
                const double squared = floor[static_cast<size_t>(c)] + excess;
                sigma[out + c] = static_cast<float>(std::max(squared, 0.0)); // its root below
                pixel_squared += squared;
            }
            counts.squared_error[chosen] += pixel_squared;
            if (options.non_local)
                work.pixel_squared[static_cast<size_t>(y - row) * width + x] = pixel_squared;
            chosen_of_pixel[static_cast<std::int64_t>(y - row) * width + x] =
                static_cast<std::uint8_t>(chosen);
            ++counts.pixels[chosen];
        }
    }
    if (options.non_local)
        replace_by_non_local(frame, total, row, end, values, chosen_of_pixel, counts, work);
    // The roots in one loop that vectorises (one at a time they were a tenth of the choice).
    const std::int64_t samples = (end - row) * row_samples;
    for (std::int64_t i = 0; i < samples; ++i)
        sigma[i] = std::sqrt(sigma[i]);
    return counts;
}

} // namespace

void noise_scale_rows(const float* noise_variance, std::int64_t pixels, int channels, float* scale)
{
    for (std::int64_t pixel = 0; pixel < pixels; ++pixel) {
        double sum = 0;
        for (int c = 0; c < channels; ++c)
            sum += std::sqrt(std::max(static_cast<double>(noise_variance[pixel * channels + c]), 0.0));
        scale[pixel] = static_cast<float>(sum / channels);
    }
}

ChoiceCounts choose_estimators(const EstimatorOptions& options, const ChoiceFrame& frame, int row, int end,
                               float* values, float* sigma, std::uint8_t* chosen)
{
    const int height = frame.image.height, reach = estimator_rebuilt_reach(options);
    if (frame.rebuilt_begin > std::max(0, row - reach) || frame.rebuilt_end < std::min(height, end + reach) ||
        frame.input_begin > std::max(0, row - estimator_input_reach(options)) ||
        frame.input_end < std::min(height, end + estimator_input_reach(options)) ||
        frame.input_begin > frame.rebuilt_begin || frame.input_end < frame.rebuilt_end)
        throw internal_error("choose_estimators: the frame's rows do not cover the choice's reach");
    thread_local Workspace work; // no task runs inside a choice, so no other choice shares it
    const std::int64_t row_samples = static_cast<std::int64_t>(frame.image.width) * frame.image.channels;
    ChoiceCounts counts;
    for (int strip = row; strip < end;
         strip += kStripRows) // strips bound the planes; the bits do not see them
        counts.add(choose_strip(options, frame, strip, std::min(end, strip + kStripRows),
                                values + (strip - row) * row_samples, sigma + (strip - row) * row_samples,
                                chosen + static_cast<std::int64_t>(strip - row) * frame.image.width, work));
    return counts;
}

} // namespace modestack::denoise
