#include "core/refine/equal_quality.h"

#include <algorithm>
#include <limits>

namespace modestack::refine {

double relative_mse(const float* x, const float* reference, std::size_t count)
{
    double sum = 0;
    for (std::size_t i = 0; i < count; ++i) {
        double difference = static_cast<double>(x[i]) - reference[i];
        sum += difference * difference / (static_cast<double>(reference[i]) * reference[i] + 0.01);
    }
    return count ? sum / static_cast<double>(count) : 0.0;
}

double noise_constant(double noisy_relative_mse, double spp, double reference_spp)
{
    return noisy_relative_mse / (1.0 / spp + 1.0 / reference_spp);
}

double equivalent_spp(double relative_mse, double c, double reference_spp)
{
    double excess = relative_mse - c / reference_spp;
    return excess > 0 ? c / excess : std::numeric_limits<double>::infinity();
}

TimeModel fit_time_model(double spp_a, double seconds_a, double spp_b, double seconds_b)
{
    TimeModel model;
    model.k = spp_b != spp_a ? (seconds_b - seconds_a) / (spp_b - spp_a) : 0.0;
    model.t0 = std::max(0.0, seconds_a - model.k * spp_a);
    return model;
}

} // namespace modestack::refine
