// The spatial filter of object space: what the mode filter is to images, over the
// surfaces. After the temporal low-rank rebuild, each point's value still carries
// the noise its own bake left in the kept modes; neighbouring points on the same
// surface see nearly the same light, so a Gaussian over them (in metres, in units
// of the lattice spacing) removes most of it. The width is chosen by Stein's
// unbiased risk estimate (SURE) over all points and frames, from the engine's
// per-point standard error, so no width is fitted to a scene; "no filter" is
// always a candidate. Points only average with points within the kernel's reach
// whose normals agree (same surface orientation), so a box's faces, or a wall and
// the floor, do not bleed into each other.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace modestack::denoise {

/// Where the points are: positions (metres) and unit normals, 3 floats each.
struct SurfaceSamples {
    std::vector<float> positions;
    std::vector<float> normals;
    double spacing = 0; ///< lattice spacing (metres): the unit of the widths
    std::int64_t count() const { return static_cast<std::int64_t>(positions.size() / 3); }
};

/// Neighbours of every point within a radius, with normals within an angle.
class SurfaceNeighbours {
public:
    /// `radius` in metres; `min_cosine`: smallest dot product of the two normals.
    SurfaceNeighbours(const SurfaceSamples& samples, double radius, double min_cosine);
    /// Neighbours of point p (itself included) and their squared distances.
    const std::int64_t* ids(std::int64_t p) const { return m_ids.data() + m_first[p]; }
    const float* distances_squared(std::int64_t p) const { return m_distances.data() + m_first[p]; }
    std::int64_t size(std::int64_t p) const { return m_first[p + 1] - m_first[p]; }
    double mean_size() const;

private:
    std::vector<std::int64_t> m_first; // CSR offsets, count + 1
    std::vector<std::int64_t> m_ids;
    std::vector<float> m_distances;
};

/// What the SURE survey found.
struct SurfaceFilterChoice {
    double width = 0;                ///< chosen Gaussian sigma in spacings (0: no filter)
    std::vector<double> widths;      ///< candidates, 0 first
    std::vector<double> risks;       ///< SURE per candidate, per value (same order)
    double mean_neighbours = 0;      ///< points within reach of the widest kernel, on average
    std::string reasoning;           ///< one line for the summary
};

/// One frame of the points, [point][channel]: the engine's input and rebuild
/// (replaced by the filtered values), and where sigma goes.
struct SurfaceFrame {
    const float* noisy;
    float* values;
    float* sigma;
    double leverage = 0; ///< h_t = Σ_{j≤N} V_tj²: the share of a frame's noise the rebuild keeps
};

/// How to filter.
struct SurfaceFilterOptions {
    std::vector<double> widths;  ///< candidate Gaussian sigmas, in spacings (0 = none is always tried)
    bool filter = true;          ///< false: only sigma
    double window_spacings = 2;  ///< radius of sigma's pooling window, in spacings
    int rank = 1;                ///< N of the rebuild
};

/// Sigma of every point and frame, as lowrank/confidence.h computes it for
/// pixels but pooled over the surface neighbours within the window instead of
/// an image window (a point image's neighbours are not the surface's), and,
/// when asked, the width among 0 and options.widths with the lowest SURE, using
/// s²·h_t as each rebuilt value's noise variance; every frame is then filtered
/// in place with it. Sigma after filtering: sqrt(Σ_q H_pq² s_q² h_t + b_t²).
SurfaceFilterChoice filter_surfaces(const SurfaceSamples& samples, const SurfaceFilterOptions& options, int channels,
                                    std::vector<SurfaceFrame>& frames);

} // namespace modestack::denoise
