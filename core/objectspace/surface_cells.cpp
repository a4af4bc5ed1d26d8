// Neighbour visits through cells (see surface_cells.h).
#include "core/objectspace/surface_cells.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>

namespace modestack::objectspace {
namespace {

std::int64_t cell_key(std::int64_t x, std::int64_t y, std::int64_t z)
{
    // 21 bits per axis, offset so that negative cells stay distinct.
    const std::int64_t offset = 1 << 20, mask = (1 << 21) - 1;
    return ((x + offset) & mask) << 42 | ((y + offset) & mask) << 21 | ((z + offset) & mask);
}

} // namespace

SurfaceCells::SurfaceCells(const SurfaceSamples& samples, double radius, double min_cosine)
    : m_samples(samples), m_radius(radius), m_min_cosine(min_cosine)
{
    if (!(radius > 0))
        throw std::invalid_argument("SurfaceCells: the radius must be positive");
    const std::int64_t count = samples.count();
    const float* position = samples.positions.data();
    std::vector<std::int64_t> cells(static_cast<std::size_t>(count) * 3),
        keys(static_cast<std::size_t>(count));
    for (std::int64_t p = 0; p < count; ++p) {
        for (int axis = 0; axis < 3; ++axis)
            cells[3 * p + axis] = static_cast<std::int64_t>(std::floor(position[3 * p + axis] / radius));
        keys[p] = cell_key(cells[3 * p], cells[3 * p + 1], cells[3 * p + 2]);
    }
    m_order.resize(static_cast<std::size_t>(count));
    std::iota(m_order.begin(), m_order.end(), 0);
    std::stable_sort(m_order.begin(), m_order.end(),
                     [&](std::int64_t a, std::int64_t b) { return keys[a] < keys[b]; });
    for (std::int64_t i = 0; i < count; ++i) {
        const std::int64_t p = m_order[i];
        if (i == 0 || keys[p] != m_cell_keys.back()) {
            m_cell_keys.push_back(keys[p]);
            m_cell_first.push_back(i);
            m_cell_x.push_back(cells[3 * p]), m_cell_y.push_back(cells[3 * p + 1]),
                m_cell_z.push_back(cells[3 * p + 2]);
        }
    }
    m_cell_first.push_back(count);
}

void SurfaceCells::for_each_point(
    const std::function<void(std::int64_t, const std::vector<SurfaceNeighbour>&)>& visit) const
{
    const float* position = m_samples.positions.data();
    const float* normal = m_samples.normals.data();
    const float radius_squared = static_cast<float>(m_radius * m_radius);
    const std::size_t cells = m_cell_keys.size();
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(0, cells), [&](const tbb::blocked_range<std::size_t>& range) {
            std::vector<std::int64_t> candidates;
            std::vector<SurfaceNeighbour> neighbours;
            for (std::size_t cell = range.begin(); cell != range.end(); ++cell) {
                candidates.clear();
                for (std::int64_t dx = -1; dx <= 1; ++dx)
                    for (std::int64_t dy = -1; dy <= 1; ++dy)
                        for (std::int64_t dz = -1; dz <= 1; ++dz) {
                            const std::int64_t key =
                                cell_key(m_cell_x[cell] + dx, m_cell_y[cell] + dy, m_cell_z[cell] + dz);
                            const auto found = std::lower_bound(m_cell_keys.begin(), m_cell_keys.end(), key);
                            if (found == m_cell_keys.end() || *found != key)
                                continue;
                            const std::size_t other = static_cast<std::size_t>(found - m_cell_keys.begin());
                            candidates.insert(candidates.end(), m_order.begin() + m_cell_first[other],
                                              m_order.begin() + m_cell_first[other + 1]);
                        }
                for (std::int64_t i = m_cell_first[cell]; i < m_cell_first[cell + 1]; ++i) {
                    const std::int64_t p = m_order[static_cast<std::size_t>(i)];
                    neighbours.clear();
                    neighbours.push_back({p, 0.0f}); // itself first, whatever its normal
                    for (std::int64_t q : candidates) {
                        if (q == p)
                            continue;
                        const float cosine = normal[3 * p] * normal[3 * q] +
                                             normal[3 * p + 1] * normal[3 * q + 1] +
                                             normal[3 * p + 2] * normal[3 * q + 2];
                        if (cosine < m_min_cosine)
                            continue;
                        const float ex = position[3 * p] - position[3 * q],
                                    ey = position[3 * p + 1] - position[3 * q + 1],
                                    ez = position[3 * p + 2] - position[3 * q + 2];
                        const float distance_squared = ex * ex + ey * ey + ez * ez;
                        if (distance_squared <= radius_squared)
                            neighbours.push_back({q, distance_squared});
                    }
                    visit(p, neighbours);
                }
            }
        });
}

} // namespace modestack::objectspace
