// Stein's unbiased risk estimate (SURE) of the surface filter: for each
// candidate width, the mean squared error per value that filtering the rebuilt
// points with its Gaussian (surface_kernel.h) would leave, estimated from the
// values alone and their noise: |Hy − y|² + 2·v·H_pp − v, with v = s²·h_t the
// noise variance a rebuilt value keeps (s² from surface_noise.h, h_t the frame's
// leverage). Summed over every frame, through the rebuild's coefficients
// (surface_modes.h): Σ_t |(Hc − c)·Q_t|² = |Hc − c|² and Σ_t v = s² Σ_t h_t.
#pragma once

#include "core/objectspace/surface_cells.h"
#include "core/objectspace/surface_modes.h"

#include <vector>

namespace modestack::objectspace {

/// SURE per value of each of `widths` (Gaussian sigmas in spacings of `spacing`
/// metres; a width of 0 is the unfiltered values), in the same order. `noise`:
/// s² per point and channel; `leverage_sum`: Σ_t h_t; `frames`: F; `cells`
/// must reach kReachInSigmas of the widest. `mean_neighbours` receives how many
/// points lie within that reach (itself included), on average.
std::vector<double> surface_sure_risks(const SurfaceCells& cells, double spacing,
                                       const std::vector<double>& widths, const std::vector<double>& noise,
                                       const SurfaceModes& modes, double leverage_sum, int frames,
                                       double& mean_neighbours);

} // namespace modestack::objectspace
