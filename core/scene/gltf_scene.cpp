// Building the tracer's scene from a glTF scene at one time (see gltf_scene.h).
#include "core/scene/gltf_scene.h"

#include "core/scene/gltf_animation.h"
#include "core/scene/gltf_lights.h"

#include <algorithm>
#include <cmath>

namespace modestack::scene {
namespace {

constexpr double kDefaultFps = 24;
constexpr float kPi = 3.14159265358979323846f;

// The nodes of the scene, parents before children (depth first from the roots).
std::vector<int> scene_nodes(const GltfScene& gltf)
{
    std::vector<int> order, stack(gltf.roots.rbegin(), gltf.roots.rend());
    while (!stack.empty()) {
        int node = stack.back();
        stack.pop_back();
        order.push_back(node);
        const auto& children = gltf.nodes[node].children;
        stack.insert(stack.end(), children.rbegin(), children.rend());
    }
    return order;
}

} // namespace

double gltf_fps(const GltfScene& gltf, double requested)
{
    if (requested > 0)
        return requested;
    return gltf.file_fps > 0 ? gltf.file_fps : kDefaultFps;
}

float gltf_frame_time(int frame, double fps)
{
    return static_cast<float>((frame - 1) / fps);
}

int gltf_last_frame(const GltfScene& gltf, double fps)
{
    // The small tolerance keeps a last key at exactly a frame time (1 s at 24 fps).
    return 1 + static_cast<int>(std::floor(gltf.end_time_seconds * fps + 1e-4));
}

Scene gltf_scene_at(const GltfScene& gltf, float time_seconds)
{
    Scene scene;
    std::vector<Mat4> world = gltf_world_matrices(gltf, time_seconds);
    std::vector<int> nodes = scene_nodes(gltf);
    Vec3 low{1e30f, 1e30f, 1e30f}, high{-1e30f, -1e30f, -1e30f};
    for (int node : nodes) {
        int mesh_index = gltf.nodes[node].mesh;
        if (mesh_index < 0)
            continue;
        const GltfMesh& mesh = gltf.meshes[mesh_index];
        bool mirrored = linear_determinant(world[node]) < 0;
        for (std::size_t p = 0; p < mesh.primitives.size(); ++p) {
            const GltfPrimitive& primitive = mesh.primitives[p];
            Mesh out;
            out.name = mesh.primitives.size() > 1 ? mesh.name + "." + std::to_string(p) : mesh.name;
            out.material = primitive.material;
            out.positions.reserve(primitive.positions.size());
            for (Vec3 position : primitive.positions) {
                Vec3 q = transform_point(world[node], position);
                out.positions.push_back(q);
                low = {std::min(low.x, q.x), std::min(low.y, q.y), std::min(low.z, q.z)};
                high = {std::max(high.x, q.x), std::max(high.y, q.y), std::max(high.z, q.z)};
            }
            out.indices = primitive.indices;
            // A mirroring transform turns counter-clockwise into clockwise: swap back
            // so that the front side (and emission) stays where glTF puts it.
            if (mirrored)
                for (std::size_t t = 0; t + 2 < out.indices.size(); t += 3)
                    std::swap(out.indices[t + 1], out.indices[t + 2]);
            scene.meshes.push_back(std::move(out));
        }
    }
    Vec3 center{0, 0, 0};
    float radius = 1;
    if (!scene.meshes.empty()) {
        center = (low + high) * 0.5f;
        radius = 0.5f * length(high - low);
    }
    for (int node : nodes)
        if (gltf.nodes[node].light >= 0)
            scene.meshes.push_back(
                gltf_light_mesh(gltf.lights[gltf.nodes[node].light], world[node], center, radius));

    if (gltf.camera_node >= 0) {
        const Mat4& camera = world[gltf.camera_node];
        Vec3 position = transform_point(camera, {0, 0, 0});
        Vec3 forward = normalize(transform_direction(camera, {0, 0, -1}));
        scene.camera.position = position;
        scene.camera.look_at = position + forward;
        scene.camera.up = normalize(transform_direction(camera, {0, 1, 0}));
        scene.camera.vertical_fov_degrees =
            gltf.cameras[gltf.nodes[gltf.camera_node].camera].vertical_fov_radians * (180.0f / kPi);
    }
    return scene;
}

} // namespace modestack::scene
