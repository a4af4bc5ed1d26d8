#include "core/denoise/non_local_means.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace modestack::denoise {
namespace {
// Rousselle et al.'s k: how many noise deviations a patch may differ by and
// still count as alike (their 0.45 for colour patches).
constexpr double kSimilarity = 0.45;
} // namespace

void non_local_means(const NonLocalInput& frame, int x, int y, const float* variance, float* value,
                     float* divergence, std::vector<double>& scratch)
{
    const int width = frame.width, height = frame.height, channels = frame.channels;
    const std::int64_t row_samples = static_cast<std::int64_t>(width) * frame.channels;
    auto sample = [&](int row, int column, int c) {
        return static_cast<double>(frame.input[(row - frame.input_begin) * row_samples +
                                               static_cast<std::int64_t>(column) * frame.channels + c]);
    };
    // Per channel: 1/den, the distance's scale, and the noise a patch pair shows alone (2v).
    scratch.assign(static_cast<size_t>(6 * channels), 0.0);
    double* inverse = scratch.data();
    double* noise = inverse + channels;
    double* weighted = noise + channels; // Σw·y_q
    double* moving_value = weighted + channels;
    double* moving_square = moving_value + channels;
    double* patch = moving_square + channels;
    for (int c = 0; c < channels; ++c) {
        const double v = std::max(static_cast<double>(variance[c]), 0.0);
        inverse[c] = 1.0 / (1e-10 + 2 * kSimilarity * kSimilarity * v);
        noise[c] = 2 * v;
    }
    // Σw and Σw·y_q; over the neighbours whose weight moves with the centre (a
    // distance above 0), a = w/n, Σa·y_q and Σa·y_q² for the divergence.
    double weight = 0, moving = 0;
    for (int dy = -kNonLocalSearch; dy <= kNonLocalSearch; ++dy) {
        if (y + dy < 0 || y + dy >= height)
            continue;
        for (int dx = -kNonLocalSearch; dx <= kNonLocalSearch; ++dx) {
            if (x + dx < 0 || x + dx >= width)
                continue;
            // The 3×3 patches around p and q = p + (dx, dy), where both lie inside.
            std::fill(patch, patch + channels, 0.0);
            int count = 0;
            const int row_first = std::max({0, y - 1, -dy}),
                      row_last = std::min({height - 1, y + 1, height - 1 - dy});
            const int column_first = std::max({0, x - 1, -dx}),
                      column_last = std::min({width - 1, x + 1, width - 1 - dx});
            for (int py = row_first; py <= row_last; ++py)
                for (int px = column_first; px <= column_last; ++px, ++count)
                    for (int c = 0; c < channels; ++c) {
                        const double d = sample(py, px, c) - sample(py + dy, px + dx, c);
                        patch[c] += d * d;
                    }
            // The distance in units of the centre's noise, less what noise alone gives.
            double distance = 0;
            for (int c = 0; c < channels; ++c)
                distance += (patch[c] / count - noise[c]) * inverse[c];
            distance /= channels;
            const double w = std::exp(-std::max(distance, 0.0));
            const double a = distance > 0 ? w / count : 0.0;
            weight += w, moving += a;
            for (int c = 0; c < channels; ++c) {
                const double q = sample(y + dy, x + dx, c);
                weighted[c] += w * q;
                moving_value[c] += a * q, moving_square[c] += a * q * q;
            }
        }
    }
    for (int c = 0; c < channels; ++c) {
        const double result = weighted[c] / weight, centre = sample(y, x, c);
        // ∂value/∂centre = (w_pp + Σ_q ∂w_q/∂y_p · (y_q − value)) / Σw, where
        // ∂w_q/∂y_p = a·2(y_q − y_p)·inverse/C from the centre's own patch term.
        const double spread =
            moving_square[c] - (centre + result) * moving_value[c] + result * centre * moving;
        value[c] = static_cast<float>(result);
        divergence[c] = static_cast<float>((1.0 + 2.0 * inverse[c] / channels * spread) / weight);
    }
}

} // namespace modestack::denoise
