// Evaluating a glTF node hierarchy at an animation time: each node's local
// transform (its rest T, R, S with every animation channel that drives it sampled
// at that time, or its fixed matrix) and the world transform of every node,
// parents first.
#pragma once

#include "core/scene/gltf_scene.h"

#include <vector>

namespace modestack::scene {

/// Local transform of node `node` at `time_seconds`.
Mat4 gltf_local_matrix(const GltfScene& gltf, int node, float time_seconds);
/// World transform of every node at `time_seconds` (index = node index).
std::vector<Mat4> gltf_world_matrices(const GltfScene& gltf, float time_seconds);

} // namespace modestack::scene
