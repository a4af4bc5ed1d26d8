// Stein's unbiased risk estimate (SURE) of the surface filter: for each
// candidate width, the mean squared error per value that filtering the rebuilt
// points with its Gaussian (surface_kernel.h) would leave, estimated from the
// values alone and their noise: |Hy − y|² + 2·v·H_pp − v, with v = s²·h_t the
// noise variance a rebuilt value keeps (s² from surface_noise.h, h_t the frame's
// leverage). It is summed over a few frames spread evenly over the shot.
#pragma once

#include "core/objectspace/surface_neighbours.h"
#include "core/objectspace/surface_samples.h"

#include <vector>

namespace modestack::objectspace {

/// SURE per value of each of `widths` (Gaussian sigmas in spacings of `spacing`
/// metres; a width of 0 is the unfiltered values), in the same order; all 0 for
/// a single candidate (nothing to choose). `noise`: s² per point and channel;
/// `neighbours` must reach kReachInSigmas of the widest.
std::vector<double> surface_sure_risks(const SurfaceNeighbours& neighbours, double spacing,
                                       const std::vector<double>& widths, const std::vector<double>& noise,
                                       const std::vector<SurfaceFrame>& frames, int channels);

} // namespace modestack::objectspace
