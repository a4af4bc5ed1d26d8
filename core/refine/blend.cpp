#include "core/refine/blend.h"

#include <cmath>

namespace modestack::refine {

double rendered_share(double denoised_variance, double rendered_variance)
{
    const double total = denoised_variance + rendered_variance;
    return total > 0 ? denoised_variance / total : 1.0;
}

void blend_refined(const float* weights, std::size_t pixels, int channels, const float* rendered,
                   const float* rendered_variance, float* value, float* sigma)
{
    for (std::size_t p = 0; p < pixels; ++p) {
        double w = weights[p];
        if (!(w > 0))
            continue;
        double denoised_variance = 0, rendered_mean_variance = 0;
        for (int c = 0; c < channels; ++c) {
            const std::size_t i = p * channels + c;
            denoised_variance += static_cast<double>(sigma[i]) * sigma[i];
            rendered_mean_variance += std::fmax(0.0, rendered_variance[i]);
        }
        w *= rendered_share(denoised_variance, rendered_mean_variance);
        for (int c = 0; c < channels; ++c) {
            std::size_t i = p * channels + c;
            double old_sigma = sigma[i];
            double variance = std::fmax(0.0, rendered_variance[i]);
            value[i] = static_cast<float>(w * rendered[i] + (1.0 - w) * value[i]);
            sigma[i] = static_cast<float>(std::sqrt(blended_variance(w, variance, old_sigma)));
        }
    }
}

double estimated_relative_mse(const float* value, const float* sigma, std::size_t pixels, int channels,
                              float dark_floor)
{
    if (pixels == 0 || channels == 0)
        return 0.0;
    double floor_squared = static_cast<double>(dark_floor) * dark_floor, sum = 0.0;
    for (std::size_t i = 0; i < pixels * channels; ++i) {
        double v = value[i], s = sigma[i];
        sum += s * s / (v * v + floor_squared);
    }
    return sum / static_cast<double>(pixels * channels);
}

} // namespace modestack::refine
