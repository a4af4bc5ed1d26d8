// One glTF animation sampler: key times and values, and its value at any time.
// LINEAR interpolates vectors linearly and rotations by slerp, STEP holds the
// previous key, CUBICSPLINE is approximated as LINEAR between its value elements
// (its tangents are ignored; the loader reports it). Before the first key the first
// value holds, after the last key the last.
#pragma once

#include "core/scene/gltf_math.h"

#include <vector>

namespace modestack::scene {

/// How a track interpolates between keys.
enum class Interpolation { Linear, Step, CubicSpline };

/// The keys of one animated property.
struct KeyframeTrack {
    Interpolation interpolation = Interpolation::Linear;
    std::vector<float> times; ///< seconds, increasing
    int components = 3;       ///< 3 (translation, scale) or 4 (rotation quaternion x, y, z, w)
    /// `components` floats per key; for CubicSpline three elements per key
    /// (in-tangent, value, out-tangent), as glTF stores them.
    std::vector<float> values;
};

/// The vector value of a 3-component track at `time_seconds`.
Vec3 sample_vec3(const KeyframeTrack& track, float time_seconds);
/// The rotation of a 4-component track at `time_seconds` (unit quaternion).
Quat sample_rotation(const KeyframeTrack& track, float time_seconds);

} // namespace modestack::scene
