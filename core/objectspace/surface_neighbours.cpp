// Surface neighbours through a grid of cells (see surface_neighbours.h).
#include "core/objectspace/surface_neighbours.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <utility>

namespace modestack::objectspace {
namespace {

std::int64_t cell_key(std::int64_t x, std::int64_t y, std::int64_t z)
{
    // 21 bits per axis, offset so that negative cells stay distinct.
    const std::int64_t offset = 1 << 20, mask = (1 << 21) - 1;
    return ((x + offset) & mask) << 42 | ((y + offset) & mask) << 21 | ((z + offset) & mask);
}

} // namespace

SurfaceNeighbours::SurfaceNeighbours(const SurfaceSamples& samples, double radius, double min_cosine)
{
    const std::int64_t count = samples.count();
    const float* position = samples.positions.data();
    const float* normal = samples.normals.data();
    auto cell_of = [&](std::int64_t p, int axis) {
        return static_cast<std::int64_t>(std::floor(position[3 * p + axis] / radius));
    };
    // Points sorted by cell: a cell's points are one run of `order`.
    std::vector<std::int64_t> keys(static_cast<std::size_t>(count)), order(static_cast<std::size_t>(count));
    for (std::int64_t p = 0; p < count; ++p)
        keys[p] = cell_key(cell_of(p, 0), cell_of(p, 1), cell_of(p, 2));
    std::iota(order.begin(), order.end(), 0);
    std::stable_sort(order.begin(), order.end(), [&](std::int64_t a, std::int64_t b) { return keys[a] < keys[b]; });
    std::vector<std::int64_t> sorted_keys(static_cast<std::size_t>(count));
    for (std::int64_t i = 0; i < count; ++i)
        sorted_keys[i] = keys[order[i]];
    const float radius_squared = static_cast<float>(radius * radius);

    // Visits the neighbours of p in a fixed order (cells, then ids).
    auto visit = [&](std::int64_t p, auto&& take) {
        take(p, 0.0f); // itself first, whatever its normal
        const std::int64_t cx = cell_of(p, 0), cy = cell_of(p, 1), cz = cell_of(p, 2);
        for (std::int64_t dx = -1; dx <= 1; ++dx)
            for (std::int64_t dy = -1; dy <= 1; ++dy)
                for (std::int64_t dz = -1; dz <= 1; ++dz) {
                    const std::int64_t key = cell_key(cx + dx, cy + dy, cz + dz);
                    auto begin = std::lower_bound(sorted_keys.begin(), sorted_keys.end(), key);
                    for (auto it = begin; it != sorted_keys.end() && *it == key; ++it) {
                        const std::int64_t q = order[static_cast<std::size_t>(it - sorted_keys.begin())];
                        if (q == p)
                            continue;
                        float cosine = normal[3 * p] * normal[3 * q] + normal[3 * p + 1] * normal[3 * q + 1] +
                                       normal[3 * p + 2] * normal[3 * q + 2];
                        if (cosine < min_cosine)
                            continue;
                        float ex = position[3 * p] - position[3 * q], ey = position[3 * p + 1] - position[3 * q + 1],
                              ez = position[3 * p + 2] - position[3 * q + 2];
                        float distance_squared = ex * ex + ey * ey + ez * ez;
                        if (distance_squared <= radius_squared)
                            take(q, distance_squared);
                    }
                }
    };
    std::vector<std::int64_t> sizes(static_cast<std::size_t>(count), 0);
    tbb::parallel_for(tbb::blocked_range<std::int64_t>(0, count), [&](const tbb::blocked_range<std::int64_t>& range) {
        for (std::int64_t p = range.begin(); p != range.end(); ++p)
            visit(p, [&](std::int64_t, float) { ++sizes[p]; });
    });
    m_first.assign(static_cast<std::size_t>(count) + 1, 0);
    for (std::int64_t p = 0; p < count; ++p)
        m_first[p + 1] = m_first[p] + sizes[p];
    m_ids.resize(static_cast<std::size_t>(m_first.back()));
    m_distances.resize(m_ids.size());
    tbb::parallel_for(tbb::blocked_range<std::int64_t>(0, count), [&](const tbb::blocked_range<std::int64_t>& range) {
        for (std::int64_t p = range.begin(); p != range.end(); ++p) {
            std::int64_t next = m_first[p];
            visit(p, [&](std::int64_t q, float distance_squared) {
                m_ids[next] = q;
                m_distances[next++] = distance_squared;
            });
            // Nearest first (p itself stays first), so that any radius is a prefix.
            std::vector<std::pair<float, std::int64_t>> sorted;
            for (std::int64_t n = m_first[p] + 1; n < m_first[p + 1]; ++n)
                sorted.emplace_back(m_distances[n], m_ids[n]);
            std::sort(sorted.begin(), sorted.end());
            for (std::size_t n = 0; n < sorted.size(); ++n) {
                m_distances[m_first[p] + 1 + n] = sorted[n].first;
                m_ids[m_first[p] + 1 + n] = sorted[n].second;
            }
        }
    });
}

double SurfaceNeighbours::mean_size() const
{
    const std::size_t points = m_first.size() - 1;
    return points > 0 ? static_cast<double>(m_first.back()) / static_cast<double>(points) : 0.0;
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
