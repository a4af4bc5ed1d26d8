// glTF keyframes and node transforms sampled at given times give exact values:
// LINEAR, STEP, CUBICSPLINE (as LINEAR), quaternion slerp, a node hierarchy,
// matrix nodes and the frame → time mapping.
#include "core/scene/gltf_animation.h"

#include <doctest/doctest.h>

#include <cmath>

using namespace modestack::scene;

namespace {

constexpr float kPi = 3.14159265358979323846f;

void check_vec3(Vec3 actual, Vec3 expected)
{
    CHECK(actual.x == doctest::Approx(expected.x).epsilon(1e-6));
    CHECK(actual.y == doctest::Approx(expected.y).epsilon(1e-6));
    CHECK(actual.z == doctest::Approx(expected.z).epsilon(1e-6));
}

void check_quat(Quat actual, Quat expected)
{
    CHECK(actual.x == doctest::Approx(expected.x).epsilon(1e-6));
    CHECK(actual.y == doctest::Approx(expected.y).epsilon(1e-6));
    CHECK(actual.z == doctest::Approx(expected.z).epsilon(1e-6));
    CHECK(actual.w == doctest::Approx(expected.w).epsilon(1e-6));
}

KeyframeTrack vec3_track(Interpolation interpolation)
{
    KeyframeTrack track;
    track.interpolation = interpolation;
    track.times = {0, 1, 3};
    track.values = {0, 0, 0, 2, 4, 6, 4, 4, 4};
    return track;
}

Quat about_y(float angle)
{
    return {0, std::sin(angle / 2), 0, std::cos(angle / 2)};
}

} // namespace

TEST_CASE("LINEAR keys interpolate linearly and hold the end values outside the keys")
{
    KeyframeTrack track = vec3_track(Interpolation::Linear);
    check_vec3(sample_vec3(track, 0.5f), {1, 2, 3});
    check_vec3(sample_vec3(track, 2.0f), {3, 4, 5});
    check_vec3(sample_vec3(track, 1.0f), {2, 4, 6});
    check_vec3(sample_vec3(track, -1.0f), {0, 0, 0});
    check_vec3(sample_vec3(track, 10.0f), {4, 4, 4});
}

TEST_CASE("STEP keys hold the previous key until the next key's time")
{
    KeyframeTrack track = vec3_track(Interpolation::Step);
    check_vec3(sample_vec3(track, 0.999f), {0, 0, 0});
    check_vec3(sample_vec3(track, 1.0f), {2, 4, 6});
    check_vec3(sample_vec3(track, 2.5f), {2, 4, 6});
    check_vec3(sample_vec3(track, 3.0f), {4, 4, 4});
}

TEST_CASE("CUBICSPLINE keys are sampled as LINEAR between their value elements")
{
    KeyframeTrack track;
    track.interpolation = Interpolation::CubicSpline;
    track.times = {0, 2};
    // in-tangent, value, out-tangent per key: the tangents are ignored.
    track.values = {9, 9, 9, 1, 2, 3, 9, 9, 9, -9, -9, -9, 3, 4, 5, -9, -9, -9};
    check_vec3(sample_vec3(track, 0.0f), {1, 2, 3});
    check_vec3(sample_vec3(track, 1.0f), {2, 3, 4});
    check_vec3(sample_vec3(track, 2.0f), {3, 4, 5});
}

