// The leverage of each frame in the rank-N rebuild: h_t = Σ_{j<N} V_tj², the
// diagonal of the projection V Vᵀ onto the kept temporal modes. A frame's
// rebuilt value keeps the share h_t of that frame's own noise variance, which
// the surface filter's SURE and sigma need (surface_filter.h). With orthonormal
// modes the leverages lie in [0, 1] and sum to N.
#pragma once

#include <vector>

namespace modestack::objectspace {

/// h_t for t < `frames`, from the kept temporal modes, [j][t] as the engine
/// reports them (denoise::Report::temporal_modes).
std::vector<double> frame_leverages(const std::vector<std::vector<double>>& temporal_modes, int frames);

} // namespace modestack::objectspace
