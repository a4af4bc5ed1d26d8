// The points within a radius of every surface point, visited without listing
// them: the points are sorted into cubic cells as wide as the radius, so that a
// point's neighbours are among the points of its own cell and the 26 around it,
// and those candidates are gathered once per cell for all of its points. A list
// per point (surface_neighbours.h) holds a number of entries that grows with the
// radius squared; at the surface filter's widest reach that was most of a run's
// memory and time, so the wide kernels go through here and only the narrow
// sigma window keeps lists.
#pragma once

#include "core/objectspace/surface_samples.h"

#include <cstdint>
#include <functional>
#include <vector>

namespace modestack::objectspace {

/// One neighbour of a point.
struct SurfaceNeighbour {
    std::int64_t id;
    float distance_squared; ///< in metres²
};

/// Points sorted into cells, for neighbour visits within one radius.
class SurfaceCells {
public:
    /// `radius` in metres (> 0); `min_cosine`: smallest dot product of two neighbours' normals.
    SurfaceCells(const SurfaceSamples& samples, double radius, double min_cosine);

    /// Calls visit(p, neighbours) once for every point p, in parallel over
    /// cells: the points within the radius whose normals agree with p's, p
    /// itself first (whatever its normal), the others in a fixed order that does
    /// not depend on the threads. `neighbours` is valid during the call only.
    void for_each_point(
        const std::function<void(std::int64_t, const std::vector<SurfaceNeighbour>&)>& visit) const;

private:
    const SurfaceSamples& m_samples;
    double m_radius, m_min_cosine;
    std::vector<std::int64_t> m_order;      // point ids sorted by cell
    std::vector<std::int64_t> m_cell_keys;  // one per cell, ascending
    std::vector<std::int64_t> m_cell_first; // start of each cell's run in m_order, cells + 1
    std::vector<std::int64_t> m_cell_x, m_cell_y, m_cell_z;
};

} // namespace modestack::objectspace
