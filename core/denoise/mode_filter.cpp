#include "core/denoise/mode_filter.h"

#include "core/common/error.h"
#include "core/common/progress.h"
#include "core/common/scratch_buffer.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace modestack::denoise {
namespace {

using lowrank::BandView;
using lowrank::ImageBandShape;
using lowrank::MutableBandView;

// Largest noise scale a mode gets. SVD over-fitting raised the noise of pure-noise
// modes by at most ~2.05× on our renders; a larger high-pass ratio is texture or
// edges, not noise, and must not make a clean (or nearly clean) shot look noisy.
constexpr double kMaximumNoiseScale = 4.0;

int kernel_radius(double width) { return width > 0 ? static_cast<int>(std::ceil(2.5 * width)) : 0; }

// Normalised 1D Gaussian of width σ on [−radius, radius].
std::vector<double> gaussian_1d(double width)
{
    int radius = kernel_radius(width);
    std::vector<double> kernel(2 * radius + 1);
    double sum = 0;
    for (int d = -radius; d <= radius; ++d)
        sum += kernel[d + radius] = std::exp(-0.5 * d * d / (width * width));
    for (double& value : kernel)
        value /= sum;
    return kernel;
}

// Σ taps and Σ taps² over the part of a window of `radius` centred at `at` that
// lies inside [0, length): a window's weight and noise gain where the band clips it.
void clipped_tap_sums(const std::vector<double>& taps, int radius, int at, int length, double& sum, double& squares)
{
    sum = squares = 0;
    for (int q = std::max(0, at - radius); q <= std::min(length - 1, at + radius); ++q)
        sum += taps[q - at + radius], squares += taps[q - at + radius] * taps[q - at + radius];
}

// Smooths `image` ([y][x][c] rows of the band) with the separable Gaussian of
// `width`, clipped at the band's edges and renormalised by the clipped window's
// weight (a box product, so still separable), and hands each smoothed row y of
// [y0, y1) to row_done(y, values), from parallel workers.
template <typename RowDone>
void smooth_clipped(const float* image, const ImageBandShape& shape, double width, int y0, int y1, RowDone&& row_done)
{
    const std::vector<double> taps = gaussian_1d(width);
    const int radius = kernel_radius(width);
    const std::int64_t row_length = static_cast<std::int64_t>(shape.width) * shape.channels;
    const int first_row = std::max(0, y0 - radius), last_row = std::min(shape.height - 1, y1 - 1 + radius);
    const auto clipped_weight = [&](int at, int length) {
        double sum = 0, squares = 0;
        clipped_tap_sums(taps, radius, at, length, sum, squares);
        return sum;
    };
    std::vector<double> horizontal(static_cast<std::size_t>(last_row - first_row + 1) * row_length);
    tbb::parallel_for(first_row, last_row + 1, [&](int y) {
        const float* row = image + y * row_length;
        double* target = horizontal.data() + (y - first_row) * row_length;
        for (int x = 0; x < shape.width; ++x)
            for (int c = 0; c < shape.channels; ++c) {
                double sum = 0;
                for (int q = std::max(0, x - radius); q <= std::min(shape.width - 1, x + radius); ++q)
                    sum += taps[q - x + radius] * row[q * shape.channels + c];
                target[x * shape.channels + c] = sum;
            }
    });
    std::vector<double> column_weight(static_cast<std::size_t>(shape.width));
    for (int x = 0; x < shape.width; ++x)
        column_weight[static_cast<std::size_t>(x)] = clipped_weight(x, shape.width);
    tbb::parallel_for(y0, y1, [&](int y) {
        const double row_weight = clipped_weight(y, shape.height);
        std::vector<double> sum(static_cast<std::size_t>(row_length), 0.0);
        for (int q = std::max(0, y - radius); q <= std::min(shape.height - 1, y + radius); ++q) {
            const double tap = taps[q - y + radius];
            const double* source = horizontal.data() + (q - first_row) * row_length;
            for (std::int64_t k = 0; k < row_length; ++k)
                sum[static_cast<std::size_t>(k)] += tap * source[k];
        }
        for (int x = 0; x < shape.width; ++x) {
            const double total = column_weight[static_cast<std::size_t>(x)] * row_weight;
            for (int c = 0; c < shape.channels; ++c)
                sum[static_cast<std::size_t>(x * shape.channels + c)] /= total;
        }
        row_done(y, static_cast<const double*>(sum.data()));
    });
}

// The guide of a band: c_1 pre-smoothed (clipped and renormalised at the band's
// edges) and the noise variance of each of its samples.
struct Guide {
    std::vector<double> value;
    std::vector<double> noise;
    const float* features = nullptr;  // normalised features [y][x][k] (feature_guide.h), or none
    int feature_channels = 0;
};

Guide build_guide(const BandView& coefficients, const std::vector<float>& noise_variance, const ImageBandShape& shape,
                  double smoothing)
{
    const std::int64_t row_length = static_cast<std::int64_t>(shape.width) * shape.channels;
    const std::size_t samples = static_cast<std::size_t>(row_length) * shape.height;
    Guide guide;
    guide.value.assign(samples, 0.0);
    guide.noise.assign(samples, 0.0);
    if (smoothing <= 0) {
        for (std::size_t i = 0; i < samples; ++i)
            guide.value[i] = coefficients.data[i], guide.noise[i] = noise_variance[i];
        return guide;
    }
    double gain_1d = 0;  // Σ k²: the white-noise variance gain per dimension (interior)
    for (double value : gaussian_1d(smoothing))
        gain_1d += value * value;
    smooth_clipped(coefficients.data, shape, smoothing, 0, shape.height, [&](int y, const double* row) {
        const std::int64_t first = y * row_length;
        std::copy(row, row + row_length, guide.value.begin() + first);
        for (std::int64_t k = first; k < first + row_length; ++k)
            guide.noise[static_cast<std::size_t>(k)] = noise_variance[static_cast<std::size_t>(k)] * gain_1d * gain_1d;
    });
    return guide;
}

// Weights of one candidate filter around pixel (x, y), clipped to the band.
class WeightWindow {
public:
    WeightWindow(const Guide& guide, const ImageBandShape& shape) : m_guide(guide), m_shape(shape) {}

