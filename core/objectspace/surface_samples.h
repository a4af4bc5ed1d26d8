// What the surface filter of object space works on: where the points sit on
// their surfaces (the shot's rest pose, so neighbours on a surface stay
// neighbours as it moves) and one frame of their values.
#pragma once

#include <cstdint>
#include <vector>

namespace modestack::objectspace {

/// Where the points are: positions (metres) and unit normals, 3 floats each.
struct SurfaceSamples {
    std::vector<float> positions;
    std::vector<float> normals;
    double spacing = 0; ///< lattice spacing (metres): the unit of the widths
    std::int64_t count() const { return static_cast<std::int64_t>(positions.size() / 3); }
};

/// One frame of the points, [point][channel]: the engine's input and rebuild
/// (replaced by the filtered values), and where sigma goes.
struct SurfaceFrame {
    const float* noisy;
    float* values;
    float* sigma;
    double leverage = 0; ///< h_t = Σ_{j≤N} V_tj²: the share of a frame's noise the rebuild keeps (leverage.h)
};

} // namespace modestack::objectspace
