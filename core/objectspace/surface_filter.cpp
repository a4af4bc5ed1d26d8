// SURE-chosen Gaussian filtering over surface points (see surface_filter.h).
#include "core/objectspace/surface_filter.h"

#include "core/objectspace/surface_cells.h"
#include "core/objectspace/surface_kernel.h"
#include "core/objectspace/surface_modes.h"
#include "core/objectspace/surface_neighbours.h"
#include "core/objectspace/surface_noise.h"
#include "core/objectspace/surface_sure.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <optional>
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
        return fmt::format("none: the unfiltered values have the lowest SURE ({:.4g} per value)",
                           choice.risks[0]);
    return fmt::format("Gaussian of {} spacings ({:.3g} m), SURE {:.4g} per value against {:.4g} unfiltered",
                       choice.width, choice.width * spacing, choice.risks[best], choice.risks[0]);
}

// The coefficients under the chosen Gaussian, and the noise variance they keep
// per unit of leverage, Σ_q H_pq² s_q².
struct FilteredModes {
    std::vector<double> coefficients; // [point][n][channel], like SurfaceModes
    std::vector<double> kept_noise;   // [point][channel]
};

FilteredModes filter_modes(const SurfaceCells& cells, const SurfaceModes& modes,
                           const std::vector<double>& noise, double width, double spacing)
{
    const std::size_t ch = static_cast<std::size_t>(modes.channels);
    const std::size_t values = static_cast<std::size_t>(modes.count()) * ch;
    const SurfaceGaussian gaussian = surface_gaussian(width, spacing);
    FilteredModes filtered{std::vector<double>(modes.coefficients.size(), 0.0),
                           std::vector<double>(noise.size(), 0.0)};
    cells.for_each_point([&](std::int64_t p, const std::vector<SurfaceNeighbour>& neighbours) {
        double* sums = filtered.coefficients.data() + static_cast<std::size_t>(p) * values;
        double* kept = filtered.kept_noise.data() + static_cast<std::size_t>(p) * ch;
        const double total = weigh_neighbours(gaussian, p, neighbours, [&](std::int64_t q, double weight) {
            const double* theirs = modes.of(q);
            for (std::size_t i = 0; i < values; ++i)
                sums[i] += weight * theirs[i];
            for (std::size_t c = 0; c < ch; ++c)
                kept[c] += weight * weight * noise[q * ch + c];
        });
        for (std::size_t i = 0; i < values; ++i)
            sums[i] /= total;
        for (std::size_t c = 0; c < ch; ++c)
            kept[c] /= total * total;
    });
    return filtered;
}

// Frame t filtered (when `filtered` is given: its rebuilt value less its part in
// the basis plus that part filtered) and its sigma = sqrt(Σ H² s² h_t + b_t²),
// with b_t² = max(0, μ_t² − s²(1 − h_t)/|W|), μ_t the window's mean residual.
void filter_frame(const SurfaceNeighbours& window_neighbours, double window, const std::vector<double>& noise,
                  const SurfaceModes& modes, const FilteredModes* filtered, int t, int channels,
                  SurfaceFrame& frame)
{
    const std::int64_t count = window_neighbours.count();
    const std::size_t ch = static_cast<std::size_t>(channels);
    const std::vector<float> rebuilt(frame.values, frame.values + count * ch);
    auto residual_of = [&](std::int64_t q, std::size_t c) {
        return static_cast<double>(frame.noisy[q * ch + c]) - rebuilt[q * ch + c];
    };
    const double h = frame.leverage;
    const int n = modes.count();
    for (std::int64_t p = 0; p < count; ++p) {
        const std::int64_t* ids = window_neighbours.ids(p);
        const int members = window_neighbours.count_within(p, window);
        for (std::size_t c = 0; c < ch; ++c) {
            double value = rebuilt[p * ch + c], kept_noise = noise[p * ch + c];
            if (filtered) {
                const double* own = modes.of(p);
                const double* smooth = filtered->coefficients.data() + static_cast<std::size_t>(p) * n * ch;
                for (int j = 0; j < n; ++j)
                    value += (smooth[j * ch + c] - own[j * ch + c]) * modes.basis(t, j);
                kept_noise = filtered->kept_noise[p * ch + c];
            }
            double mean_residual = 0;
            for (int m = 0; m < members; ++m)
                mean_residual += residual_of(ids[m], c);
            mean_residual /= members;
            const double bias =
                std::max(0.0, mean_residual * mean_residual - noise[p * ch + c] * (1 - h) / members);
            frame.values[p * ch + c] = static_cast<float>(value);
            frame.sigma[p * ch + c] = static_cast<float>(std::sqrt(kept_noise * h + bias));
        }
    }
}

} // namespace

SurfaceFilterChoice filter_surfaces(const SurfaceSamples& samples, const SurfaceFilterOptions& options,
                                    int channels, const std::vector<std::vector<double>>& rebuild_weights,
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
    const SurfaceNeighbours window_neighbours(samples, window, kMinNormalCosine);
    const std::vector<double> noise =
        surface_noise_variance(window_neighbours, window, frames, channels, options.kept_modes);

    SurfaceModes modes;
    std::optional<SurfaceCells> cells;
    choice.risks.assign(1, 0.0);
    choice.mean_neighbours = window_neighbours.mean_size();
    if (choice.widths.size() > 1) {
        if (rebuild_weights.empty())
            throw std::invalid_argument("filter_surfaces: no rebuild weights to filter with");
        modes = project_on_weights(rebuild_weights, frames, samples.count(), channels);
        double leverage_sum = 0;
        for (const SurfaceFrame& frame : frames)
            leverage_sum += frame.leverage;
        const double widest = *std::max_element(choice.widths.begin(), choice.widths.end());
        cells.emplace(samples, kReachInSigmas * widest * spacing, kMinNormalCosine);
        choice.risks = surface_sure_risks(*cells, spacing, choice.widths, noise, modes, leverage_sum,
                                          static_cast<int>(frames.size()), choice.mean_neighbours);
    }
    const int best =
        static_cast<int>(std::min_element(choice.risks.begin(), choice.risks.end()) - choice.risks.begin());
    choice.width = choice.widths[best];
    choice.reasoning = reasoning_of(choice, options.filter, best, spacing);

    std::optional<FilteredModes> filtered;
    if (choice.width > 0)
        filtered.emplace(filter_modes(*cells, modes, noise, choice.width, spacing));
    tbb::parallel_for(0, static_cast<int>(frames.size()), [&](int t) {
        filter_frame(window_neighbours, window, noise, modes, filtered ? &*filtered : nullptr, t, channels,
                     frames[t]);
    });
    return choice;
}

} // namespace modestack::objectspace
