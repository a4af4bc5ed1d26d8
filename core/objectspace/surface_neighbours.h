// The neighbours of every surface point, listed: the points within a radius (in
// metres, in the rest pose) whose normals agree, found through the cells of
// surface_cells.h. Each point's list starts with the point itself and runs
// nearest first, so the neighbours within any smaller radius are a prefix of it.
// For narrow radii (sigma's window): a list's length grows with the radius squared.
#pragma once

#include "core/objectspace/surface_samples.h"

#include <cstdint>
#include <vector>

namespace modestack::objectspace {

/// Neighbours of every point within a radius, with normals within an angle.
class SurfaceNeighbours {
public:
    /// `radius` in metres; `min_cosine`: smallest dot product of the two normals.
    /// Throws a usage error for more points than a 32-bit id holds.
    SurfaceNeighbours(const SurfaceSamples& samples, double radius, double min_cosine);
    /// Points (as many as the samples had).
    std::int64_t count() const { return static_cast<std::int64_t>(m_first.size()) - 1; }
    /// Neighbours of point p (itself included) and their squared distances.
    /// 32-bit ids: a film frame has a few million points, and the lists are
    /// most of object space's memory besides the rebuild (a third less than
    /// 64-bit ids).
    const std::int32_t* ids(std::int64_t p) const { return m_ids.data() + m_first[p]; }
    const float* distances_squared(std::int64_t p) const { return m_distances.data() + m_first[p]; }
    std::int64_t size(std::int64_t p) const { return m_first[p + 1] - m_first[p]; }
    double mean_size() const;
    /// Bytes the lists hold.
    std::int64_t bytes() const;
    /// How many of p's neighbours (itself first) lie within `radius` metres.
    int count_within(std::int64_t p, double radius) const;
    /// count_within(p, radius) of every point p.
    std::vector<int> counts_within(double radius) const;

private:
    std::vector<std::int64_t> m_first; // CSR offsets, count + 1
    std::vector<std::int32_t> m_ids;
    std::vector<float> m_distances;
};

} // namespace modestack::objectspace