TEST_CASE("rotation keys are interpolated by slerp along the shorter arc")
{
    KeyframeTrack track;
    track.components = 4;
    track.times = {0, 1};
    Quat quarter = about_y(kPi / 2);
    track.values = {0, 0, 0, 1, quarter.x, quarter.y, quarter.z, quarter.w};
    check_quat(sample_rotation(track, 0.5f), about_y(kPi / 4));
    check_quat(sample_rotation(track, 0.25f), about_y(kPi / 8));
    // The same rotation written as −q: still the short way, same result.
    track.values = {0, 0, 0, 1, -quarter.x, -quarter.y, -quarter.z, -quarter.w};
    Quat half_way = sample_rotation(track, 0.5f);
    float sign = half_way.w < 0 ? -1.0f : 1.0f;
    check_quat({sign * half_way.x, sign * half_way.y, sign * half_way.z, sign * half_way.w},
               about_y(kPi / 4));
    // A turn of 270° between keys is slerped the short way (−90°).
    Quat three_quarters = about_y(3 * kPi / 2);
    track.values = {0, 0, 0, 1, three_quarters.x, three_quarters.y, three_quarters.z, three_quarters.w};
    Quat q = sample_rotation(track, 0.5f);
    sign = q.w < 0 ? -1.0f : 1.0f;
    check_quat({sign * q.x, sign * q.y, sign * q.z, sign * q.w}, about_y(-kPi / 4));
}

TEST_CASE("a node hierarchy composes animated parent and child transforms at the given time")
{
    GltfScene gltf;
    gltf.nodes.resize(3);
    gltf.nodes[0].children = {1};
    gltf.nodes[0].rotation = about_y(kPi / 2);
    gltf.nodes[1].parent = 0;
    gltf.nodes[1].children = {2};
    gltf.nodes[1].translation = {0, 0, 1};
    gltf.nodes[1].scale = {2, 2, 2};
    gltf.nodes[2].parent = 1;
    gltf.nodes[2].translation = {0, 1, 0};
    GltfChannel move;
    move.node = 0;
    move.property = AnimatedProperty::Translation;
    move.track.times = {0, 2};
    move.track.values = {0, 0, 0, 4, 0, 0};
    gltf.channels.push_back(move);

    std::vector<Mat4> world = gltf_world_matrices(gltf, 1.0f);
    // Parent at (2, 0, 0) turned 90° about +y: the child's (0, 0, 1) becomes (1, 0, 0).
    check_vec3(transform_point(world[1], {0, 0, 0}), {3, 0, 0});
    // Grandchild: (0, 1, 0) scaled by 2 in the child's space.
    check_vec3(transform_point(world[2], {0, 0, 0}), {3, 2, 0});
    check_vec3(transform_direction(world[2], {0, 0, 1}), {2, 0, 0}); // scaled by 2
    check_vec3(transform_point(gltf_world_matrices(gltf, 0.0f)[2], {0, 0, 0}), {1, 2, 0});
    check_vec3(transform_point(gltf_world_matrices(gltf, 5.0f)[2], {0, 0, 0}), {5, 2, 0});
}

TEST_CASE("a matrix node uses its matrix, and TRS is T·R·S")
{
    GltfScene gltf;
    gltf.nodes.resize(1);
    gltf.nodes[0].has_matrix = true;
    gltf.nodes[0].matrix = trs_matrix({1, 2, 3}, about_y(kPi), {1, 1, -1});
    check_vec3(transform_point(gltf_local_matrix(gltf, 0, 0), {1, 0, 1}), {0, 2, 4});
    CHECK(linear_determinant(gltf_local_matrix(gltf, 0, 0)) == doctest::Approx(-1));
}

TEST_CASE("frame f is at time (f - 1) / fps, and the last frame covers the last key")
{
    CHECK(gltf_frame_time(1, 24) == 0.0f);
    CHECK(gltf_frame_time(25, 24) == doctest::Approx(1.0));
    CHECK(gltf_frame_time(7, 30) == doctest::Approx(0.2));
    GltfScene gltf;
    CHECK(gltf_last_frame(gltf, 24) == 1);
    gltf.end_time_seconds = 23.0f / 24.0f;
    CHECK(gltf_last_frame(gltf, 24) == 24);
    CHECK(gltf_last_frame(gltf, 48) == 47);
    CHECK(gltf_fps(gltf, 0) == 24);
    gltf.file_fps = 30;
    CHECK(gltf_fps(gltf, 0) == 30);
    CHECK(gltf_fps(gltf, 12) == 12);
}
