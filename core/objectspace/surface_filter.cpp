// SURE-chosen Gaussian filtering over surface points (see surface_filter.h).
#include "core/objectspace/surface_filter.h"

#include "core/objectspace/surface_kernel.h"
#include "core/objectspace/surface_neighbours.h"
#include "core/objectspace/surface_noise.h"
#include "core/objectspace/surface_sure.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>

namespace modestack::objectspace {
namespace {

// Neighbours must face within ~25° of each other: the same surface, not the wall across a corner.
constexpr double kMinNormalCosine = 0.9;

std::string reasoning_of(const SurfaceFilterChoice& choice, bool filter, int best, double spacing)
{
    if (!filter)
        return "off";
    if (best == 0)
        return fmt::format("none: the unfiltered values have the lowest SURE ({:.4g} per value)", choice.risks[0]);
    return fmt::format("Gaussian of {} spacings ({:.3g} m), SURE {:.4g} per value against {:.4g} unfiltered",
                       choice.width, choice.width * spacing, choice.risks[best], choice.risks[0]);
}

// Frame t filtered with the chosen width (0: as it is) and its sigma =
// sqrt(Σ H² s² h_t + b_t²), with b_t² = max(0, μ_t² − s²(1 − h_t)/|W|), μ_t the
// window's mean residual.
void filter_frame(const SurfaceNeighbours& neighbours, double width, double spacing, double window,
                  const std::vector<double>& noise, int channels, SurfaceFrame& frame)
{
    const std::int64_t count = neighbours.count();
    const std::size_t ch = static_cast<std::size_t>(channels);
    const std::vector<float> rebuilt(frame.values, frame.values + count * ch);
    auto residual_of = [&](std::int64_t q, std::size_t c) {
        return static_cast<double>(frame.noisy[q * ch + c]) - rebuilt[q * ch + c];
    };
    const double h = frame.leverage;
    std::vector<double> weights{1.0};
    for (std::int64_t p = 0; p < count; ++p) {
        const std::int64_t* ids = neighbours.ids(p);
        if (width > 0)
            gaussian_weights(neighbours, p, width, spacing, weights);
        const int members = neighbours.count_within(p, window);
        for (std::size_t c = 0; c < ch; ++c) {
            double filtered = 0, kept_noise = 0, mean_residual = 0;
            for (std::size_t n = 0; n < weights.size(); ++n) {
                filtered += weights[n] * rebuilt[ids[n] * ch + c];
                kept_noise += weights[n] * weights[n] * noise[ids[n] * ch + c] * h;
            }
            for (int n = 0; n < members; ++n)
                mean_residual += residual_of(ids[n], c);
            mean_residual /= members;
            const double bias = std::max(0.0, mean_residual * mean_residual - noise[p * ch + c] * (1 - h) / members);
            frame.values[p * ch + c] = static_cast<float>(filtered);
            frame.sigma[p * ch + c] = static_cast<float>(std::sqrt(kept_noise + bias));
        }
    }
}

} // namespace

SurfaceFilterChoice filter_surfaces(const SurfaceSamples& samples, const SurfaceFilterOptions& options, int channels,
                                    std::vector<SurfaceFrame>& frames)
{
    SurfaceFilterChoice choice;
    choice.widths.push_back(0);
    if (options.filter)
        for (double width : options.widths)
            if (width > 0)
                choice.widths.push_back(width);
    if (samples.count() == 0 || frames.empty() || !(samples.spacing > 0))
        throw std::invalid_argument("filter_surfaces: no points, frames or spacing");
    const double spacing = samples.spacing;
    const double window = options.window_spacings * spacing;
    const double widest = *std::max_element(choice.widths.begin(), choice.widths.end()) * spacing;
    const SurfaceNeighbours neighbours(samples, std::max(kReachInSigmas * widest, window), kMinNormalCosine);
    choice.mean_neighbours = neighbours.mean_size();

    const std::vector<double> noise =
        surface_noise_variance(neighbours, window, frames, channels, options.kept_modes);
    choice.risks = surface_sure_risks(neighbours, spacing, choice.widths, noise, frames, channels);
    const int best = static_cast<int>(std::min_element(choice.risks.begin(), choice.risks.end()) - choice.risks.begin());
    choice.width = choice.widths[best];
    choice.reasoning = reasoning_of(choice, options.filter, best, spacing);

    tbb::parallel_for(0, static_cast<int>(frames.size()), [&](int t) {
        filter_frame(neighbours, choice.width, spacing, window, noise, channels, frames[t]);
    });
    return choice;
}

} // namespace modestack::objectspace