    // Fills the weights of `candidate` (width > 0) around (x, y); returns their sum.
    double compute(const FilterCandidate& candidate, int x, int y)
    {
        const int radius = kernel_radius(candidate.width);
        x0 = std::max(0, x - radius), x1 = std::min(m_shape.width - 1, x + radius);
        y0 = std::max(0, y - radius), y1 = std::min(m_shape.height - 1, y + radius);
        weights.resize(static_cast<std::size_t>(x1 - x0 + 1) * (y1 - y0 + 1));
        const double spatial_scale = -0.5 / (candidate.width * candidate.width);
        const double range_scale =
            candidate.range > 0 ? -0.5 / (candidate.range * candidate.range * m_shape.channels) : 0.0;
        const int feature_channels = m_guide.feature_channels;
        const double feature_scale =
            candidate.feature_range > 0 && m_guide.features
                ? -0.5 / (candidate.feature_range * candidate.feature_range * feature_channels)
                : 0.0;
        const float* centre_features =
            feature_scale != 0 ? m_guide.features + (static_cast<std::int64_t>(y) * m_shape.width + x) * feature_channels
                               : nullptr;
        const std::int64_t row_length = static_cast<std::int64_t>(m_shape.width) * m_shape.channels;
        const std::int64_t centre = y * row_length + static_cast<std::int64_t>(x) * m_shape.channels;
        // Without a range or feature term the weight depends on the squared distance
        // alone: looked up, not an exp per tap (the same values).
        const bool unguided = range_scale == 0 && feature_scale == 0;
        const double* spatial = unguided ? spatial_weights(candidate.width, radius).data() : nullptr;
        double sum = 0;
        std::size_t index = 0;
        for (int qy = y0; qy <= y1; ++qy)
            for (int qx = x0; qx <= x1; ++qx, ++index) {
                const int distance2 = (qx - x) * (qx - x) + (qy - y) * (qy - y);
                double exponent = spatial_scale * distance2;
                if (range_scale != 0) {
                    const std::int64_t other = qy * row_length + static_cast<std::int64_t>(qx) * m_shape.channels;
                    double distance = 0;  // squared guide difference in units of its noise
                    for (int c = 0; c < m_shape.channels; ++c) {
                        double difference = m_guide.value[centre + c] - m_guide.value[other + c];
                        distance += difference * difference /
                                    (m_guide.noise[centre + c] + m_guide.noise[other + c] + 1e-30);
                    }
                    exponent += range_scale * distance;
                }
                if (feature_scale != 0) {
                    const float* other =
                        m_guide.features + (static_cast<std::int64_t>(qy) * m_shape.width + qx) * feature_channels;
                    double distance = 0;
                    for (int k = 0; k < feature_channels; ++k) {
                        const double difference = static_cast<double>(centre_features[k]) - other[k];
                        distance += difference * difference;
                    }
                    exponent += feature_scale * distance;
                }
                // A guided weight in float precision (1e-7) is plenty for a filter
                // weight, and expf costs a fraction of exp.
                sum += weights[index] = unguided ? spatial[distance2]
                                                 : std::exp(static_cast<float>(exponent));
            }
        self = static_cast<std::size_t>(y - y0) * (x1 - x0 + 1) + (x - x0);
        return sum;
    }

