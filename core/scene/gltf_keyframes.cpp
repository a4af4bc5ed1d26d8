// Sampling a keyframe track (see gltf_keyframes.h).
#include "core/scene/gltf_keyframes.h"

#include <algorithm>
#include <cstddef>

namespace modestack::scene {
namespace {

// The two keys around `time` and the fraction u ∈ [0, 1] between them. Outside the
// keys both are the nearest key.
struct Bracket {
    std::size_t before, after;
    float u;
};

Bracket bracket(const std::vector<float>& times, float time, Interpolation interpolation)
{
    if (times.size() < 2 || time <= times.front())
        return {0, 0, 0};
    if (time >= times.back())
        return {times.size() - 1, times.size() - 1, 0};
    auto after = static_cast<std::size_t>(std::upper_bound(times.begin(), times.end(), time) - times.begin());
    std::size_t before = after - 1;
    if (interpolation == Interpolation::Step)
        return {before, before, 0};
    float span = times[after] - times[before];
    return {before, after, span > 0 ? (time - times[before]) / span : 0.0f};
}

// The first of the `components` floats of key `key`'s value.
const float* key_value(const KeyframeTrack& track, std::size_t key)
{
    std::size_t elements_per_key = track.interpolation == Interpolation::CubicSpline ? 3 : 1;
    std::size_t element = key * elements_per_key + (elements_per_key == 3 ? 1 : 0);
    return &track.values[element * track.components];
}

} // namespace

Vec3 sample_vec3(const KeyframeTrack& track, float time_seconds)
{
    if (track.times.empty())
        return {};
    Bracket b = bracket(track.times, time_seconds, track.interpolation);
    const float* p = key_value(track, b.before);
    const float* q = key_value(track, b.after);
    if (b.before == b.after || b.u == 0)
        return {p[0], p[1], p[2]};
    float u = b.u;
    return {p[0] + (q[0] - p[0]) * u, p[1] + (q[1] - p[1]) * u, p[2] + (q[2] - p[2]) * u};
}

Quat sample_rotation(const KeyframeTrack& track, float time_seconds)
{
    if (track.times.empty())
        return {};
    Bracket b = bracket(track.times, time_seconds, track.interpolation);
    const float* p = key_value(track, b.before);
    const float* q = key_value(track, b.after);
    Quat a{p[0], p[1], p[2], p[3]};
    if (b.before == b.after || b.u == 0)
        return normalize(a);
    return slerp(a, Quat{q[0], q[1], q[2], q[3]}, b.u);
}

} // namespace modestack::scene
