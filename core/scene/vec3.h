// A three-component float vector and the few operations the scene builder and the
// path tracer need (points, directions, RGB colours). Header-only and free of any
// dependency so that scene descriptions stay plain data that tests can build.
#pragma once

#include <cmath>

namespace modestack::scene {

/// A point, a direction or a linear RGB colour, in single precision.
struct Vec3 {
    float x = 0, y = 0, z = 0;
};

inline Vec3 operator+(Vec3 a, Vec3 b)
{
    return {a.x + b.x, a.y + b.y, a.z + b.z};
}
inline Vec3 operator-(Vec3 a, Vec3 b)
{
    return {a.x - b.x, a.y - b.y, a.z - b.z};
}
inline Vec3 operator-(Vec3 a)
{
    return {-a.x, -a.y, -a.z};
}
/// Component-wise product (colours).
inline Vec3 operator*(Vec3 a, Vec3 b)
{
    return {a.x * b.x, a.y * b.y, a.z * b.z};
}
inline Vec3 operator*(Vec3 a, float s)
{
    return {a.x * s, a.y * s, a.z * s};
}
inline Vec3 operator*(float s, Vec3 a)
{
    return a * s;
}
inline Vec3& operator+=(Vec3& a, Vec3 b)
{
    return a = a + b;
}
inline float dot(Vec3 a, Vec3 b)
{
    return a.x * b.x + a.y * b.y + a.z * b.z;
}
inline Vec3 cross(Vec3 a, Vec3 b)
{
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline float length(Vec3 a)
{
    return std::sqrt(dot(a, a));
}
/// `a` scaled to unit length; `a` must not be the zero vector.
inline Vec3 normalize(Vec3 a)
{
    return a * (1.0f / length(a));
}
inline float max_component(Vec3 a)
{
    return std::fmax(a.x, std::fmax(a.y, a.z));
}
/// Rec. 709 luminance of a linear RGB colour.
inline float luminance(Vec3 rgb)
{
    return 0.2126f * rgb.x + 0.7152f * rgb.y + 0.0722f * rgb.z;
}

} // namespace modestack::scene
