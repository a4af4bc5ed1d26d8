#include "core/denoise/rank_map.h"

#include "core/common/error.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace modestack::denoise {
namespace {

// Spreads of the pure-noise window energy a local signal must exceed to count.
// Without it a pixel keeps every noise mode whose window happens to hold a little
// more than its expected noise (half of them), and the best-prefix rule, a maximum
// over many such noisy sums, keeps most modes. Two spreads let a pure-noise mode in
// about 2 % of the time.
constexpr double kSignificance = 2.0;

}  // namespace

void RankMapSummary::add(const std::vector<float>& ranks)
{
    if (histogram.empty())
        histogram.assign(static_cast<size_t>(largest_rank) + 1, 0);
    for (float kept_modes : ranks) {
        const int bin = std::clamp(static_cast<int>(std::floor(kept_modes)), 0, largest_rank);
        ++histogram[static_cast<size_t>(bin)];
        m_micro_rank_sum += std::llround(static_cast<double>(kept_modes) * 1e6);
        smallest = m_any ? std::min(smallest, static_cast<double>(kept_modes)) : kept_modes;
        largest = m_any ? std::max(largest, static_cast<double>(kept_modes)) : kept_modes;
        m_any = true;
    }
    m_pixels += static_cast<std::int64_t>(ranks.size());
}

void RankMapSummary::finish()
{
    mean = m_pixels > 0 ? static_cast<double>(m_micro_rank_sum) / 1e6 / static_cast<double>(m_pixels) : 0.0;
}

void local_rank(const lowrank::BandView& coefficients, const std::vector<float>& noise_variance,
                const lowrank::ImageBandShape& shape, int valid_y0, int valid_y1, const ModeFilterPlan& plan,
                int min_modes, int modes, const std::vector<float>& gains, int radius, std::vector<float>& weights,
                std::vector<float>& ranks)
{
    const std::int64_t row_length = static_cast<std::int64_t>(shape.width) * shape.channels;
    const std::int64_t band_pixels = static_cast<std::int64_t>(shape.width) * shape.height;
    const std::int64_t valid_pixels = static_cast<std::int64_t>(shape.width) * (valid_y1 - valid_y0);
    if (min_modes < 1 || min_modes > modes || modes > coefficients.frames || modes > static_cast<int>(plan.modes.size()) ||
        coefficients.rows != row_length * shape.height ||
        static_cast<std::int64_t>(noise_variance.size()) != coefficients.rows ||
        static_cast<std::int64_t>(gains.size()) < valid_pixels * modes)
        throw internal_error("local_rank: band shapes do not match");

    // Per pixel of the band: Σ_c c_j² for each mode and Σ_c v; then box sums over
    // the window (rows clipped to the band, which carries enough halo rows).
    std::vector<double> pixel_sums(static_cast<size_t>(band_pixels) * (modes + 1));
    tbb::parallel_for(0, shape.height, [&](int y) {
        for (int x = 0; x < shape.width; ++x) {
            const std::int64_t pixel = static_cast<std::int64_t>(y) * shape.width + x;
            const std::int64_t sample = pixel * shape.channels;
            double* sums = pixel_sums.data() + pixel * (modes + 1);
            for (int j = 0; j < modes; ++j) {
                double energy = 0;
                for (int c = 0; c < shape.channels; ++c)
                    energy += static_cast<double>(coefficients.at(sample + c, j)) * coefficients.at(sample + c, j);
                sums[j] = energy;
            }
            double noise = 0;
            for (int c = 0; c < shape.channels; ++c)
                noise += noise_variance[static_cast<size_t>(sample + c)];
            sums[modes] = noise;
        }
    });
    std::vector<double> horizontal(pixel_sums.size());
    tbb::parallel_for(0, shape.height, [&](int y) {
        for (int x = 0; x < shape.width; ++x)
            for (int k = 0; k <= modes; ++k) {
                double sum = 0;
                for (int q = std::max(0, x - radius); q <= std::min(shape.width - 1, x + radius); ++q)
                    sum += pixel_sums[static_cast<size_t>((static_cast<std::int64_t>(y) * shape.width + q) * (modes + 1) + k)];
                horizontal[static_cast<size_t>((static_cast<std::int64_t>(y) * shape.width + x) * (modes + 1) + k)] = sum;
            }
    });

    weights.assign(static_cast<size_t>(valid_pixels) * modes, 0.0f);
    ranks.assign(static_cast<size_t>(valid_pixels), 0.0f);
    tbb::parallel_for(valid_y0, valid_y1, [&](int y) {
        std::vector<double> window(static_cast<size_t>(modes) + 1), signal(static_cast<size_t>(modes)),
            kept_noise(static_cast<size_t>(modes));
        const int first = std::max(0, y - radius), last = std::min(shape.height - 1, y + radius);
        for (int x = 0; x < shape.width; ++x) {
            std::fill(window.begin(), window.end(), 0.0);
            for (int q = first; q <= last; ++q)
                for (int k = 0; k <= modes; ++k)
                    window[static_cast<size_t>(k)] +=
                        horizontal[static_cast<size_t>((static_cast<std::int64_t>(q) * shape.width + x) * (modes + 1) + k)];
            const std::int64_t out_pixel = static_cast<std::int64_t>(y - valid_y0) * shape.width + x;
            const int window_pixels = (last - first + 1) * (std::min(shape.width - 1, x + radius) - std::max(0, x - radius) + 1);
            const double samples = static_cast<double>(window_pixels) * shape.channels;
            // The best prefix of modes by Σ (S_j − K_j), at least min_modes.
            int kept = 1;
            double gain = 0, best = 0;
            for (int j = 0; j < modes; ++j) {
                const double mode_noise = plan.modes[static_cast<size_t>(j)].noise_scale * window[static_cast<size_t>(modes)];
                // Σ c² over the window spreads by about √(2/n) of its noise part on pure
                // noise: only the signal beyond kSignificance such spreads counts.
                const double spread = mode_noise * std::sqrt(2.0 / samples);
                signal[static_cast<size_t>(j)] =
                    std::max(0.0, window[static_cast<size_t>(j)] - mode_noise - kSignificance * spread);
                kept_noise[static_cast<size_t>(j)] =
                    mode_noise * gains[static_cast<size_t>(static_cast<std::int64_t>(j) * valid_pixels + out_pixel)];
                gain += signal[static_cast<size_t>(j)] - kept_noise[static_cast<size_t>(j)];
                if (j < min_modes || gain > best)
                    best = gain, kept = j + 1;
            }
            double fraction = 0;
            if (kept < modes) {
                const double s = signal[static_cast<size_t>(kept)], k = kept_noise[static_cast<size_t>(kept)];
                fraction = s + k > 0 ? s / (s + k) : 0.0;
            }
            for (int j = 0; j < modes; ++j)
                weights[static_cast<size_t>(static_cast<std::int64_t>(j) * valid_pixels + out_pixel)] =
                    j < kept ? 1.0f : j == kept ? static_cast<float>(fraction) : 0.0f;
            ranks[static_cast<size_t>(out_pixel)] = static_cast<float>(kept + fraction);
        }
    });
}

}  // namespace modestack::denoise
