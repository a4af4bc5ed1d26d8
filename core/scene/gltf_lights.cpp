// Punctual lights as small emitters (see gltf_lights.h).
#include "core/scene/gltf_lights.h"

#include <cmath>
#include <utility>

namespace modestack::scene {
namespace {

constexpr float kPi = 3.14159265358979323846f;
constexpr float kLumensPerWatt = 683.0f;
constexpr int kSphereRings = 8;     // latitude bands of the point-light sphere
constexpr int kSphereSegments = 16; // longitude segments

// Two unit vectors t, b with cross(t, b) = n (n unit).
void basis(Vec3 n, Vec3& t, Vec3& b)
{
    Vec3 helper = std::fabs(n.y) < 0.9f ? Vec3{0, 1, 0} : Vec3{1, 0, 0};
    t = normalize(cross(helper, n));
    b = cross(n, t);
}

// A square of side `side` centred on `center`, its front (emitting) side facing `facing`.
void add_square(Mesh& mesh, Vec3 center, Vec3 facing, float side)
{
    Vec3 t, b;
    basis(facing, t, b);
    float h = 0.5f * side;
    add_quad(mesh, center - t * h - b * h, center + t * h - b * h, center + t * h + b * h,
             center - t * h + b * h);
}

void add_sphere(Mesh& mesh, Vec3 center, float radius)
{
    auto point = [&](int ring, int segment) {
        float theta = kPi * ring / kSphereRings, phi = 2 * kPi * segment / kSphereSegments;
        return center +
               Vec3{std::sin(theta) * std::cos(phi), std::cos(theta), std::sin(theta) * std::sin(phi)} *
                   radius;
    };
    for (int ring = 0; ring < kSphereRings; ++ring)
        for (int segment = 0; segment < kSphereSegments; ++segment) {
            Vec3 corners[4] = {point(ring, segment), point(ring + 1, segment), point(ring + 1, segment + 1),
                               point(ring, segment + 1)};
            // Front side outwards: flip the winding if the quad's normal points in.
            Vec3 middle = (corners[0] + corners[2]) * 0.5f;
            Vec3 normal = cross(corners[1] - corners[0], corners[2] - corners[0]);
            if (ring == kSphereRings - 1) // the bottom band's second corner pair meets at the pole
                normal = cross(corners[2] - corners[0], corners[3] - corners[0]);
            if (dot(normal, middle - center) < 0)
                std::swap(corners[1], corners[3]);
            add_quad(mesh, corners[0], corners[1], corners[2], corners[3]);
        }
}

double mesh_area(const Mesh& mesh)
{
    double area = 0;
    for (std::size_t t = 0; t + 2 < mesh.indices.size(); t += 3) {
        Vec3 p0 = mesh.positions[mesh.indices[t]], p1 = mesh.positions[mesh.indices[t + 1]],
             p2 = mesh.positions[mesh.indices[t + 2]];
        area += 0.5 * length(cross(p1 - p0, p2 - p0));
    }
    return area;
}

} // namespace

Mesh gltf_light_mesh(const GltfLight& light, const Mat4& world, Vec3 scene_center, float scene_radius)
{
    Mesh mesh;
    mesh.name = light.name.empty() ? "light" : light.name;
    mesh.material.albedo = {0, 0, 0};
    Vec3 position = transform_point(world, {0, 0, 0});
    Vec3 direction = transform_direction(world, {0, 0, -1});
    direction = length(direction) > 0 ? normalize(direction) : Vec3{0, 0, -1};
    Vec3 radiometric = light.color * (light.intensity / kLumensPerWatt); // W/sr or W/m²
    switch (light.type) {
    case GltfLightType::Point:
        add_sphere(mesh, position, kPointLightRadius);
        // A convex body's mean projected area is its surface area / 4 (Cauchy); using
        // the tessellated sphere's own area keeps the emitted power exact.
        mesh.material.emission = radiometric * static_cast<float>(4 / mesh_area(mesh));
        break;
    case GltfLightType::Spot:
        add_square(mesh, position, direction, kSpotLightSide);
        mesh.material.emission = radiometric * (1 / (kSpotLightSide * kSpotLightSide));
        break;
    case GltfLightType::Directional: {
        float radius = scene_radius > 0 ? scene_radius : 1.0f;
        add_square(mesh, scene_center - direction * (2 * radius), direction, 2 * radius);
        // A side-2R square at 2R subtends 4·asin(1/5) ≈ 0.8 sr from the centre: E ≈ L · Ω.
        mesh.material.emission = radiometric * (1 / (4 * std::asin(0.2f)));
        break;
    }
    }
    return mesh;
}

} // namespace modestack::scene
