#include "core/denoise/mode_filter.h"

#include "core/denoise/filter_weights.h"
#include "core/denoise/guided_filter.h"

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

// The per-sample ratio q = HP(c_j)² / (1 + 1/n) / v_p of each mode, counted in
// log-spaced bins (8 per octave over [2^-8, 2^8), one bin below and one above):
// counts add exactly in any order, so the median is that of one run however the
// rows were split.
constexpr int kRatioBinsPerOctave = 8;
constexpr int kRatioOctaves = 16;
constexpr int kRatioBins = kRatioBinsPerOctave * kRatioOctaves + 2;
const double kLowestRatio = std::ldexp(1.0, -kRatioOctaves / 2); // the first counted bin's lower edge

int ratio_bin(double ratio)
{
    if (!(ratio >= kLowestRatio))
        return 0;
    const int bin =
        static_cast<int>(std::floor((std::log2(ratio) + kRatioOctaves / 2) * kRatioBinsPerOctave)) + 1;
    return std::min(bin, kRatioBins - 1);
}

// The median of counted ratios, interpolated in log space within its bin (the
// range's edges for the bins below and above it; 0 without counts).
double ratio_median(const double* counts)
{
    double total = 0;
    for (int b = 0; b < kRatioBins; ++b)
        total += counts[b];
    if (total <= 0)
        return 0;
    double below = 0;
    for (int b = 0; b < kRatioBins; ++b) {
        if (below + counts[b] >= 0.5 * total) {
            if (b == 0)
                return kLowestRatio;
            const double edge = static_cast<double>(b - 1) / kRatioBinsPerOctave - kRatioOctaves / 2;
            if (b == kRatioBins - 1)
                return std::exp2(edge);
            const double inside = counts[b] > 0 ? (0.5 * total - below) / counts[b] : 0.0;
            return std::exp2(edge + inside / kRatioBinsPerOctave);
        }
        below += counts[b];
    }
    return 0;
}

using lowrank::BandView;
using lowrank::ImageBandShape;
using lowrank::MutableBandView;

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