    // Σ_q w_q · image(q, c) over the window for every channel c into sums[c],
    // image = [y][x][c] of the band, each sum in the order apply() takes. RGB (the
    // usual layer) in one pass over the weights, with its sums in registers.
    void apply_all(const float* image, double* sums) const
    {
        if (m_shape.channels != 3) {
            for (int c = 0; c < m_shape.channels; ++c)
                sums[c] = apply(image, c);
            return;
        }
        const std::int64_t row_length = static_cast<std::int64_t>(m_shape.width) * 3;
        double red = 0, green = 0, blue = 0;
        std::size_t index = 0;
        for (int qy = y0; qy <= y1; ++qy) {
            const float* row = image + qy * row_length + static_cast<std::int64_t>(x0) * 3;
            for (int qx = x0; qx <= x1; ++qx, ++index, row += 3) {
                const double weight = weights[index];
                red += weight * row[0];
                green += weight * row[1];
                blue += weight * row[2];
            }
        }
        sums[0] = red, sums[1] = green, sums[2] = blue;
    }

    // Σ_q w_q · image(q, c) over the window, image = [y][x][c] of the band.
    double apply(const float* image, int c) const
    {
        const std::int64_t row_length = static_cast<std::int64_t>(m_shape.width) * m_shape.channels;
        double sum = 0;
        std::size_t index = 0;
        for (int qy = y0; qy <= y1; ++qy) {
            const float* row = image + qy * row_length + c;
            for (int qx = x0; qx <= x1; ++qx, ++index)
                sum += weights[index] * row[static_cast<std::int64_t>(qx) * m_shape.channels];
        }
        return sum;
    }

    std::vector<double> weights;
    std::size_t self = 0;
    int x0 = 0, x1 = 0, y0 = 0, y1 = 0;

private:
    // exp(−d² / 2σ²) for every squared distance d² a window of `radius` holds.
    const std::vector<double>& spatial_weights(double width, int radius)
    {
        for (const auto& [table_width, table] : m_spatial_tables)
            if (table_width == width)
                return table;
        std::vector<double> table(static_cast<std::size_t>(2 * radius * radius + 1));
        const double spatial_scale = -0.5 / (width * width);
        for (std::size_t d2 = 0; d2 < table.size(); ++d2)
            table[d2] = std::exp(spatial_scale * static_cast<int>(d2));
        m_spatial_tables.emplace_back(width, std::move(table));
        return m_spatial_tables.back().second;
    }

