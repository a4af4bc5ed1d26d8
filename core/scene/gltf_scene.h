// A glTF 2.0 scene as loaded (see gltf_loader.h): plain data, independent of the
// file format and of time, plus the function that builds the scene::Scene the
// path tracer renders at any animation time. Every quantity is computed from the
// time alone (as the built-in scenes are from the frame number), so refine and
// single-frame renders rebuild any frame exactly. Frame f is at time (f − 1) / fps.
#pragma once

#include "core/scene/gltf_keyframes.h"
#include "core/scene/gltf_math.h"
#include "core/scene/gltf_notices.h"
#include "core/scene/scene.h"

#include <cstdint>
#include <string>
#include <vector>

namespace modestack::scene {

/// One node of the hierarchy with its rest transform.
struct GltfNode {
    std::string name;
    int parent = -1; ///< index into GltfScene::nodes, −1 for a root
    std::vector<int> children;
    Vec3 translation{0, 0, 0};
    Quat rotation;
    Vec3 scale{1, 1, 1};
    bool has_matrix = false; ///< the node gives `matrix` instead of T, R, S (not animatable)
    Mat4 matrix;
    int mesh = -1;   ///< index into GltfScene::meshes
    int camera = -1; ///< index into GltfScene::cameras
    int light = -1;  ///< index into GltfScene::lights
};

/// Which node property an animation channel drives.
enum class AnimatedProperty { Translation, Rotation, Scale };

/// One animation channel: a node property and its keys.
struct GltfChannel {
    int node = -1;
    AnimatedProperty property = AnimatedProperty::Translation;
    KeyframeTrack track;
};

/// One triangle list in the mesh's own space.
struct GltfPrimitive {
    std::vector<Vec3> positions;
    std::vector<std::uint32_t> indices; ///< three per triangle
    Material material;
};

struct GltfMesh {
    std::string name;
    std::vector<GltfPrimitive> primitives;
};

/// A perspective camera (looks down its node's −z with +y up, as glTF says).
struct GltfCamera {
    float vertical_fov_radians = 0.8f;
};

enum class GltfLightType { Point, Spot, Directional };

/// A KHR_lights_punctual light, in glTF's photometric units.
struct GltfLight {
    std::string name;
    GltfLightType type = GltfLightType::Point;
    Vec3 color{1, 1, 1};
    float intensity = 1; ///< candela (point, spot) or lux (directional)
};

/// The whole file.
struct GltfScene {
    std::string file; ///< for messages and provenance
    std::vector<GltfNode> nodes;
    std::vector<int> roots; ///< the root nodes of the scene rendered
    std::vector<GltfMesh> meshes;
    std::vector<GltfCamera> cameras;
    std::vector<GltfLight> lights;
    std::vector<GltfChannel> channels; ///< of every animation, played together
    int camera_node = -1;              ///< the first camera node of the scene (depth first)
    float end_time_seconds = 0;        ///< last key time of every channel (0 if static)
    double file_fps = 0; ///< frames per second the file asks for (scene extras "fps"), 0 if none
    GltfNotices notices; ///< approximations and unsupported features, one line each
};

/// Frames per second: `requested` when positive, else the file's, else 24.
double gltf_fps(const GltfScene& gltf, double requested);
/// Animation time of frame `frame` (the first frame is 1): (frame − 1) / fps.
float gltf_frame_time(int frame, double fps);
/// The last frame whose time lies within the animation (1 for a static scene).
int gltf_last_frame(const GltfScene& gltf, double fps);

/// The scene the tracer renders at `time_seconds`: every primitive moved to world
/// space, the camera, and each light as a small emitter (see gltf_lights.h).
Scene gltf_scene_at(const GltfScene& gltf, float time_seconds);

} // namespace modestack::scene
