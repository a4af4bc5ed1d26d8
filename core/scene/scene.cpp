// Builders for the pieces of a scene (see scene.h).
#include "core/scene/scene.h"

#include <cmath>

namespace modestack::scene {

void add_quad(Mesh& mesh, Vec3 p0, Vec3 p1, Vec3 p2, Vec3 p3)
{
    auto first = static_cast<std::uint32_t>(mesh.positions.size());
    mesh.positions.insert(mesh.positions.end(), {p0, p1, p2, p3});
    mesh.indices.insert(mesh.indices.end(), {first, first + 1, first + 2, first, first + 2, first + 3});
}

Mesh make_box(const std::string& name, Vec3 base_center, Vec3 size, float angle_radians,
              const Material& material)
{
    Mesh box;
    box.name = name;
    box.material = material;
    float c = std::cos(angle_radians), s = std::sin(angle_radians);
    // Corner (i, j, k) ∈ {0,1}³ of the box before the turn, then turned about +y.
    auto corner = [&](int i, int j, int k) {
        float x = (i ? 0.5f : -0.5f) * size.x, y = j ? size.y : 0.0f, z = (k ? 0.5f : -0.5f) * size.z;
        return Vec3{base_center.x + c * x + s * z, base_center.y + y, base_center.z - s * x + c * z};
    };
    add_quad(box, corner(0, 0, 1), corner(1, 0, 1), corner(1, 1, 1), corner(0, 1, 1)); // +z
    add_quad(box, corner(1, 0, 0), corner(0, 0, 0), corner(0, 1, 0), corner(1, 1, 0)); // -z
    add_quad(box, corner(1, 0, 1), corner(1, 0, 0), corner(1, 1, 0), corner(1, 1, 1)); // +x
    add_quad(box, corner(0, 0, 0), corner(0, 0, 1), corner(0, 1, 1), corner(0, 1, 0)); // -x
    add_quad(box, corner(0, 1, 1), corner(1, 1, 1), corner(1, 1, 0), corner(0, 1, 0)); // +y
    add_quad(box, corner(0, 0, 0), corner(1, 0, 0), corner(1, 0, 1), corner(0, 0, 1)); // -y
    return box;
}

Mesh make_ceiling_light(const std::string& name, Vec3 center, float width, float depth, Vec3 emission)
{
    Mesh light;
    light.name = name;
    light.material.albedo = {0.78f, 0.78f, 0.78f};
    light.material.emission = emission;
    float hx = 0.5f * width, hz = 0.5f * depth;
    // Counter-clockwise seen from below, so the front faces down.
    add_quad(light, {center.x - hx, center.y, center.z - hz}, {center.x + hx, center.y, center.z - hz},
             {center.x + hx, center.y, center.z + hz}, {center.x - hx, center.y, center.z + hz});
    return light;
}

} // namespace modestack::scene
