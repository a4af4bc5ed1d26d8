// SURE of the surface filter's widths (see surface_sure.h).
#include "core/objectspace/surface_sure.h"

#include "core/objectspace/surface_kernel.h"

#include <algorithm>
#include <cstdint>

namespace modestack::objectspace {

std::vector<double> surface_sure_risks(const SurfaceCells& cells, double spacing,
                                       const std::vector<double>& widths, const std::vector<double>& noise,
                                       const SurfaceModes& modes, double leverage_sum, int frames,
                                       double& mean_neighbours)
{
    const int candidates = static_cast<int>(widths.size());
    const std::int64_t count = static_cast<std::int64_t>(noise.size()) / std::max(modes.channels, 1);
    const std::size_t ch = static_cast<std::size_t>(modes.channels);
    const std::size_t values = static_cast<std::size_t>(modes.count()) * ch; // coefficients per point
    std::vector<SurfaceGaussian> gaussians;
    for (double width : widths)
        gaussians.push_back(width > 0 ? surface_gaussian(width, spacing) : SurfaceGaussian{});
    // Per point first, summed in point order after: the same bits for any thread count.
    std::vector<double> point_risk(static_cast<std::size_t>(count) * candidates, 0.0);
    std::vector<std::int64_t> sizes(static_cast<std::size_t>(count), 0);
    cells.for_each_point([&](std::int64_t p, const std::vector<SurfaceNeighbour>& neighbours) {
        sizes[p] = static_cast<std::int64_t>(neighbours.size());
        const double* own = modes.of(p);
        std::vector<double> sums(values);
        for (int k = 0; k < candidates; ++k) {
            double& risk = point_risk[static_cast<std::size_t>(p) * candidates + k];
            if (widths[k] == 0) {
                for (std::size_t c = 0; c < ch; ++c)
                    risk += noise[p * ch + c] * leverage_sum;
                continue;
            }
            std::fill(sums.begin(), sums.end(), 0.0);
            const double total =
                weigh_neighbours(gaussians[k], p, neighbours, [&](std::int64_t q, double weight) {
                    const double* theirs = modes.of(q);
                    for (std::size_t i = 0; i < values; ++i)
                        sums[i] += weight * theirs[i];
                });
            for (std::size_t i = 0; i < values; ++i) {
                const double change = sums[i] / total - own[i];
                risk += change * change;
            }
            for (std::size_t c = 0; c < ch; ++c)
                risk += noise[p * ch + c] * leverage_sum * (2 / total - 1);
        }
    });
    std::vector<double> risks(static_cast<std::size_t>(candidates), 0.0);
    std::int64_t neighbours = 0;
    for (std::int64_t p = 0; p < count; ++p) {
        neighbours += sizes[p];
        for (int k = 0; k < candidates; ++k)
            risks[k] += point_risk[p * candidates + k];
    }
    mean_neighbours = count > 0 ? static_cast<double>(neighbours) / count : 0.0;
    const double surveyed = static_cast<double>(count) * ch * std::max(frames, 1);
    for (double& risk : risks)
        risk /= surveyed;
    return risks;
}

} // namespace modestack::objectspace
