// The built-in animated scenes of `modestack render --scene NAME`: small closed
// Cornell-style rooms (white floor, ceiling, back and front walls, red left wall,
// green right wall, boxes, a ceiling quad light; sweep and cross: a small cube key
// light with hard shadows and a dim ceiling fill) whose animation is a closed-form
// function of the frame number, so any frame can be rebuilt exactly and on its own
// (the refine step re-renders single frames). Also the white-furnace room the
// tests use to check the tracer's radiometry.
#pragma once

#include "core/scene/scene.h"

#include <string>
#include <vector>

namespace modestack::scene {

/// Frames first to last (inclusive) of a shot; empty when first > last.
struct FrameSpan {
    int first = 0;
    int last = -1;
    bool empty() const { return first > last; }
    bool contains(int frame) const { return frame >= first && frame <= last; }
};

/// One line of `modestack render --scene list`.
struct SceneInfo {
    std::string name;        ///< what --scene takes
    std::string description; ///< one line: what moves, and when
    int first_frame;         ///< first frame of the shot (inclusive)
    int last_frame;          ///< last frame of the shot (inclusive)
    /// A brief event worth a closer look (switch: the box crossing the floor, where
    /// the denoiser fails); `modestack run` shows its middle frame on the contact
    /// sheet and measures these frames on their own. Empty for most scenes.
    FrameSpan highlight_frames;
};

/// The built-in scenes, in the order they are listed: static, orbit, switch, spin, flythrough,
/// sweep, cross.
const std::vector<SceneInfo>& builtin_scenes();

/// Builds frame `frame` of the built-in scene `name`.
/// Throws a usage error naming the available scenes when `name` is unknown, and one
/// giving the scene's frame range when `frame` lies outside it.
Scene make_builtin_scene(const std::string& name, int frame);

/// The `switch` scene's small box crosses the floor in these frames only (inclusive).
inline constexpr int kSwitchCrossingFirstFrame = 30;
inline constexpr int kSwitchCrossingLastFrame = 36;
/// The `switch` scene's light is in its second place from this frame on.
inline constexpr int kSwitchLightJumpFrame = 25;
/// The `cross` scene's small box exists in these frames only (inclusive).
inline constexpr int kCrossFirstFrame = 20;
inline constexpr int kCrossLastFrame = 27;

/// A closed room (with a box in it) where every surface has albedo `albedo` and
/// emits `emission` towards the room: the radiance everywhere is
/// emission / (1 − albedo) (the white-furnace test). 0 ≤ albedo < 1.
Scene make_furnace_scene(float albedo, float emission);

} // namespace modestack::scene
