// The built-in animated rooms (see builtin_scenes.h). Every quantity that moves
// is computed from the frame number alone, never accumulated from earlier frames.
#include "core/scene/builtin_scenes.h"

#include "core/common/error.h"

#include <cmath>

namespace modestack::scene {
namespace {

constexpr int kFirstFrame = 1;
constexpr int kLastFrame = 48;
constexpr float kPi = 3.14159265358979323846f;

// The room spans x ∈ [−1, 1], y ∈ [0, 2], z ∈ [kBackZ, kFrontZ]; the camera stands
// inside it near the front wall, so the room is closed and every ray hits something.
constexpr float kBackZ = -1.0f;
constexpr float kFrontZ = 2.6f;
constexpr float kLightY = 1.98f; // just below the ceiling, so the light is not coplanar with it
const Vec3 kWhite{0.73f, 0.73f, 0.73f};
const Vec3 kRed{0.63f, 0.065f, 0.05f};
const Vec3 kGreen{0.14f, 0.45f, 0.091f};
const Vec3 kLightEmission{22.0f, 18.0f, 12.5f};
const Vec3 kFillEmission = kLightEmission * 0.12f;
// sweep's and cross's key light: a 5 cm cube, about as bright in total as the ceiling light.
constexpr float kKeyLightEdge = 0.05f;
const Vec3 kKeyLightEmission{190.0f, 165.0f, 120.0f};
const Vec3 kCrossKeyLight{-0.7f, 1.0f, 1.4f};

Mesh make_wall(const std::string& name, Vec3 albedo, Vec3 emission, Vec3 p0, Vec3 p1, Vec3 p2, Vec3 p3)
{
    Mesh wall;
    wall.name = name;
    wall.material.albedo = albedo;
    wall.material.emission = emission;
    add_quad(wall, p0, p1, p2, p3);
    return wall;
}

// The six inward-facing walls. `emission` is for the furnace; lit rooms pass zero.
void add_room(Scene& scene, Vec3 floor_ceiling_back_front, Vec3 left, Vec3 right, Vec3 emission)
{
    const float b = kBackZ, f = kFrontZ;
    const Vec3 white = floor_ceiling_back_front;
    scene.meshes.push_back(make_wall("floor", white, emission, {-1, 0, f}, {1, 0, f}, {1, 0, b}, {-1, 0, b}));
    scene.meshes.push_back(
        make_wall("ceiling", white, emission, {-1, 2, b}, {1, 2, b}, {1, 2, f}, {-1, 2, f}));
    scene.meshes.push_back(make_wall("back", white, emission, {-1, 0, b}, {1, 0, b}, {1, 2, b}, {-1, 2, b}));
    scene.meshes.push_back(make_wall("front", white, emission, {1, 0, f}, {-1, 0, f}, {-1, 2, f}, {1, 2, f}));
    scene.meshes.push_back(make_wall("left", left, emission, {-1, 0, f}, {-1, 0, b}, {-1, 2, b}, {-1, 2, f}));
    scene.meshes.push_back(make_wall("right", right, emission, {1, 0, b}, {1, 0, f}, {1, 2, f}, {1, 2, b}));
}

Scene make_lit_room()
{
    Scene scene;
    scene.camera.position = {0, 1.05f, 2.5f};
    scene.camera.look_at = {0, 0.8f, 0};
    scene.camera.up = {0, 1, 0};
    scene.camera.vertical_fov_degrees = 48;
    add_room(scene, kWhite, kRed, kGreen, {});
    return scene;
}

Material white_material()
{
    Material material;
    material.albedo = kWhite;
    return material;
}

Scene make_static(int)
{
    Scene scene = make_lit_room();
    scene.meshes.push_back(
        make_box("tall box", {-0.38f, 0, -0.35f}, {0.55f, 1.2f, 0.55f}, 0.3f, white_material()));
    scene.meshes.push_back(
        make_box("short box", {0.4f, 0, 0.2f}, {0.55f, 0.55f, 0.55f}, -0.3f, white_material()));
    scene.meshes.push_back(make_ceiling_light("light", {0, kLightY, 0}, 0.5f, 0.5f, kLightEmission));
    return scene;
}

Scene make_orbit(int frame)
{
    Scene scene = make_lit_room();
    scene.meshes.push_back(
        make_box("tall box", {-0.38f, 0, -0.35f}, {0.55f, 1.2f, 0.55f}, 0.3f, white_material()));
    scene.meshes.push_back(
        make_box("short box", {0.4f, 0, 0.2f}, {0.55f, 0.55f, 0.55f}, -0.3f, white_material()));
    // One full turn over the shot, radius 0.55 m about the room's centre.
    float angle =
        2 * kPi * static_cast<float>(frame - kFirstFrame) / static_cast<float>(kLastFrame - kFirstFrame + 1);
    Vec3 center{0.55f * std::cos(angle), kLightY, 0.1f + 0.55f * std::sin(angle)};
    scene.meshes.push_back(make_ceiling_light("light", center, 0.45f, 0.45f, kLightEmission));
    return scene;
}

Scene make_switch(int frame)
{
    Scene scene = make_lit_room();
    scene.meshes.push_back(
        make_box("tall box", {-0.45f, 0, -0.5f}, {0.5f, 1.2f, 0.5f}, 0.35f, white_material()));
    scene.meshes.push_back(
        make_box("short box", {0.5f, 0, -0.35f}, {0.5f, 0.5f, 0.5f}, -0.3f, white_material()));
    Vec3 center = frame < kSwitchLightJumpFrame ? Vec3{-0.45f, kLightY, 0.1f} : Vec3{0.45f, kLightY, 0.5f};
    scene.meshes.push_back(make_ceiling_light("light", center, 0.5f, 0.5f, kLightEmission));
    if (frame >= kSwitchCrossingFirstFrame && frame <= kSwitchCrossingLastFrame) {
        // Left to right across the open floor in front of the boxes, one step per frame.
        float t = static_cast<float>(frame - kSwitchCrossingFirstFrame) /
                  static_cast<float>(kSwitchCrossingLastFrame - kSwitchCrossingFirstFrame);
        Material blue;
        blue.albedo = {0.15f, 0.25f, 0.7f};
        scene.meshes.push_back(
            make_box("crossing box", {-0.7f + 1.4f * t, 0, 0.45f}, {0.28f, 0.28f, 0.28f}, 2.0f * t, blue));
    }
    return scene;
}

Scene make_spin(int frame)
{
    Scene scene = make_lit_room();
    // Half a turn over the shot; the box is not square so its shadow changes shape.
    float angle =
        kPi * static_cast<float>(frame - kFirstFrame) / static_cast<float>(kLastFrame - kFirstFrame + 1);
    scene.meshes.push_back(
        make_box("spinning box", {0, 0, -0.2f}, {0.9f, 0.8f, 0.3f}, angle, white_material()));
    scene.meshes.push_back(make_ceiling_light("light", {0.35f, kLightY, 0.35f}, 0.4f, 0.4f, kLightEmission));
    return scene;
}

// The camera walks in through the front of the room, past the short box and
// round towards the back left, while the light's colour and strength change and
// the short box turns: every pixel sees different surfaces from frame to frame.
Scene make_flythrough(int frame)
{
    Scene scene = make_lit_room();
    float t = static_cast<float>(frame - kFirstFrame) / static_cast<float>(kLastFrame - kFirstFrame);
    float ease = t * t * (3 - 2 * t);
    auto mix = [ease](Vec3 a, Vec3 b) { return a * (1 - ease) + b * ease; };
    scene.camera.position = mix({0.6f, 1.35f, 2.45f}, {-0.55f, 0.9f, 0.95f});
    scene.camera.look_at = mix({-0.25f, 0.55f, -0.6f}, {0.5f, 0.45f, -0.55f});
    scene.camera.vertical_fov_degrees = 55;
    scene.meshes.push_back(
        make_box("tall box", {-0.38f, 0, -0.35f}, {0.55f, 1.2f, 0.55f}, 0.3f, white_material()));
    scene.meshes.push_back(make_box("short box", {0.4f, 0, 0.2f}, {0.55f, 0.55f, 0.55f}, -0.3f + 0.8f * t,
                                    white_material()));
    // Warm and dim to cool and bright and back, one and a half cycles over the shot.
    float swing = 0.5f - 0.5f * std::cos(3 * kPi * t);
    Vec3 warm{20.0f, 13.0f, 7.0f}, cool{16.0f, 20.0f, 26.0f};
    scene.meshes.push_back(make_ceiling_light("light", {0, kLightY, 0.2f}, 0.5f, 0.5f,
                                              warm * (1 - swing) + cool * swing));
    return scene;
}

// A small cube that emits from all six faces: a near-point key light whose shadows
// stay hard (penumbra ≈ edge × distance behind the occluder / distance to it).
Mesh make_cube_light(const std::string& name, Vec3 center, float edge, Vec3 emission)
{
    Material material;
    material.albedo = {0.78f, 0.78f, 0.78f};
    material.emission = emission;
    return make_box(name, {center.x, center.y - 0.5f * edge, center.z}, {edge, edge, edge}, 0, material);
}

// A dim ceiling quad so that every surface the key light misses still gets some light.
Mesh make_fill_light()
{
    return make_ceiling_light("fill light", {0, kLightY, 0.2f}, 0.5f, 0.5f, kFillEmission);
}

// A small hard key light circles the room once, low (30 cm above the floor), round two
// boxes: their long shadows sweep across the floor and all four walls, ~7.5° per frame.
Scene make_sweep(int frame)
{
    Scene scene = make_lit_room();
    scene.meshes.push_back(
        make_box("tall box", {-0.25f, 0, -0.15f}, {0.4f, 1.0f, 0.4f}, 0.3f, white_material()));
    scene.meshes.push_back(
        make_box("short box", {0.3f, 0, 0.25f}, {0.35f, 0.35f, 0.35f}, -0.3f, white_material()));
    // Radius 0.8 m about (0, 0.05): clear of both boxes (≤ 0.67 m from the centre) and of the walls.
    float angle =
        2 * kPi * static_cast<float>(frame - kFirstFrame) / static_cast<float>(kLastFrame - kFirstFrame + 1);
    Vec3 center{0.8f * std::sin(angle), 0.3f, 0.05f + 0.8f * std::cos(angle)};
    scene.meshes.push_back(make_cube_light("key light", center, kKeyLightEdge, kKeyLightEmission));
    scene.meshes.push_back(make_fill_light());
    return scene;
}

// Fixed lighting; a small box flies across the room, left to right, in frames
// kCrossFirstFrame..kCrossLastFrame only, a little more than its own width per frame.
Scene make_cross(int frame)
{
    Scene scene = make_lit_room();
    scene.meshes.push_back(
        make_box("tall box", {-0.38f, 0, -0.35f}, {0.55f, 1.2f, 0.55f}, 0.3f, white_material()));
    scene.meshes.push_back(
        make_box("short box", {0.4f, 0, 0.2f}, {0.55f, 0.55f, 0.55f}, -0.3f, white_material()));
    scene.meshes.push_back(make_cube_light("key light", kCrossKeyLight, kKeyLightEdge, kKeyLightEmission));
    scene.meshes.push_back(make_fill_light());
    if (frame >= kCrossFirstFrame && frame <= kCrossLastFrame) {
        float t = static_cast<float>(frame - kCrossFirstFrame) /
                  static_cast<float>(kCrossLastFrame - kCrossFirstFrame);
        Material yellow;
        yellow.albedo = {0.7f, 0.55f, 0.1f};
        scene.meshes.push_back(
            make_box("crossing box", {-0.8f + 1.6f * t, 0.3f, 0.75f}, {0.2f, 0.2f, 0.2f}, 1.5f * t, yellow));
    }
    return scene;
}

std::string scene_names()
{
    std::string names;
    for (const SceneInfo& info : builtin_scenes())
        names += (names.empty() ? "" : ", ") + info.name;
    return names;
}

} // namespace

const std::vector<SceneInfo>& builtin_scenes()
{
    static const std::vector<SceneInfo> scenes = {
        {"static", "nothing moves: two boxes under a ceiling light", kFirstFrame, kLastFrame, {}},
        {"orbit", "the ceiling light circles the room once during the shot", kFirstFrame, kLastFrame, {}},
        {"switch",
         "the light jumps to another place at frame 25; a small blue box crosses the floor in frames 30-36 "
         "only",
         kFirstFrame,
         kLastFrame,
         {kSwitchCrossingFirstFrame, kSwitchCrossingLastFrame}},
        {"spin",
         "a flat box turns half a turn under a fixed light; its shadow sweeps the floor",
         kFirstFrame,
         kLastFrame,
         {}},
        {"flythrough",
         "the camera moves through the room while the light changes colour and strength and the short box "
         "turns (object-space denoising)",
         kFirstFrame,
         kLastFrame,
         {}},
        {"sweep",
         "a small low key light circles the room once: the boxes' hard shadows sweep floor and walls every "
         "frame (dim ceiling fill)",
         kFirstFrame,
         kLastFrame,
         {}},
        {"cross",
         "fixed small key light; a small yellow box flies across the room in frames 20-27 only, its hard "
         "shadow with it",
         kFirstFrame,
         kLastFrame,
         {kCrossFirstFrame, kCrossLastFrame}},
    };
    return scenes;
}

Scene make_builtin_scene(const std::string& name, int frame)
{
    const SceneInfo* info = nullptr;
    for (const SceneInfo& candidate : builtin_scenes())
        if (candidate.name == name)
            info = &candidate;
    if (info == nullptr)
        throw usage_error("unknown scene '" + name + "' (available: " + scene_names() + ")");
    if (frame < info->first_frame || frame > info->last_frame)
        throw usage_error("frame " + std::to_string(frame) + " is outside scene '" + name + "' (frames " +
                          std::to_string(info->first_frame) + "-" + std::to_string(info->last_frame) + ")");
    if (name == "static")
        return make_static(frame);
    if (name == "orbit")
        return make_orbit(frame);
    if (name == "switch")
        return make_switch(frame);
    if (name == "flythrough")
        return make_flythrough(frame);
    if (name == "sweep")
        return make_sweep(frame);
    if (name == "cross")
        return make_cross(frame);
    return make_spin(frame);
}

Scene make_furnace_scene(float albedo, float emission)
{
    if (!(albedo >= 0 && albedo < 1) || !(emission >= 0))
        throw usage_error("furnace scene needs 0 <= albedo < 1 and emission >= 0");
    Scene scene;
    scene.camera.position = {0, 1, 2.2f};
    scene.camera.look_at = {0, 0.8f, 0};
    scene.camera.vertical_fov_degrees = 60;
    Vec3 a{albedo, albedo, albedo}, e{emission, emission, emission};
    add_room(scene, a, a, a, e);
    Material material;
    material.albedo = a;
    material.emission = e;
    scene.meshes.push_back(make_box("box", {0.2f, 0, -0.2f}, {0.6f, 0.8f, 0.6f}, 0.4f, material));
    return scene;
}

} // namespace modestack::scene
