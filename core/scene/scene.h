// The plain scene description the path tracer renders: triangle meshes with a
// Lambertian material (albedo and emitted radiance), a pinhole camera, and helpers
// to build the quads and boxes the built-in rooms are made of. Lights are not a
// separate kind of object: any mesh with non-zero emission is an area light that
// emits from the side its triangles face (counter-clockwise winding seen from the
// front). Units: metres for positions, linear RGB radiance for emission.
#pragma once

#include "core/scene/vec3.h"

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace modestack::scene {

/// A Lambertian surface, optionally emitting.
struct Material {
    Vec3 albedo{0.5f, 0.5f, 0.5f}; ///< diffuse reflectance per RGB channel, each in [0, 1)
    Vec3 emission{0, 0, 0};        ///< emitted radiance (W·sr⁻¹·m⁻², linear RGB), front side only
    bool is_emissive() const { return emission.x > 0 || emission.y > 0 || emission.z > 0; }
};

/// A triangle mesh with one material.
struct Mesh {
    std::string name;                   ///< for messages and debugging ("floor", "light", ...)
    std::vector<Vec3> positions;        ///< world-space vertex positions
    std::vector<std::uint32_t> indices; ///< three vertex indices per triangle
    Material material;

    std::size_t triangle_count() const { return indices.size() / 3; }
    /// The corners of triangle `t` in winding order (its indices must be in range).
    std::array<Vec3, 3> corners(std::size_t t) const
    {
        return {positions[indices[3 * t]], positions[indices[3 * t + 1]], positions[indices[3 * t + 2]]};
    }
};

/// A pinhole camera.
struct Camera {
    Vec3 position{0, 1, 3};
    Vec3 look_at{0, 1, 0};
    Vec3 up{0, 1, 0};
    float vertical_fov_degrees = 45; ///< full vertical field of view
};

/// Everything the tracer needs for one frame.
struct Scene {
    std::vector<Mesh> meshes;
    Camera camera;
};

/// Appends the quad p0 p1 p2 p3 (counter-clockwise seen from its front) to `mesh`
/// as two triangles.
void add_quad(Mesh& mesh, Vec3 p0, Vec3 p1, Vec3 p2, Vec3 p3);

/// A box of size `size` standing on `base_center` (the centre of its bottom face),
/// turned by `angle_radians` about the vertical (+y) axis, faces pointing outwards.
Mesh make_box(const std::string& name, Vec3 base_center, Vec3 size, float angle_radians,
              const Material& material);

/// A horizontal quad light of `width` × `depth` centred on `center`, facing down (−y).
Mesh make_ceiling_light(const std::string& name, Vec3 center, float width, float depth, Vec3 emission);

} // namespace modestack::scene
