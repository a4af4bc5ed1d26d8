// The noise level of the surface points, as lowrank/confidence.h estimates it
// for pixels but pooled over a point's surface neighbours instead of an image
// window (a point image's neighbours are not the surface's): from the residual
// r = noisy − rebuilt, high-passed against its window (d = r_p − mean of r over
// p's window without p, whose variance is (1 + 1/k)·s² for white noise), summed
// over the frames and pooled over the window, with F − N degrees of freedom.
#pragma once

#include "core/objectspace/surface_neighbours.h"
#include "core/objectspace/surface_samples.h"

#include <vector>

namespace modestack::objectspace {

/// s², the variance of one noisy value, per point and channel ([point][channel]),
/// from the residuals of `shot`'s frames over each point's window: its first
/// `window_members[p]` neighbours (itself included; neighbours.counts_within of
/// the window's radius). `kept_modes`: N of the rebuild.
/// The frames' inputs are read one at a time, in order.
std::vector<double> surface_noise_variance(const SurfaceNeighbours& neighbours,
                                           const std::vector<int>& window_members, const SurfaceShot& shot,
                                           int kept_modes);

} // namespace modestack::objectspace
