// The spatial filter of object space: what the mode filter is to images, over the
// surfaces. After the temporal low-rank rebuild, each point's value still carries
// the noise its own bake left in the kept modes; neighbouring points on the same
// surface see nearly the same light, so a Gaussian over them (in metres, in units
// of the lattice spacing; surface_kernel.h) removes most of it. The width is
// chosen by Stein's unbiased risk estimate (surface_sure.h) over all points and
// frames, from the per-point noise level (surface_noise.h), so no width is fitted
// to a scene; "no filter" is always a candidate. Points only average with points
// within the kernel's reach whose normals agree (same surface orientation;
// surface_neighbours.h), so a box's faces, or a wall and the floor, do not bleed
// into each other. The filter runs on the rebuild's coefficients, once for
// every frame (surface_modes.h), and visits the wide kernels' neighbours cell by
// cell without listing them (surface_cells.h): its time grows with the points
// and N, not the frames, and its memory with the points only.
#pragma once

#include "core/objectspace/surface_neighbours.h"
#include "core/objectspace/surface_samples.h"

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace modestack::objectspace {

/// What the SURE survey found.
struct SurfaceFilterChoice {
    double width = 0;           ///< chosen Gaussian sigma in spacings (0: no filter)
    std::vector<double> widths; ///< candidates, 0 first
    std::vector<double> risks;  ///< SURE per candidate, per value (same order)
    double mean_neighbours = 0; ///< points within reach of the widest kernel, on average
    std::string reasoning;      ///< one line for the summary
    double seconds = 0;         ///< wall time of the filter and sigma
};

/// How to filter.
struct SurfaceFilterOptions {
    std::vector<double> widths; ///< candidate Gaussian sigmas, in spacings (0 = none is always tried)
    bool filter = true;         ///< false: only sigma
    double window_spacings = 2; ///< radius of sigma's pooling window, in spacings
    int kept_modes = 1;         ///< N of the rebuild
};

/// The surface filter of one shot: built once (the noise level from every
/// frame's residual, the width SURE chooses, the filtered coefficients), then
/// asked for any frame's filtered values and sigma.
class SurfaceFilter {
public:
    /// Sigma as lowrank/confidence.h computes it for pixels but pooled over the
    /// surface neighbours within the window instead of an image window (a point
    /// image's neighbours are not the surface's), and, when asked, the width
    /// among 0 and options.widths with the lowest SURE, using s²·h_t as each
    /// rebuilt value's noise variance. `rebuild_weights`: the temporal weights
    /// the frames were rebuilt from ([j][t], denoise::Report::rebuild_weights).
    /// `shot` must outlive the filter. Throws std::invalid_argument
    /// without points, frames, a spacing or (to filter) weights of the frames' length.
    /// `window`: window_neighbours(samples, options), made beforehand so that
    /// its memory is known before the engine runs.
    SurfaceFilter(const SurfaceSamples& samples, const SurfaceFilterOptions& options,
                  const std::vector<std::vector<double>>& rebuild_weights, const SurfaceShot& shot,
                  SurfaceNeighbours window);
    ~SurfaceFilter();
    SurfaceFilter(const SurfaceFilter&) = delete;
    SurfaceFilter& operator=(const SurfaceFilter&) = delete;

    /// The neighbours of sigma's window (options.window_spacings) the filter works with.
    static SurfaceNeighbours window_neighbours(const SurfaceSamples& samples,
                                               const SurfaceFilterOptions& options);
    /// Bytes the filter keeps besides its window's lists, for `points` points of
    /// `channels` channels rebuilt from `modes` modes: its coefficients, their
    /// filtered copy, the noise levels. (Its survey's temporaries, about 100
    /// bytes per point, are freed before any frame is made.)
    static std::int64_t state_bytes(std::int64_t points, int channels, int modes);

    const SurfaceFilterChoice& choice() const { return m_choice; }

    /// Frame t of the samples' points filtered with the chosen width (0: as
    /// rebuilt) into `values`, and sigma = sqrt(Σ_q H_pq² s_q² h_t + b_t²) into
    /// `sigma`, both [point][channel]; `noisy`: the frame's input as
    /// SurfaceShot::read_noisy gives it. May be called concurrently.
    void frame(int t, const float* noisy, float* values, float* sigma) const;

private:
    struct State;
    SurfaceFilterChoice m_choice;
    std::unique_ptr<State> m_state;
};

} // namespace modestack::objectspace
