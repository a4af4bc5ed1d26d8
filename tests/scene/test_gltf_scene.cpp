// The tracer's scene built from glTF data at a given time: world-space meshes
// (mirroring transforms keep the front side), the animated camera, and the
// punctual lights as emitters with the documented radiometry.
#include "core/scene/gltf_lights.h"
#include "core/scene/gltf_scene.h"

#include <doctest/doctest.h>

#include <cmath>

using namespace modestack::scene;

namespace {

constexpr float kPi = 3.14159265358979323846f;

Quat about_y(float angle)
{
    return {0, std::sin(angle / 2), 0, std::cos(angle / 2)};
}

void check_vec3(Vec3 actual, Vec3 expected, double epsilon = 1e-5)
{
    CHECK(actual.x == doctest::Approx(expected.x).epsilon(epsilon));
    CHECK(actual.y == doctest::Approx(expected.y).epsilon(epsilon));
    CHECK(actual.z == doctest::Approx(expected.z).epsilon(epsilon));
}

Vec3 front_normal(const Mesh& mesh, std::size_t triangle)
{
    auto [p0, p1, p2] = mesh.corners(triangle);
    return cross(p1 - p0, p2 - p0);
}

// One camera node (animated) and one node with a triangle, as the loader builds them.
GltfScene camera_and_triangle()
{
    GltfScene gltf;
    gltf.cameras.push_back({kPi / 3});
    gltf.nodes.resize(2);
    gltf.roots = {0, 1};
    gltf.nodes[0].camera = 0;
    gltf.camera_node = 0;
    GltfChannel move;
    move.node = 0;
    move.track.times = {0, 1};
    move.track.values = {0, 1, 5, 2, 1, 5};
    gltf.channels.push_back(move);
    GltfChannel turn;
    turn.node = 0;
    turn.property = AnimatedProperty::Rotation;
    turn.track.components = 4;
    turn.track.times = {0, 1};
    Quat quarter = about_y(kPi / 2);
    turn.track.values = {0, 0, 0, 1, quarter.x, quarter.y, quarter.z, quarter.w};
    gltf.channels.push_back(turn);
    gltf.end_time_seconds = 1;
    GltfMesh mesh;
    mesh.name = "tri";
    GltfPrimitive primitive;
    primitive.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    primitive.indices = {0, 1, 2};
    primitive.material.emission = {1, 2, 3};
    mesh.primitives.push_back(primitive);
    gltf.meshes.push_back(mesh);
    gltf.nodes[1].mesh = 0;
    gltf.nodes[1].translation = {0, 0, -2};
    return gltf;
}

} // namespace

TEST_CASE("the camera follows its animated node: position, view direction (-z), up (+y), fov")
{
    GltfScene gltf = camera_and_triangle();
    Scene start = gltf_scene_at(gltf, 0);
    check_vec3(start.camera.position, {0, 1, 5});
    check_vec3(start.camera.look_at - start.camera.position, {0, 0, -1});
    check_vec3(start.camera.up, {0, 1, 0});
    CHECK(start.camera.vertical_fov_degrees == doctest::Approx(60));
    Scene middle = gltf_scene_at(gltf, 0.5f);
    check_vec3(middle.camera.position, {1, 1, 5});
    // 45° about +y turns −z towards −x.
    check_vec3(middle.camera.look_at - middle.camera.position, {-std::sqrt(0.5f), 0, -std::sqrt(0.5f)});
    Scene end = gltf_scene_at(gltf, 1);
    check_vec3(end.camera.look_at - end.camera.position, {-1, 0, 0});
}

TEST_CASE("meshes go to world space with their material, and a mirroring scale keeps the front side")
{
    GltfScene gltf = camera_and_triangle();
    Scene scene = gltf_scene_at(gltf, 0);
    REQUIRE(scene.meshes.size() == 1);
    CHECK(scene.meshes[0].name == "tri");
    check_vec3(scene.meshes[0].positions[1], {1, 0, -2});
    check_vec3(scene.meshes[0].material.emission, {1, 2, 3});
    check_vec3(normalize(front_normal(scene.meshes[0], 0)), {0, 0, 1});
    gltf.nodes[1].scale = {-1, 1, 1};
    Scene mirrored = gltf_scene_at(gltf, 0);
    check_vec3(mirrored.meshes[0].positions[1], {-1, 0, -2});
    check_vec3(normalize(front_normal(mirrored.meshes[0], 0)), {0, 0, 1});
}

