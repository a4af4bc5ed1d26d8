#include "core/refine/selection.h"

#include "core/refine/blend.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace modestack::refine {
namespace {

constexpr int kBins = 1 << 14;
constexpr double kLowestScore = 1e-6;
constexpr double kHighestScore = 1e6;

double log_span()
{
    return std::log(kHighestScore / kLowestScore);
}

int bin_of(float score)
{
    if (!(score > kLowestScore))
        return 0;
    if (!(score < kHighestScore))
        return kBins - 1;
    int bin = static_cast<int>(std::log(score / kLowestScore) / log_span() * kBins);
    return std::clamp(bin, 0, kBins - 1);
}

float lower_edge_of(int bin)
{
    if (bin <= 0)
        return 0.0f;
    return static_cast<float>(kLowestScore * std::exp(log_span() * bin / kBins));
}

} // namespace

void relative_error_scores(const float* value, const float* sigma, std::size_t pixels, int channels,
                           float dark_floor, float* scores)
{
    double floor_squared = static_cast<double>(dark_floor) * dark_floor;
    for (std::size_t p = 0; p < pixels; ++p) {
        float score = 0.0f;
        for (int c = 0; c < channels; ++c) {
            double v = value[p * channels + c], s = sigma[p * channels + c];
            if (!std::isfinite(s)) {
                score = std::numeric_limits<float>::infinity();
                break;
            }
            double relative = std::fabs(s) / std::sqrt(v * v + floor_squared);
            score = std::max(score, std::isfinite(relative) ? static_cast<float>(relative)
                                                            : std::numeric_limits<float>::infinity());
        }
        scores[p] = score;
    }
}

void refine_gains(const float* value, const float* sigma, const float* input_variance, double variance_scale,
                  std::size_t pixels, int channels, float dark_floor, float* gains)
{
    const double floor_squared = static_cast<double>(dark_floor) * dark_floor;
    for (std::size_t p = 0; p < pixels; ++p) {
        const float* v = value + p * channels;
        const float* s = sigma + p * channels;
        const float* r = input_variance + p * channels;
        double denoised = 0, rendered = 0;
        bool finite = true;
        for (int c = 0; c < channels; ++c) {
            finite = finite && std::isfinite(s[c]) && std::isfinite(r[c]);
            denoised += static_cast<double>(s[c]) * s[c];
            rendered += std::fmax(0.0, r[c] * variance_scale);
        }
        if (!finite) {
            gains[p] = std::numeric_limits<float>::infinity();
            continue;
        }
        const double w = rendered_share(denoised, rendered);
        double gain = 0;
        for (int c = 0; c < channels; ++c) {
            const double before = static_cast<double>(s[c]) * s[c];
            const double after = blended_variance(w, std::fmax(0.0, r[c] * variance_scale), s[c]);
            gain += (before - after) / (static_cast<double>(v[c]) * v[c] + floor_squared);
        }
        const double mean = gain / channels;
        gains[p] = std::isfinite(mean) ? static_cast<float>(mean) : std::numeric_limits<float>::infinity();
    }
}

float gain_threshold(double shot_relative_mse, int input_spp, int refine_spp)
{
    const double threshold = static_cast<double>(refine_spp) / input_spp * shot_relative_mse;
    return threshold > 0 ? static_cast<float>(threshold) : std::numeric_limits<float>::infinity();
}

ScoreHistogram::ScoreHistogram() : m_counts(kBins, 0) {}

void ScoreHistogram::add(const float* scores, std::size_t count)
{
    for (std::size_t i = 0; i < count; ++i)
        ++m_counts[bin_of(scores[i])];
    m_total += static_cast<std::int64_t>(count);
}

float ScoreHistogram::threshold_for_fraction(double fraction) const
{
    if (!(fraction > 0) || m_total == 0)
        return std::numeric_limits<float>::infinity();
    if (fraction >= 1)
        return 0.0f;
    auto wanted = static_cast<std::int64_t>(std::floor(fraction * static_cast<double>(m_total)));
    std::int64_t from_top = 0;
    for (int bin = kBins - 1; bin >= 0; --bin) {
        if (from_top + m_counts[bin] > wanted)
            return bin == kBins - 1 ? std::numeric_limits<float>::infinity() : lower_edge_of(bin + 1);
        from_top += m_counts[bin];
    }
    return 0.0f;
}

std::vector<std::uint8_t> select_pixels(const float* scores, std::size_t pixels, float threshold)
{
    std::vector<std::uint8_t> selection(pixels, 0);
    for (std::size_t p = 0; p < pixels; ++p)
        selection[p] = scores[p] >= threshold && scores[p] > 0 ? 1 : 0;
    return selection;
}

void drop_isolated_pixels(std::vector<std::uint8_t>& selection, int width, int height, int min_neighbours)
{
    const std::vector<std::uint8_t> input = selection;
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            std::size_t p = static_cast<std::size_t>(y) * width + x;
            if (!input[p])
                continue;
            int neighbours = 0;
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    int u = x + dx, v = y + dy;
                    if ((dx != 0 || dy != 0) && u >= 0 && u < width && v >= 0 && v < height)
                        neighbours += input[static_cast<std::size_t>(v) * width + u] ? 1 : 0;
                }
            if (neighbours < min_neighbours)
                selection[p] = 0;
        }
}

} // namespace modestack::refine