void coefficient_noise_variance(const BandView& noisy, const BandView& coefficients,
                                const ImageBandShape& shape, int radius, std::vector<float>& variance,
                                const Eigen::VectorXd& frame_scales)
{
    if (frame_scales.size() != 0 && frame_scales.size() != noisy.frames)
        throw internal_error("coefficient_noise_variance: a scale per frame is needed");
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
            if (frame_scales.size() == 0) {
                for (std::int64_t k = 0; k < row_length; ++k)
                    energy[k] += static_cast<double>(frame_row[k]) * frame_row[k];
                continue;
            }
            const double weight = 1.0 / lowrank::frame_noise_variance(frame_scales, t);
            for (std::int64_t k = 0; k < row_length; ++k)
                energy[k] += static_cast<double>(frame_row[k]) * frame_row[k] * weight;
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
    if (m_options.feature_channels > 0 && !features)
        throw internal_error("SureSurvey::add_band: the survey expects feature rows");
    const Guide guide = build_guide(coefficients, noise_variance, shape, m_options.guide_smoothing, features,
                                    m_options.feature_channels);
    int widest = 0;
    for (const FilterCandidate& candidate : m_candidates)
        widest = std::max(widest, kernel_radius(candidate.width));
    const int candidates = static_cast<int>(m_candidates.size());
    const std::int64_t row_length = static_cast<std::int64_t>(shape.width) * shape.channels;
    throw_if_cancelled();
    // The surveyed modes of the rows the windows reach, as [y][x][mode][c]: every
    // tap of a window then adds one contiguous run of all the modes' samples.
    const int per_pixel = m_modes * shape.channels;
    int first_surveyed = valid_y0;
    while (first_surveyed < valid_y1 && (band_y0 + first_surveyed) % m_stride != 0)
        ++first_surveyed;
    ScratchBuffer<float> pixels;  // every value written before it is read
    int reach_y0 = 0;
    if (first_surveyed < valid_y1) {
        const int last_surveyed = first_surveyed + (valid_y1 - 1 - first_surveyed) / m_stride * m_stride;
        reach_y0 = std::max(0, first_surveyed - widest);
        const int reach_y1 = std::min(shape.height, last_surveyed + widest + 1);
        pixels.resize(static_cast<std::size_t>(reach_y1 - reach_y0) * shape.width * per_pixel);
        tbb::parallel_for(reach_y0, reach_y1, [&](int y) {
            for (int x = 0; x < shape.width; ++x) {
                const std::int64_t pixel = static_cast<std::int64_t>(y) * shape.width + x;
                float* target = pixels.data() + (pixel - static_cast<std::int64_t>(reach_y0) * shape.width) * per_pixel;
                for (int j = 0; j < m_modes; ++j)
                    for (int c = 0; c < shape.channels; ++c)
                        target[j * shape.channels + c] =
                            coefficients.data[j * coefficients.frame_stride + pixel * shape.channels + c];
            }
        });
    }
    tbb::parallel_for(valid_y0, valid_y1, [&](int y) {
        const int image_y = band_y0 + y;
        std::vector<double>& sums = m_rows[static_cast<std::size_t>(image_y)];
        if (image_y % m_stride != 0) { // a row off the survey's grid adds nothing: held empty
            sums.clear();
            return;
        }
        sums.assign(row_sum_length(), 0.0);
        double* fit_trace = sums.data();
        double* energy = fit_trace + static_cast<std::size_t>(m_modes) * candidates * 2;
        double& noise = energy[m_modes];
        double* high_pass_energy = energy + m_modes + 1;
        double* ratio_counts = high_pass_energy + m_modes; // [mode][bin]
        WeightWindow window(guide, widest);
        std::vector<float> applied(static_cast<std::size_t>(per_pixel));
        for (int x = 0; x < shape.width; x += m_stride) {
            window.centre(x, y);
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
                    const double power = high_pass * high_pass / (1.0 + 1.0 / count);
                    high_pass_energy[j] += power;
                    if (variance > 0)
                        ratio_counts[j * kRatioBins + ratio_bin(power / variance)] += 1;
                }
            }
            for (int k = 1; k < candidates; ++k) {
                const bool guided = m_candidates[k].range > 0;
                const double sum = window.compute(m_candidates[k]);
                const double self = window.weights[window.self] / sum;
                window.apply(pixels.data(), reach_y0, per_pixel, applied.data());
                for (int j = guided ? 1 : 0; j < m_modes; ++j) {
                    const float* image = coefficients.data + j * coefficients.frame_stride;
                    double* slot = fit_trace + (static_cast<std::size_t>(j) * candidates + k) * 2;
                    for (int c = 0; c < shape.channels; ++c) {
                        const double difference =
                            applied[static_cast<std::size_t>(j * shape.channels + c)] / sum - image[pixel + c];
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
    return static_cast<std::size_t>(m_modes) * m_candidates.size() * 2 + 2 * m_modes + 1 +
           static_cast<std::size_t>(m_modes) * kRatioBins;
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

ModeFilterPlan SureSurvey::finish(int fixed_modes, double noise_scale_cap) const
{
    const int candidates = static_cast<int>(m_candidates.size());
    std::vector<double> totals(row_sum_length(), 0.0);
    for (const std::vector<double>& row : m_rows)  // image-row order: the same for any banding
        for (std::size_t i = 0; i < row.size(); ++i)
            totals[i] += row[i];
    const double* energy = totals.data() + static_cast<std::size_t>(m_modes) * candidates * 2;
    const double noise = energy[m_modes];
    const double* high_pass_energy = energy + m_modes + 1;
    const double* ratio_counts = high_pass_energy + m_modes;
    std::vector<double> ratio_medians(static_cast<std::size_t>(m_modes));
    for (int j = 0; j < m_modes; ++j)
        ratio_medians[j] = ratio_median(ratio_counts + j * kRatioBins);
    // The later half of the surveyed modes are the most nearly pure noise: their
    // mean ratio over their median is what the noise's spread of ratios gives
    // (more than a Gaussian's 2.2 on rendered noise, heterogeneous from pixel to
    // pixel, and more in the modes that gather its noisiest pixels): the largest.
    double noise_mean_per_median = 0;
    for (int j = m_modes / 2; j < m_modes && noise > 0; ++j)
        if (ratio_medians[j] > 0)
            noise_mean_per_median =
                std::max(noise_mean_per_median, high_pass_energy[j] / noise / ratio_medians[j]);

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
        // capped at noise_scale_cap (kMaximumNoiseScale unless noise repeats).
        choice.noise_scale = noise > 0 ? std::min(noise_scale_cap, high_pass_energy[j] / noise) : 1.0;
        // A mean at the cap measured edges (see the file comment); edges raise
        // the mean of a lit mode's ratios, not their median, so the scale is then
        // what its median implies by the noise's own spread (at most the cap, at
        // least v_p). Not where noise that repeats is counted (a raised cap):
        // that noise gathers in the first modes with a spread of its own.
        if (noise_mean_per_median > 0 && noise_scale_cap <= kMaximumNoiseScale &&
            choice.noise_scale >= noise_scale_cap)
            choice.noise_scale =
                std::min(choice.noise_scale, std::max(1.0, ratio_medians[j] * noise_mean_per_median));
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
    if (fixed_modes > 0) {
        plan.kept_modes = std::min(fixed_modes, m_modes);
        plan.reasoning =
            fmt::format("N = {} as asked; each mode's filter width chosen by SURE", plan.kept_modes);
    } else {
        plan.kept_modes = 1;
        for (int n = 2; n <= m_modes; ++n)
            if (cumulative_gain[n - 1] > cumulative_gain[plan.kept_modes - 1])
                plan.kept_modes = n;
        double total = 0;
        for (int j = 0; j < m_modes; ++j)
            total += energy[j];
        plan.reasoning = fmt::format("mode-filter SURE: the first {} of {} surveyed modes, each filtered at "
                                     "its SURE-best width, lower the "
                                     "estimated error most ({:.3g} of the surveyed energy)",
                                     plan.kept_modes, m_modes,
                                     total > 0 ? cumulative_gain[plan.kept_modes - 1] / total : 0.0);
    }
    for (int j = 0; j < plan.kept_modes; ++j)
        plan.modes[j].kept = true;
    return plan;
}

void filter_coefficients(const BandView& coefficients, const std::vector<float>& noise_variance,
                         const ImageBandShape& shape, int valid_y0, int valid_y1, const ModeFilterPlan& plan,
                         int kept_modes, MutableBandView filtered, std::vector<float>& gains,
                         const float* features)
{
    check_band(coefficients, noise_variance, shape, valid_y0, valid_y1, "filter_coefficients");
    const std::int64_t row_length = static_cast<std::int64_t>(shape.width) * shape.channels;
    if (kept_modes > coefficients.frames || kept_modes > static_cast<int>(plan.modes.size()) ||
        filtered.frames != kept_modes || filtered.rows != row_length * (valid_y1 - valid_y0))
        throw internal_error("filter_coefficients: output does not match the plan");
    const std::int64_t valid_pixels = static_cast<std::int64_t>(shape.width) * (valid_y1 - valid_y0);
    gains.assign(static_cast<std::size_t>(valid_pixels) * kept_modes, 1.0f);
    if (plan.feature_channels > 0 && !features)
        throw internal_error("filter_coefficients: the plan expects feature rows");
    throw_if_cancelled();
    // Each mode: unfiltered (copied), a plain Gaussian (separable), or guided.
    std::vector<GuidedImage> guided;
    for (int j = 0; j < kept_modes; ++j) {
        const FilterCandidate& candidate = plan.candidates[plan.modes[j].candidate];
        const float* image = coefficients.data + j * coefficients.frame_stride;
        float* out = filtered.data + j * filtered.frame_stride;
        const bool feature_term = candidate.feature_range > 0 && plan.feature_channels > 0;
        if (candidate.width <= 0) {
            std::copy(image + valid_y0 * row_length, image + valid_y1 * row_length, out);
        } else if (candidate.range <= 0 && !feature_term) {
            separable_gaussian(image, shape, valid_y0, valid_y1, candidate.width, out, gains.data() + j * valid_pixels);
        } else {
            guided.push_back({candidate, image, out, gains.data() + j * valid_pixels});
        }
    }
    if (!guided.empty()) {
        const Guide guide = build_guide(coefficients, noise_variance, shape, plan.guide_smoothing, features,
                                        plan.feature_channels);
        guided_filter(guide, valid_y0, valid_y1, guided);
    }
}

}  // namespace modestack::denoise