TEST_CASE("a point light is a 5 cm sphere, facing out, of intensity candela / 683 in W/sr")
{
    GltfLight light;
    light.type = GltfLightType::Point;
    light.color = {1, 0.5f, 0.25f};
    light.intensity = 683;
    Mesh mesh = gltf_light_mesh(light, trs_matrix({1, 2, 3}, {}, {7, 7, 7}), {}, 1);
    double area = 0;
    for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
        Vec3 n = front_normal(mesh, t);
        area += 0.5 * length(n);
        Vec3 middle = (mesh.positions[mesh.indices[3 * t]] + mesh.positions[mesh.indices[3 * t + 1]] +
                       mesh.positions[mesh.indices[3 * t + 2]]) *
                      (1.0f / 3);
        if (length(n) > 0)
            CHECK(dot(n, middle - Vec3{1, 2, 3}) > 0);
    }
    for (Vec3 p : mesh.positions) // the node's scale does not resize the light
        CHECK(length(p - Vec3{1, 2, 3}) == doctest::Approx(kPointLightRadius).epsilon(1e-4));
    // Mean projected area = area / 4, so the mean intensity is L · area / 4 = 1 W/sr × colour.
    check_vec3(mesh.material.emission * static_cast<float>(area / 4), {1, 0.5f, 0.25f}, 1e-4);
    CHECK(area == doctest::Approx(4 * kPi * kPointLightRadius * kPointLightRadius).epsilon(0.05));
}

TEST_CASE("a spot light is a small square facing the spot's direction with the same on-axis intensity")
{
    GltfLight light;
    light.type = GltfLightType::Spot;
    light.intensity = 2 * 683;
    // The node turned 90° about +y: the spot shines along −x.
    Mesh mesh = gltf_light_mesh(light, trs_matrix({0, 1, 0}, about_y(kPi / 2), {1, 1, 1}), {}, 1);
    REQUIRE(mesh.triangle_count() == 2);
    check_vec3(normalize(front_normal(mesh, 0)), {-1, 0, 0});
    check_vec3(normalize(front_normal(mesh, 1)), {-1, 0, 0});
    // On-axis intensity L · side² = 2 W/sr.
    CHECK(mesh.material.emission.x * kSpotLightSide * kSpotLightSide == doctest::Approx(2));
}

TEST_CASE("a directional light is a large square outside the scene's bounds, shining along the light")
{
    GltfLight light;
    light.type = GltfLightType::Directional;
    light.intensity = 683;
    Mesh mesh = gltf_light_mesh(light, Mat4{}, {0, 1, 0}, 2); // shines along −z
    check_vec3(normalize(front_normal(mesh, 0)), {0, 0, -1});
    for (Vec3 p : mesh.positions)
        CHECK(p.z == doctest::Approx(4));
    CHECK(mesh.material.emission.x * 4 * std::asin(0.2f) == doctest::Approx(1));
}

TEST_CASE("lights are placed by their nodes in the frame's scene, after the meshes")
{
    GltfScene gltf = camera_and_triangle();
    gltf.lights.push_back({"lamp", GltfLightType::Point, {1, 1, 1}, 100});
    gltf.nodes.push_back({});
    gltf.nodes[2].light = 0;
    gltf.nodes[2].translation = {0, 3, 0};
    gltf.roots.push_back(2);
    Scene scene = gltf_scene_at(gltf, 0);
    REQUIRE(scene.meshes.size() == 2);
    CHECK(scene.meshes[1].name == "lamp");
    CHECK(scene.meshes[1].material.is_emissive());
    CHECK(length(scene.meshes[1].positions[0] - Vec3{0, 3, 0}) == doctest::Approx(kPointLightRadius));
}
