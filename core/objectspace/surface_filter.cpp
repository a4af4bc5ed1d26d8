// SURE-chosen Gaussian filtering over surface points (see surface_filter.h).
#include "core/objectspace/surface_filter.h"

#include "core/objectspace/surface_cells.h"
#include "core/objectspace/surface_kernel.h"
#include "core/objectspace/surface_modes.h"
#include "core/objectspace/surface_neighbours.h"
#include "core/objectspace/surface_noise.h"
#include "core/objectspace/surface_sure.h"

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <utility>

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

} // namespace

struct SurfaceFilter::State {
    State(double window_radius, SurfaceNeighbours neighbours, const SurfaceShot& shot)
        : window_neighbours(std::move(neighbours)),
          window_members(window_neighbours.counts_within(window_radius)), shot(shot)
    {
    }
    SurfaceNeighbours window_neighbours;
    std::vector<int> window_members; // per point: its window's size, itself included
    const SurfaceShot& shot;
    std::vector<double> noise; // s² per point and channel
    SurfaceModes modes;
    std::optional<FilteredModes> filtered; // none: width 0
};

SurfaceNeighbours SurfaceFilter::window_neighbours(const SurfaceSamples& samples,
                                                   const SurfaceFilterOptions& options)
{
    return SurfaceNeighbours(samples, options.window_spacings * samples.spacing, kMinNormalCosine);
}

std::int64_t SurfaceFilter::state_bytes(std::int64_t points, int channels, int modes)
{
    return points * static_cast<std::int64_t>(sizeof(double)) * (2 * modes + 2) * channels;
}

SurfaceFilter::SurfaceFilter(const SurfaceSamples& samples, const SurfaceFilterOptions& options,
                             const std::vector<std::vector<double>>& rebuild_weights, const SurfaceShot& shot,
                             SurfaceNeighbours window)
{
    m_choice.widths.push_back(0);
    if (options.filter)
        for (double width : options.widths)
            if (width > 0)
                m_choice.widths.push_back(width);
    if (samples.count() == 0 || shot.frames() == 0 || !(samples.spacing > 0))
        throw std::invalid_argument("SurfaceFilter: no points, frames or spacing");
    const double spacing = samples.spacing;
    m_state = std::make_unique<State>(options.window_spacings * spacing, std::move(window), shot);
    State& state = *m_state;
    state.noise =
        surface_noise_variance(state.window_neighbours, state.window_members, shot, options.kept_modes);

    std::optional<SurfaceCells> cells;
    m_choice.risks.assign(1, 0.0);
    m_choice.mean_neighbours = state.window_neighbours.mean_size();
    if (m_choice.widths.size() > 1) {
        if (rebuild_weights.empty())
            throw std::invalid_argument("SurfaceFilter: no rebuild weights to filter with");
        state.modes = project_on_weights(rebuild_weights, shot, samples.count());
        double leverage_sum = 0;
        for (double leverage : shot.leverages)
            leverage_sum += leverage;
        const double widest = *std::max_element(m_choice.widths.begin(), m_choice.widths.end());
        cells.emplace(samples, kReachInSigmas * widest * spacing, kMinNormalCosine);
        m_choice.risks = surface_sure_risks(*cells, spacing, m_choice.widths, state.noise, state.modes,
                                            leverage_sum, shot.frames(), m_choice.mean_neighbours);
    }
    const int best = static_cast<int>(std::min_element(m_choice.risks.begin(), m_choice.risks.end()) -
                                      m_choice.risks.begin());
    m_choice.width = m_choice.widths[best];
    m_choice.reasoning = reasoning_of(m_choice, options.filter, best, spacing);
    if (m_choice.width > 0)
        state.filtered.emplace(filter_modes(*cells, state.modes, state.noise, m_choice.width, spacing));
}

SurfaceFilter::~SurfaceFilter() = default;

// The rebuilt value less its part in the basis plus that part filtered, and
// sigma with b_t² = max(0, μ_t² − s²(1 − h_t)/|W|), μ_t the window's mean residual.
void SurfaceFilter::frame(int t, const float* noisy, float* values, float* sigma) const
{
    const State& state = *m_state;
    const SurfaceNeighbours& window_neighbours = state.window_neighbours;
    const std::int64_t count = window_neighbours.count();
    const std::size_t ch = static_cast<std::size_t>(state.shot.channels);
    const float* rebuilt = state.shot.rebuilt[static_cast<std::size_t>(t)];
    auto residual_of = [&](std::int64_t q, std::size_t c) {
        return static_cast<double>(noisy[q * ch + c]) - rebuilt[q * ch + c];
    };
    const double h = state.shot.leverages[static_cast<std::size_t>(t)];
    const int n = state.modes.count();
    const FilteredModes* filtered = state.filtered ? &*state.filtered : nullptr;
    tbb::parallel_for(
        tbb::blocked_range<std::int64_t>(0, count), [&](const tbb::blocked_range<std::int64_t>& range) {
            for (std::int64_t p = range.begin(); p != range.end(); ++p) {
                const std::int32_t* ids = window_neighbours.ids(p);
                const int members = state.window_members[static_cast<std::size_t>(p)];
                for (std::size_t c = 0; c < ch; ++c) {
                    double value = rebuilt[p * ch + c], kept_noise = state.noise[p * ch + c];
                    if (filtered) {
                        const double* own = state.modes.of(p);
                        const double* smooth =
                            filtered->coefficients.data() + static_cast<std::size_t>(p) * n * ch;
                        for (int j = 0; j < n; ++j)
                            value += (smooth[j * ch + c] - own[j * ch + c]) * state.modes.basis(t, j);
                        kept_noise = filtered->kept_noise[p * ch + c];
                    }
                    double mean_residual = 0;
                    for (int m = 0; m < members; ++m)
                        mean_residual += residual_of(ids[m], c);
                    mean_residual /= members;
                    const double bias = std::max(0.0, mean_residual * mean_residual -
                                                          state.noise[p * ch + c] * (1 - h) / members);
                    values[p * ch + c] = static_cast<float>(value);
                    sigma[p * ch + c] = static_cast<float>(std::sqrt(kept_noise * h + bias));
                }
            }
        });
}

} // namespace modestack::objectspace