    const Guide& m_guide;
    const ImageBandShape& m_shape;
    std::vector<std::pair<double, std::vector<double>>> m_spatial_tables;
};

// A filter without a range or feature term is a Gaussian, separable also where
// the band clips it (the clipped window is a box): it is applied as a horizontal
// and a vertical pass, 2(2r+1) taps per sample instead of (2r+1)², with the
// window's normalisation and noise gain Σw²/(Σw)² as products of the passes'.
// Writes rows [valid_y0, valid_y1) of `image` filtered into `out` and each valid
// pixel's gain into `gains`.
void separable_gaussian(const float* image, const ImageBandShape& shape, int valid_y0, int valid_y1, double width,
                        float* out, float* gains)
{
    const std::vector<double> taps = gaussian_1d(width);  // normalised: only ratios matter below
    const int radius = kernel_radius(width);
    const std::int64_t row_length = static_cast<std::int64_t>(shape.width) * shape.channels;
    std::vector<double> column_sum(static_cast<std::size_t>(shape.width)), column_squares(column_sum.size());
    for (int x = 0; x < shape.width; ++x)
        clipped_tap_sums(taps, radius, x, shape.width, column_sum[x], column_squares[x]);
    smooth_clipped(image, shape, width, valid_y0, valid_y1, [&](int y, const double* row) {
        double row_sum = 0, row_squares = 0;
        clipped_tap_sums(taps, radius, y, shape.height, row_sum, row_squares);
        float* target = out + (y - valid_y0) * row_length;
        for (std::int64_t k = 0; k < row_length; ++k)
            target[k] = static_cast<float>(row[k]);
        float* row_gains = gains + static_cast<std::int64_t>(y - valid_y0) * shape.width;
        for (int x = 0; x < shape.width; ++x) {
            const double total = column_sum[x] * row_sum;
            row_gains[x] = static_cast<float>(column_squares[x] * row_squares / (total * total));
        }
    });
}

void check_band(const BandView& coefficients, const std::vector<float>& noise_variance, const ImageBandShape& shape,
                int valid_y0, int valid_y1, const char* what)
{
    const std::int64_t samples = static_cast<std::int64_t>(shape.width) * shape.height * shape.channels;
    if (coefficients.rows != samples || static_cast<std::int64_t>(noise_variance.size()) != samples ||
        valid_y0 < 0 || valid_y1 > shape.height || valid_y0 > valid_y1)
        throw internal_error(std::string(what) + ": band shapes do not match");
}

}  // namespace

std::vector<FilterCandidate> filter_candidates(const ModeFilterOptions& options)
{
    std::vector<FilterCandidate> candidates{{0.0, 0.0}};
    for (double width : options.widths)
        if (width > 0)
            candidates.push_back({width, 0.0});
    for (double range : options.range_scales)
        for (double width : options.widths)
            if (width > 0 && range > 0)
                candidates.push_back({width, range});
    if (options.feature_channels > 0)
        for (double feature_range : options.feature_ranges) {
            if (feature_range <= 0)
                continue;
            for (double width : options.widths)
                if (width > 0)
                    candidates.push_back({width, 0.0, feature_range});
            for (double range : options.range_scales)
                for (double width : options.widths)
                    if (width > 0 && range > 0)
                        candidates.push_back({width, range, feature_range});
        }
    return candidates;
}

int mode_filter_halo(const ModeFilterOptions& options)
{
    int widest = 0;
    for (double width : options.widths)
        widest = std::max(widest, kernel_radius(width));
    return widest + std::max(kernel_radius(options.guide_smoothing), options.noise_radius);
}

