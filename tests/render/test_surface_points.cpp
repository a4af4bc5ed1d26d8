// Surface points of object space: placement is deterministic and by area, the
// lattice interpolation reproduces linear functions exactly, ids stay on the same
// spot of a moving object, and a changing topology is a clear error.
#include "core/common/error.h"
#include "core/render/surface_points.h"
#include "core/scene/builtin_scenes.h"

#include <doctest/doctest.h>

#include <cmath>
#include <random>

using namespace modestack;
using render::PointPlace;
using render::PointWeight;
using render::SurfacePoints;

namespace {

scene::Vec3 world_position(const scene::Scene& scene, const PointPlace& place)
{
    const scene::Mesh& mesh = scene.meshes[place.mesh];
    auto [p0, p1, p2] = mesh.corners(static_cast<std::size_t>(place.triangle));
    return p0 + (p1 - p0) * place.b1 + (p2 - p0) * place.b2;
}

double mesh_area(const scene::Mesh& mesh)
{
    double area = 0;
    for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
        auto [p0, p1, p2] = mesh.corners(t);
        area += 0.5 * scene::length(scene::cross(p1 - p0, p2 - p0));
    }
    return area;
}

} // namespace

TEST_CASE("surface points: the same scene and spacing give the same points, and the count follows the target")
{
    scene::Scene rest = scene::make_builtin_scene("flythrough", 1);
    for (std::int64_t target : {2000, 20000, 80000}) {
        double spacing = SurfacePoints::spacing_for_count(rest, target);
        SurfacePoints a(rest, spacing, 1 << 24), b(rest, spacing, 1 << 24);
        CHECK(a.count() == b.count());
        std::vector<PointPlace> pa = a.places(), pb = b.places();
        REQUIRE(pa.size() == static_cast<std::size_t>(a.count()));
        for (std::size_t i = 0; i < pa.size(); i += 97) {
            CHECK(pa[i].mesh == pb[i].mesh);
            CHECK(pa[i].triangle == pb[i].triangle);
            CHECK(pa[i].b1 == pb[i].b1);
            CHECK(pa[i].b2 == pb[i].b2);
        }
        // The bisection lands on the smallest spacing not above the target (lattices are whole).
        CHECK(a.count() <= target);
        CHECK(a.count() > target * 8 / 10);
    }
}

TEST_CASE("surface points: placed by area, with no lattice cell longer than the spacing")
{
    scene::Scene rest = scene::make_builtin_scene("static", 1);
    SurfacePoints points(rest, 0.05, 1 << 24);
    std::vector<std::int64_t> per_mesh(rest.meshes.size(), 0);
    for (const PointPlace& place : points.places())
        ++per_mesh[static_cast<std::size_t>(place.mesh)];
    // Points per square metre are the same for every wall and box (within lattice rounding).
    double floor_density = per_mesh[0] / mesh_area(rest.meshes[0]);
    for (std::size_t m = 0; m + 1 < rest.meshes.size(); ++m) { // the small light rounds coarsely
        double density = per_mesh[m] / mesh_area(rest.meshes[m]);
        CHECK_MESSAGE(density == doctest::Approx(floor_density).epsilon(0.35), rest.meshes[m].name);
    }
    for (int mesh = 0; mesh < points.mesh_count(); ++mesh)
        for (std::size_t t = 0; t < rest.meshes[mesh].triangle_count(); ++t) {
            std::array<scene::Vec3, 3> corners = rest.meshes[mesh].corners(t);
            CHECK(scene::length(corners[1] - corners[0]) / points.resolution(mesh, static_cast<int>(t)) <= 0.05 + 1e-6);
        }
}

TEST_CASE("surface points: interpolation weights sum to one and reproduce linear functions exactly")
{
    scene::Scene rest = scene::make_builtin_scene("orbit", 1);
    SurfacePoints points(rest, 0.13, 1 << 24);
    std::vector<PointPlace> places = points.places();
    std::mt19937 random(7);
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    for (int trial = 0; trial < 2000; ++trial) {
        int mesh = static_cast<int>(random() % rest.meshes.size());
        int triangle = static_cast<int>(random() % rest.meshes[mesh].triangle_count());
        float b1 = unit(random), b2 = unit(random);
        if (b1 + b2 > 1)
            b1 = 1 - b1, b2 = 1 - b2;
        PointWeight corners[3];
        points.interpolate(mesh, triangle, b1, b2, corners);
        double sum = 0, f1 = 0, f2 = 0;
        for (const PointWeight& corner : corners) {
            REQUIRE(corner.id >= 0);
            REQUIRE(corner.id < points.count());
            CHECK(corner.weight >= -1e-6f);
            const PointPlace& place = places[static_cast<std::size_t>(corner.id)];
            CHECK(place.mesh == mesh);
            CHECK(place.triangle == triangle);
            sum += corner.weight;
            f1 += corner.weight * place.b1;
            f2 += corner.weight * place.b2;
        }
        CHECK(sum == doctest::Approx(1.0).epsilon(1e-5));
        CHECK(f1 == doctest::Approx(b1).epsilon(1e-4));
        CHECK(f2 == doctest::Approx(b2).epsilon(1e-4));
    }
}

TEST_CASE("surface points: a point stays on the same spot of a moving object")
{
    // flythrough's short box turns about its vertical axis: a point keeps its
    // height and its distance from the axis, frame after frame.
    scene::Scene rest = scene::make_builtin_scene("flythrough", 1);
    scene::Scene later = scene::make_builtin_scene("flythrough", 40);
    SurfacePoints points(rest, 0.1, 1 << 24);
    points.check_topology(later, "flythrough frame 40");
    int box = -1;
    for (std::size_t m = 0; m < rest.meshes.size(); ++m)
        if (rest.meshes[m].name == "short box")
            box = static_cast<int>(m);
    REQUIRE(box >= 0);
    const scene::Vec3 axis{0.4f, 0, 0.2f};
    int checked = 0;
    for (const PointPlace& place : points.places()) {
        if (place.mesh != box)
            continue;
        scene::Vec3 a = world_position(rest, place), b = world_position(later, place);
        CHECK(a.y == doctest::Approx(b.y).epsilon(1e-5));
        double ra = std::hypot(a.x - axis.x, a.z - axis.z), rb = std::hypot(b.x - axis.x, b.z - axis.z);
        CHECK(ra == doctest::Approx(rb).epsilon(1e-4));
        ++checked;
    }
    CHECK(checked > 20);
}

TEST_CASE("surface points: frames whose meshes differ from the rest pose are refused by name")
{
    scene::Scene rest = scene::make_builtin_scene("switch", 1);
    SurfacePoints points(rest, 0.2, 1 << 24);
    points.check_topology(scene::make_builtin_scene("switch", 29), "switch frame 29");
    try {
        points.check_topology(scene::make_builtin_scene("switch", 30), "switch frame 30");
        FAIL("no error");
    } catch (const Error& error) {
        CHECK(error.kind() == ErrorKind::BadInput);
        CHECK(std::string(error.what()).find("switch frame 30") != std::string::npos);
        CHECK(std::string(error.what()).find("same meshes in every frame") != std::string::npos);
    }
    CHECK_THROWS_AS(SurfacePoints(rest, 0.0, 1 << 24), Error);
    CHECK_THROWS_AS(SurfacePoints(rest, 0.001, 1000), Error);
}
