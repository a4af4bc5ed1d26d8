// Surface neighbours through a grid of cells (see surface_neighbours.h).
#include "core/objectspace/surface_neighbours.h"

#include "core/common/error.h"
#include "core/objectspace/surface_cells.h"

#include <fmt/format.h>

#include <algorithm>
#include <limits>
#include <utility>

namespace modestack::objectspace {

SurfaceNeighbours::SurfaceNeighbours(const SurfaceSamples& samples, double radius, double min_cosine)
{
    const std::int64_t count = samples.count();
    if (count > std::numeric_limits<std::int32_t>::max())
        throw usage_error(fmt::format("object space: {} surface points, more than the {} it can list", count,
                                      std::numeric_limits<std::int32_t>::max()));
    const SurfaceCells cells(samples, radius, min_cosine);
    std::vector<std::int64_t> sizes(static_cast<std::size_t>(count), 0);
    cells.for_each_point([&](std::int64_t p, const std::vector<SurfaceNeighbour>& neighbours) {
        sizes[p] = static_cast<std::int64_t>(neighbours.size());
    });
    m_first.assign(static_cast<std::size_t>(count) + 1, 0);
    for (std::int64_t p = 0; p < count; ++p)
        m_first[p + 1] = m_first[p] + sizes[p];
    m_ids.resize(static_cast<std::size_t>(m_first.back()));
    m_distances.resize(m_ids.size());
    cells.for_each_point([&](std::int64_t p, const std::vector<SurfaceNeighbour>& neighbours) {
        // Nearest first (ties by id; p itself stays first), so that any radius is a prefix.
        std::vector<std::pair<float, std::int64_t>> sorted;
        for (std::size_t n = 1; n < neighbours.size(); ++n)
            sorted.emplace_back(neighbours[n].distance_squared, neighbours[n].id);
        std::sort(sorted.begin(), sorted.end());
        m_ids[m_first[p]] = static_cast<std::int32_t>(p), m_distances[m_first[p]] = 0.0f;
        for (std::size_t n = 0; n < sorted.size(); ++n) {
            m_distances[m_first[p] + 1 + n] = sorted[n].first;
            m_ids[m_first[p] + 1 + n] = static_cast<std::int32_t>(sorted[n].second);
        }
    });
}

double SurfaceNeighbours::mean_size() const
{
    const std::size_t points = m_first.size() - 1;
    return points > 0 ? static_cast<double>(m_first.back()) / static_cast<double>(points) : 0.0;
}

std::int64_t SurfaceNeighbours::bytes() const
{
    return static_cast<std::int64_t>(m_first.size() * sizeof(std::int64_t) +
                                     m_ids.size() * sizeof(std::int32_t) +
                                     m_distances.size() * sizeof(float));
}

std::vector<int> SurfaceNeighbours::counts_within(double radius) const
{
    std::vector<int> counts(static_cast<std::size_t>(count()));
    for (std::int64_t p = 0; p < count(); ++p)
        counts[static_cast<std::size_t>(p)] = count_within(p, radius);
    return counts;
}

int SurfaceNeighbours::count_within(std::int64_t p, double radius) const
{
    const float* d2 = distances_squared(p);
    int members = 0;
    while (members < size(p) && d2[members] <= radius * radius)
        ++members;
    return members;
}

} // namespace modestack::objectspace