void coefficient_noise_variance(const BandView& noisy, const BandView& coefficients, const ImageBandShape& shape,
                                int radius, std::vector<float>& variance)
{
    const std::int64_t row_length = static_cast<std::int64_t>(shape.width) * shape.channels;
    if (noisy.rows != row_length * shape.height || coefficients.rows != noisy.rows)
        throw internal_error("coefficient_noise_variance: band shapes do not match");
    if (coefficients.frames >= noisy.frames)
        throw internal_error("coefficient_noise_variance: needs fewer modes than frames");
    const double degrees_of_freedom = noisy.frames - coefficients.frames;
    // This thread's band-sized scratch, kept from band to band (fresh buffers cost
    // the kernel's page clearing every band); named once here because a
    // thread_local named inside the workers' lambdas would be theirs.
    static thread_local ScratchBuffer<double> this_thread_left, this_thread_horizontal;
    ScratchBuffer<double>& left = this_thread_left;
    ScratchBuffer<double>& horizontal = this_thread_horizontal;
    left.resize(static_cast<std::size_t>(noisy.rows));
    horizontal.resize(left.size());
    tbb::parallel_for(0, shape.height, [&](int y) {
        // Frame by frame over the row (each frame's row is contiguous), each sample's
        // sum still in frame order and then mode order.
        double* energy = left.data() + y * row_length;
        std::fill_n(energy, row_length, 0.0);
        for (int t = 0; t < noisy.frames; ++t) {
            const float* frame_row = noisy.data + t * noisy.frame_stride + y * row_length;
            for (std::int64_t k = 0; k < row_length; ++k)
                energy[k] += static_cast<double>(frame_row[k]) * frame_row[k];
        }
        for (int j = 0; j < coefficients.frames; ++j) {
            const float* mode_row = coefficients.data + j * coefficients.frame_stride + y * row_length;
            for (std::int64_t k = 0; k < row_length; ++k)
                energy[k] -= static_cast<double>(mode_row[k]) * mode_row[k];
        }
        for (std::int64_t k = 0; k < row_length; ++k)
            energy[k] = std::max(0.0, energy[k]);
    });
    tbb::parallel_for(0, shape.height, [&](int y) {
        for (int x = 0; x < shape.width; ++x)
            for (int c = 0; c < shape.channels; ++c) {
                double sum = 0;
                for (int q = std::max(0, x - radius); q <= std::min(shape.width - 1, x + radius); ++q)
                    sum += left[y * row_length + q * shape.channels + c];
                horizontal[y * row_length + x * shape.channels + c] = sum;
            }
    });
    variance.resize(left.size());
    tbb::parallel_for(0, shape.height, [&](int y) {
        const int first = std::max(0, y - radius), last = std::min(shape.height - 1, y + radius);
        for (int x = 0; x < shape.width; ++x) {
            const int count_x = std::min(shape.width - 1, x + radius) - std::max(0, x - radius) + 1;
            const double count = static_cast<double>(count_x) * (last - first + 1) * degrees_of_freedom;
            for (int c = 0; c < shape.channels; ++c) {
                double sum = 0;
                for (int q = first; q <= last; ++q)
                    sum += horizontal[q * row_length + x * shape.channels + c];
                variance[y * row_length + x * shape.channels + c] = static_cast<float>(sum / count);
            }
        }
    });
}

SureSurvey::SureSurvey(const ModeFilterOptions& options, int width, int height, int channels, int modes)
    : m_options(options), m_candidates(filter_candidates(options)), m_width(width), m_height(height),
      m_channels(channels), m_modes(modes), m_stride(1)
{
    const std::int64_t pixels = static_cast<std::int64_t>(width) * height;
    while (pixels / (static_cast<std::int64_t>(m_stride) * m_stride) > std::max<std::int64_t>(1, options.survey_pixels))
        ++m_stride;
    m_rows.resize(static_cast<std::size_t>(height));
}

