// Loading a glTF 2.0 file (.gltf with its .bin and images, or .glb) with tinygltf
// into a GltfScene: the default scene's node hierarchy, triangle meshes, the first
// perspective camera, KHR_lights_punctual lights, materials and the translation,
// rotation and scale channels of every animation. Unsupported features and
// approximations are collected in GltfScene::notices (one line per kind); a file
// that cannot be rendered (unreadable, bad JSON, missing buffer, bad accessor,
// unsupported required extension, no camera) is a bad-input error naming it.
#pragma once

#include "core/scene/gltf_scene.h"

#include <string>

namespace modestack::scene {

/// True if `name` ends in .gltf or .glb (any case): --scene takes it as a file.
bool is_gltf_path(const std::string& name);

/// Loads `path`. Throws a bad-input error (one line, naming `path`) when the file
/// cannot be rendered.
GltfScene load_gltf(const std::string& path);

} // namespace modestack::scene
