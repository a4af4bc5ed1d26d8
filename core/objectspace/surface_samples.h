// What the surface filter of object space works on: where the points sit on
// their surfaces (the shot's rest pose, so neighbours on a surface stay
// neighbours as it moves) and their frames.
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

namespace modestack::objectspace {

/// Where the points are: positions (metres) and unit normals, 3 floats each.
struct SurfaceSamples {
    std::vector<float> positions;
    std::vector<float> normals;
    double spacing = 0; ///< lattice spacing (metres): the unit of the widths
    std::int64_t count() const { return static_cast<std::int64_t>(positions.size() / 3); }
};

/// The points' frames as the engine left them: its rebuild, kept, and its input,
/// read one frame at a time (from memory or from the files again), with each
/// frame's leverage. A frame is [point][channel] over the whole point image
/// (`frame_values` floats: the samples' points first, then any padding).
struct SurfaceShot {
    std::function<void(int frame, float* destination)> read_noisy;
    std::vector<const float*> rebuilt; ///< per frame
    std::vector<double>
        leverages; ///< h_t = Σ_{j≤N} V_tj²: the share of a frame's noise the rebuild keeps (leverage.h)
    int channels = 1;
    std::int64_t frame_values = 0;
    int frames() const { return static_cast<int>(rebuilt.size()); }
};

} // namespace modestack::objectspace