void SureSurvey::add_band(const BandView& coefficients, const std::vector<float>& noise_variance,
                          const ImageBandShape& shape, int band_y0, int valid_y0, int valid_y1, const float* features)
{
    check_band(coefficients, noise_variance, shape, valid_y0, valid_y1, "SureSurvey::add_band");
    if (coefficients.frames != m_modes || shape.width != m_width || shape.channels != m_channels)
        throw internal_error("SureSurvey::add_band: band does not match the survey");
    Guide guide = build_guide(coefficients, noise_variance, shape, m_options.guide_smoothing);
    if (m_options.feature_channels > 0) {
        if (!features)
            throw internal_error("SureSurvey::add_band: the survey expects feature rows");
        guide.features = features, guide.feature_channels = m_options.feature_channels;
    }
    const int candidates = static_cast<int>(m_candidates.size());
    const std::int64_t row_length = static_cast<std::int64_t>(shape.width) * shape.channels;
    throw_if_cancelled();
    tbb::parallel_for(valid_y0, valid_y1, [&](int y) {
        const int image_y = band_y0 + y;
        std::vector<double>& sums = m_rows[static_cast<std::size_t>(image_y)];
        sums.assign(static_cast<std::size_t>(m_modes) * candidates * 2 + 2 * m_modes + 1, 0.0);
        if (image_y % m_stride != 0)
            return;
        double* fit_trace = sums.data();
        double* energy = fit_trace + static_cast<std::size_t>(m_modes) * candidates * 2;
        double& noise = energy[m_modes];
        double* high_pass_energy = energy + m_modes + 1;
        WeightWindow window(guide, shape);
        std::vector<double> applied(static_cast<std::size_t>(shape.channels));
        for (int x = 0; x < shape.width; x += m_stride) {
            const std::int64_t pixel = y * row_length + static_cast<std::int64_t>(x) * shape.channels;
            for (int c = 0; c < shape.channels; ++c) {
                const double variance = noise_variance[pixel + c];
                noise += variance;
                for (int j = 0; j < m_modes; ++j) {
                    const float* image = coefficients.data + j * coefficients.frame_stride;
                    energy[j] += static_cast<double>(image[pixel + c]) * image[pixel + c];
                    double neighbours = 0;
                    int count = 0;
                    if (x > 0)
                        neighbours += image[pixel + c - shape.channels], ++count;
                    if (x + 1 < shape.width)
                        neighbours += image[pixel + c + shape.channels], ++count;
                    if (y > 0)
                        neighbours += image[pixel + c - row_length], ++count;
                    if (y + 1 < shape.height)
                        neighbours += image[pixel + c + row_length], ++count;
                    if (count == 0)
                        continue;
                    // White noise of variance v gives HP² of mean v·(1 + 1/count).
                    const double high_pass = image[pixel + c] - neighbours / count;
                    high_pass_energy[j] += high_pass * high_pass / (1.0 + 1.0 / count);
                }
            }
            for (int k = 1; k < candidates; ++k) {
                const bool guided = m_candidates[k].range > 0;
                const double sum = window.compute(m_candidates[k], x, y);
                const double self = window.weights[window.self] / sum;
                for (int j = guided ? 1 : 0; j < m_modes; ++j) {
                    const float* image = coefficients.data + j * coefficients.frame_stride;
                    double* slot = fit_trace + (static_cast<std::size_t>(j) * candidates + k) * 2;
                    window.apply_all(image, applied.data());
                    for (int c = 0; c < shape.channels; ++c) {
                        const double difference = applied[static_cast<std::size_t>(c)] / sum - image[pixel + c];
                        slot[0] += difference * difference;
                        slot[1] += noise_variance[pixel + c] * self;
                    }
                }
            }
        }
    });
}

std::size_t SureSurvey::row_sum_length() const
{
    return static_cast<std::size_t>(m_modes) * m_candidates.size() * 2 + 2 * m_modes + 1;
}

