// Node transforms at a given time (see gltf_animation.h).
#include "core/scene/gltf_animation.h"

namespace modestack::scene {

Mat4 gltf_local_matrix(const GltfScene& gltf, int node, float time_seconds)
{
    const GltfNode& n = gltf.nodes[node];
    if (n.has_matrix)
        return n.matrix;
    Vec3 translation = n.translation, scale = n.scale;
    Quat rotation = n.rotation;
    for (const GltfChannel& channel : gltf.channels) {
        if (channel.node != node)
            continue;
        switch (channel.property) {
        case AnimatedProperty::Translation:
            translation = sample_vec3(channel.track, time_seconds);
            break;
        case AnimatedProperty::Rotation:
            rotation = sample_rotation(channel.track, time_seconds);
            break;
        case AnimatedProperty::Scale:
            scale = sample_vec3(channel.track, time_seconds);
            break;
        }
    }
    return trs_matrix(translation, rotation, scale);
}

std::vector<Mat4> gltf_world_matrices(const GltfScene& gltf, float time_seconds)
{
    std::vector<Mat4> world(gltf.nodes.size());
    // Parents first: walk down from every root (the loader guarantees a forest).
    std::vector<int> stack;
    for (std::size_t i = 0; i < gltf.nodes.size(); ++i)
        if (gltf.nodes[i].parent < 0)
            stack.push_back(static_cast<int>(i));
    while (!stack.empty()) {
        int node = stack.back();
        stack.pop_back();
        Mat4 local = gltf_local_matrix(gltf, node, time_seconds);
        int parent = gltf.nodes[node].parent;
        world[node] = parent < 0 ? local : world[parent] * local;
        for (int child : gltf.nodes[node].children)
            stack.push_back(child);
    }
    return world;
}

} // namespace modestack::scene
