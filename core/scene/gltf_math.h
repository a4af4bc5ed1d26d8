// The little transform algebra glTF needs on top of Vec3: unit quaternions (node
// rotations and their spherical interpolation) and 4×4 affine matrices (node and
// world transforms), column-major as glTF stores them. Header-only and free of any
// dependency, like vec3.h, so that tests can check transforms exactly.
#pragma once

#include "core/scene/vec3.h"

#include <cmath>

namespace modestack::scene {

/// A rotation as a unit quaternion (x, y, z, w), glTF's order.
struct Quat {
    float x = 0, y = 0, z = 0, w = 1;
};

/// `q` scaled to unit length (the identity for the zero quaternion).
inline Quat normalize(Quat q)
{
    float n = std::sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w);
    return n > 0 ? Quat{q.x / n, q.y / n, q.z / n, q.w / n} : Quat{};
}

/// Spherical linear interpolation from `a` (u = 0) to `b` (u = 1) along the shorter arc;
/// falls back to normalised linear interpolation when the two are almost equal.
inline Quat slerp(Quat a, Quat b, float u)
{
    double cos_angle = double(a.x) * b.x + double(a.y) * b.y + double(a.z) * b.z + double(a.w) * b.w;
    double sign = 1;
    if (cos_angle < 0) {
        cos_angle = -cos_angle;
        sign = -1;
    }
    double wa = 1 - u, wb = u;
    if (cos_angle < 0.9995) {
        double angle = std::acos(cos_angle), sin_angle = std::sin(angle);
        wa = std::sin((1 - u) * angle) / sin_angle;
        wb = std::sin(u * angle) / sin_angle;
    }
    wb *= sign;
    return normalize(Quat{float(wa * a.x + wb * b.x), float(wa * a.y + wb * b.y), float(wa * a.z + wb * b.z),
                          float(wa * a.w + wb * b.w)});
}

/// A 4×4 matrix, column-major: element (row r, column c) is m[4 * c + r].
struct Mat4 {
    float m[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    float at(int row, int column) const { return m[4 * column + row]; }
};

inline Mat4 operator*(const Mat4& a, const Mat4& b)
{
    Mat4 product;
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r) {
            double sum = 0;
            for (int k = 0; k < 4; ++k)
                sum += double(a.at(r, k)) * b.at(k, c);
            product.m[4 * c + r] = float(sum);
        }
    return product;
}

/// The point `p` moved by the affine matrix `a`.
inline Vec3 transform_point(const Mat4& a, Vec3 p)
{
    return {a.at(0, 0) * p.x + a.at(0, 1) * p.y + a.at(0, 2) * p.z + a.at(0, 3),
            a.at(1, 0) * p.x + a.at(1, 1) * p.y + a.at(1, 2) * p.z + a.at(1, 3),
            a.at(2, 0) * p.x + a.at(2, 1) * p.y + a.at(2, 2) * p.z + a.at(2, 3)};
}

/// The direction `d` turned (and scaled) by the linear part of `a`.
inline Vec3 transform_direction(const Mat4& a, Vec3 d)
{
    return {a.at(0, 0) * d.x + a.at(0, 1) * d.y + a.at(0, 2) * d.z,
            a.at(1, 0) * d.x + a.at(1, 1) * d.y + a.at(1, 2) * d.z,
            a.at(2, 0) * d.x + a.at(2, 1) * d.y + a.at(2, 2) * d.z};
}

/// Determinant of the linear (upper-left 3×3) part; negative for a mirroring transform.
inline float linear_determinant(const Mat4& a)
{
    return a.at(0, 0) * (a.at(1, 1) * a.at(2, 2) - a.at(1, 2) * a.at(2, 1)) -
           a.at(0, 1) * (a.at(1, 0) * a.at(2, 2) - a.at(1, 2) * a.at(2, 0)) +
           a.at(0, 2) * (a.at(1, 0) * a.at(2, 1) - a.at(1, 1) * a.at(2, 0));
}

/// T · R · S, glTF's order for a node's translation, rotation and scale.
inline Mat4 trs_matrix(Vec3 translation, Quat rotation, Vec3 scale)
{
    Quat q = normalize(rotation);
    float xx = q.x * q.x, yy = q.y * q.y, zz = q.z * q.z;
    float xy = q.x * q.y, xz = q.x * q.z, yz = q.y * q.z, wx = q.w * q.x, wy = q.w * q.y, wz = q.w * q.z;
    Mat4 result;
    // Columns: rotated and scaled axes, then the translation.
    float columns[3][3] = {{1 - 2 * (yy + zz), 2 * (xy + wz), 2 * (xz - wy)},
                           {2 * (xy - wz), 1 - 2 * (xx + zz), 2 * (yz + wx)},
                           {2 * (xz + wy), 2 * (yz - wx), 1 - 2 * (xx + yy)}};
    float scales[3] = {scale.x, scale.y, scale.z};
    for (int c = 0; c < 3; ++c)
        for (int r = 0; r < 3; ++r)
            result.m[4 * c + r] = columns[c][r] * scales[c];
    result.m[12] = translation.x;
    result.m[13] = translation.y;
    result.m[14] = translation.z;
    return result;
}

} // namespace modestack::scene