std::vector<std::vector<double>> SureSurvey::row_sums(int row_begin, int row_end) const
{
    if (row_begin < 0 || row_end > m_height || row_begin > row_end)
        throw internal_error("SureSurvey::row_sums: rows out of range");
    return {m_rows.begin() + row_begin, m_rows.begin() + row_end};
}

void SureSurvey::restore_row_sums(int row_begin, std::vector<std::vector<double>> sums)
{
    if (row_begin < 0 || row_begin + static_cast<std::int64_t>(sums.size()) > m_height)
        throw internal_error("SureSurvey::restore_row_sums: rows out of range");
    for (std::size_t i = 0; i < sums.size(); ++i) {
        if (!sums[i].empty() && sums[i].size() != row_sum_length())
            throw internal_error("SureSurvey::restore_row_sums: a row does not match the survey");
        m_rows[row_begin + i] = std::move(sums[i]);
    }
}

ModeFilterPlan SureSurvey::finish(int fixed_rank) const
{
    const int candidates = static_cast<int>(m_candidates.size());
    std::vector<double> totals(static_cast<std::size_t>(m_modes) * candidates * 2 + 2 * m_modes + 1, 0.0);
    for (const std::vector<double>& row : m_rows)  // image-row order: the same for any banding
        for (std::size_t i = 0; i < row.size(); ++i)
            totals[i] += row[i];
    const double* energy = totals.data() + static_cast<std::size_t>(m_modes) * candidates * 2;
    const double noise = energy[m_modes];
    const double* high_pass_energy = energy + m_modes + 1;

    ModeFilterPlan plan;
    plan.candidates = m_candidates;
    plan.survey_stride = m_stride;
    plan.guide_smoothing = m_options.guide_smoothing;
    plan.feature_channels = m_options.feature_channels;
    std::vector<double> cumulative_gain;
    double gain = 0;
    for (int j = 0; j < m_modes; ++j) {
        ModeFilterChoice choice;
        // The mode's own noise energy over Σ v_p (1 when nothing is measured),
        // capped: see kMaximumNoiseScale.
        choice.noise_scale = noise > 0 ? std::min(kMaximumNoiseScale, high_pass_energy[j] / noise) : 1.0;
        const double mode_noise = noise * choice.noise_scale;
        choice.unfiltered_sure = mode_noise;  // identity: ‖c − c‖² + 2 Σ v − Σ v
        choice.sure = mode_noise;
        for (int k = 1; k < candidates; ++k) {
            if (j == 0 && m_candidates[k].range > 0)
                continue;  // c_1 cannot guide its own filter
            const double* slot = totals.data() + (static_cast<std::size_t>(j) * candidates + k) * 2;
            const double sure = slot[0] + choice.noise_scale * 2 * slot[1] - mode_noise;
            if (sure < choice.sure)
                choice.sure = sure, choice.candidate = k;
        }
        choice.width = m_candidates[choice.candidate].width;
        choice.range = m_candidates[choice.candidate].range;
        choice.feature_range = m_candidates[choice.candidate].feature_range;
        choice.signal = energy[j] - mode_noise;
        gain += choice.signal - choice.sure;
        cumulative_gain.push_back(gain);
        plan.modes.push_back(choice);
    }
    if (fixed_rank > 0) {
        plan.rank = std::min(fixed_rank, m_modes);
        plan.reasoning = fmt::format("N = {} as asked; each mode's filter width chosen by SURE", plan.rank);
    } else {
        plan.rank = 1;
        for (int n = 2; n <= m_modes; ++n)
            if (cumulative_gain[n - 1] > cumulative_gain[plan.rank - 1])
                plan.rank = n;
        double total = 0;
        for (int j = 0; j < m_modes; ++j)
            total += energy[j];
        plan.reasoning = fmt::format(
            "mode-filter SURE: the first {} of {} surveyed modes, each filtered at its SURE-best width, lower the "
            "estimated error most ({:.3g} of the surveyed energy)",
            plan.rank, m_modes, total > 0 ? cumulative_gain[plan.rank - 1] / total : 0.0);
    }
    for (int j = 0; j < plan.rank; ++j)
        plan.modes[j].kept = true;
    return plan;
}

