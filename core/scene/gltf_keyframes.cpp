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

// The values of the two keys around `time` and the fraction between them; `u` is 0
// when only the first counts (one key, outside the keys, STEP, or exactly on a key).
struct KeyPair {
    const float* before;
    const float* after;
    float u;
};

KeyPair key_pair(const KeyframeTrack& track, float time)
{
    Bracket b = bracket(track.times, time, track.interpolation);
    // CubicSpline stores (in-tangent, value, out-tangent) per key: take the value.
    std::size_t elements_per_key = track.interpolation == Interpolation::CubicSpline ? 3 : 1;
    std::size_t skip = elements_per_key == 3 ? 1 : 0;
    auto value = [&](std::size_t key) {
        return &track.values[(key * elements_per_key + skip) * track.components];
    };
    return {value(b.before), value(b.after), b.before == b.after ? 0.0f : b.u};
}

} // namespace

Vec3 sample_vec3(const KeyframeTrack& track, float time_seconds)
{
    if (track.times.empty())
        return {};
    KeyPair k = key_pair(track, time_seconds);
    const float *p = k.before, *q = k.after;
    if (k.u == 0)
        return {p[0], p[1], p[2]};
    return {p[0] + (q[0] - p[0]) * k.u, p[1] + (q[1] - p[1]) * k.u, p[2] + (q[2] - p[2]) * k.u};
}

Quat sample_rotation(const KeyframeTrack& track, float time_seconds)
{
    if (track.times.empty())
        return {};
    KeyPair k = key_pair(track, time_seconds);
    Quat a{k.before[0], k.before[1], k.before[2], k.before[3]};
    if (k.u == 0)
        return normalize(a);
    return slerp(a, Quat{k.after[0], k.after[1], k.after[2], k.after[3]}, k.u);
}

} // namespace modestack::scene