void filter_coefficients(const BandView& coefficients, const std::vector<float>& noise_variance,
                         const ImageBandShape& shape, int valid_y0, int valid_y1, const ModeFilterPlan& plan,
                         int rank, MutableBandView filtered, std::vector<float>& gains, const float* features)
{
    check_band(coefficients, noise_variance, shape, valid_y0, valid_y1, "filter_coefficients");
    const std::int64_t row_length = static_cast<std::int64_t>(shape.width) * shape.channels;
    if (rank > coefficients.frames || rank > static_cast<int>(plan.modes.size()) || filtered.frames != rank ||
        filtered.rows != row_length * (valid_y1 - valid_y0))
        throw internal_error("filter_coefficients: output does not match the plan");
    const std::int64_t valid_pixels = static_cast<std::int64_t>(shape.width) * (valid_y1 - valid_y0);
    gains.assign(static_cast<std::size_t>(valid_pixels) * rank, 1.0f);
    Guide guide = build_guide(coefficients, noise_variance, shape, plan.guide_smoothing);
    if (plan.feature_channels > 0) {
        if (!features)
            throw internal_error("filter_coefficients: the plan expects feature rows");
        guide.features = features, guide.feature_channels = plan.feature_channels;
    }
    throw_if_cancelled();
    // Modes whose filter has no range or feature term are filtered separably here;
    // the per-pixel windows below do the others.
    std::vector<bool> separable(static_cast<std::size_t>(rank), false);
    for (int j = 0; j < rank; ++j) {
        const FilterCandidate& candidate = plan.candidates[plan.modes[j].candidate];
        const bool feature_term = candidate.feature_range > 0 && guide.features;
        if (candidate.width <= 0 || candidate.range > 0 || feature_term)
            continue;
        separable[static_cast<std::size_t>(j)] = true;
        separable_gaussian(coefficients.data + j * coefficients.frame_stride, shape, valid_y0, valid_y1,
                           candidate.width, filtered.data + j * filtered.frame_stride,
                           gains.data() + j * valid_pixels);
    }
    tbb::parallel_for(valid_y0, valid_y1, [&](int y) {
        WeightWindow window(guide, shape);
        std::vector<double> applied(static_cast<std::size_t>(shape.channels));
        for (int x = 0; x < shape.width; ++x) {
            const std::int64_t pixel = y * row_length + static_cast<std::int64_t>(x) * shape.channels;
            const std::int64_t out = pixel - valid_y0 * row_length;
            const std::int64_t out_pixel = static_cast<std::int64_t>(y - valid_y0) * shape.width + x;
            int windowed = -1;  // the candidate window.weights hold: modes often share one
            double sum = 0, squares = 0;
            for (int j = 0; j < rank; ++j) {
                if (separable[static_cast<std::size_t>(j)])
                    continue;
                const FilterCandidate& candidate = plan.candidates[plan.modes[j].candidate];
                const float* image = coefficients.data + j * coefficients.frame_stride;
                if (candidate.width <= 0) {
                    for (int c = 0; c < shape.channels; ++c)
                        filtered.at(out + c, j) = image[pixel + c];
                    continue;
                }
                if (plan.modes[j].candidate != windowed) {
                    windowed = plan.modes[j].candidate;
                    sum = window.compute(candidate, x, y);
                    squares = 0;
                    for (double weight : window.weights)
                        squares += weight * weight;
                }
                gains[static_cast<std::size_t>(j * valid_pixels + out_pixel)] = static_cast<float>(squares / (sum * sum));
                window.apply_all(image, applied.data());
                for (int c = 0; c < shape.channels; ++c)
                    filtered.at(out + c, j) = static_cast<float>(applied[static_cast<std::size_t>(c)] / sum);
            }
        }
    });
}

}  // namespace modestack::denoise
