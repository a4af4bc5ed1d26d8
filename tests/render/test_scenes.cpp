// The built-in animated scenes: names and frame ranges, exact per-frame
// animation, finite renders of every scene, and the switch scene's crossing box
// present in its frames only (sweep's and cross's own properties:
// test_transient_scenes.cpp).
#include "core/common/error.h"
#include "core/render/render.h"
#include "core/scene/builtin_scenes.h"

#include <doctest/doctest.h>

#include <cmath>
#include <cstring>
#include <string>

using namespace modestack;

namespace {

bool same_geometry(const scene::Scene& a, const scene::Scene& b)
{
    if (a.meshes.size() != b.meshes.size())
        return false;
    for (std::size_t m = 0; m < a.meshes.size(); ++m) {
        const auto& pa = a.meshes[m].positions;
        const auto& pb = b.meshes[m].positions;
        if (pa.size() != pb.size() || std::memcmp(pa.data(), pb.data(), pa.size() * sizeof(scene::Vec3)) != 0)
            return false;
    }
    return true;
}

ErrorKind kind_of_scene_error(const std::string& name, int frame)
{
    try {
        scene::make_builtin_scene(name, frame);
    } catch (const Error& error) {
        return error.kind();
    }
    return ErrorKind::Internal;
}

} // namespace

TEST_CASE("scenes: the seven built-in scenes have 48 frames each")
{
    const auto& scenes = scene::builtin_scenes();
    REQUIRE(scenes.size() == 7);
    CHECK(scenes[0].name == "static");
    CHECK(scenes[1].name == "orbit");
    CHECK(scenes[2].name == "switch");
    CHECK(scenes[3].name == "spin");
    CHECK(scenes[4].name == "flythrough");
    CHECK(scenes[5].name == "sweep");
    CHECK(scenes[6].name == "cross");
    for (const auto& info : scenes) {
        CHECK(info.first_frame == 1);
        CHECK(info.last_frame == 48);
        CHECK(!info.description.empty());
    }
}

TEST_CASE("scenes: unknown names and frames out of range are usage errors")
{
    CHECK(kind_of_scene_error("nope", 1) == ErrorKind::Usage);
    CHECK(kind_of_scene_error("static", 0) == ErrorKind::Usage);
    CHECK(kind_of_scene_error("orbit", 49) == ErrorKind::Usage);
    try {
        scene::make_builtin_scene("nope", 1);
    } catch (const Error& error) {
        std::string message = error.what();
        CHECK(message.find("static, orbit, switch, spin, flythrough, sweep, cross") != std::string::npos);
        CHECK(message.find('\n') == std::string::npos);
    }
    CHECK_THROWS_AS(scene::make_furnace_scene(1.0f, 0.5f), Error);
}

TEST_CASE("scenes: animation is exact per frame and moves where it should")
{
    for (const auto& info : scene::builtin_scenes())
        for (int frame : {1, 17, 48})
            CHECK(same_geometry(scene::make_builtin_scene(info.name, frame),
                                scene::make_builtin_scene(info.name, frame)));
    CHECK(same_geometry(scene::make_builtin_scene("static", 1), scene::make_builtin_scene("static", 48)));
    for (const char* moving : {"orbit", "spin", "sweep"})
        for (int frame = 1; frame < 48; ++frame)
            CHECK(!same_geometry(scene::make_builtin_scene(moving, frame),
                                 scene::make_builtin_scene(moving, frame + 1)));
    // switch: one light jump between 24 and 25, otherwise only the crossing box moves.
    for (int frame = 1; frame < 48; ++frame) {
        bool expect_change =
            frame + 1 == scene::kSwitchLightJumpFrame ||
            (frame + 1 >= scene::kSwitchCrossingFirstFrame && frame <= scene::kSwitchCrossingLastFrame);
        CHECK(expect_change != same_geometry(scene::make_builtin_scene("switch", frame),
                                             scene::make_builtin_scene("switch", frame + 1)));
    }
    // cross: only the flying box moves, and it exists in frames 20-27 only.
    for (int frame = 1; frame < 48; ++frame) {
        bool expect_change = frame + 1 >= scene::kCrossFirstFrame && frame <= scene::kCrossLastFrame;
        CHECK(expect_change != same_geometry(scene::make_builtin_scene("cross", frame),
                                             scene::make_builtin_scene("cross", frame + 1)));
    }
}

TEST_CASE("scenes: every built-in scene renders finite and lit images")
{
    render::RenderOptions options;
    options.width = 32;
    options.height = 24;
    options.spp = 2;
    for (const auto& info : scene::builtin_scenes())
        for (int frame : {info.first_frame, 24, info.last_frame}) {
            render::FrameAovs aovs;
            render::render_frame(scene::make_builtin_scene(info.name, frame), frame, options, nullptr, aovs,
                                 Progress::silent());
            bool finite = true;
            double sum = 0;
            for (const render::AovLayer& layer : render::aov_layers(aovs))
                for (float value : layer.image->pixels)
                    finite = finite && std::isfinite(value);
            for (float value : aovs.beauty.pixels)
                sum += value;
            CHECK_MESSAGE(finite, info.name << " frame " << frame);
            CHECK_MESSAGE(sum > 0.05 * aovs.beauty.pixels.size(), info.name << " frame " << frame);
            CHECK(aovs.beauty.pixels[3] == 1.0f); // closed rooms: every sample hits
        }
}

TEST_CASE("scenes: switch's crossing box shows in the albedo AOV in frames 30-36 only")
{
    // With a fixed seed the pixel jitter is the same every frame, so the albedo AOV
    // changes only where geometry does (the light's jump does not change albedo).
    render::RenderOptions options;
    options.width = 32;
    options.height = 24;
    options.spp = 1;
    options.max_depth = 1;
    options.fixed_seed = true;
    render::FrameAovs before;
    render::render_frame(scene::make_builtin_scene("switch", 25), 25, options, nullptr, before,
                         Progress::silent());
    for (int frame = 1; frame <= 48; ++frame) {
        render::FrameAovs aovs;
        render::render_frame(scene::make_builtin_scene("switch", frame), frame, options, nullptr, aovs,
                             Progress::silent());
        int changed = 0;
        for (std::size_t i = 0; i < aovs.albedo.pixels.size(); ++i)
            changed += aovs.albedo.pixels[i] != before.albedo.pixels[i];
        bool crossing = frame >= scene::kSwitchCrossingFirstFrame && frame <= scene::kSwitchCrossingLastFrame;
        CHECK_MESSAGE(crossing == (changed > 0),
                      "frame " << frame << ": " << changed << " albedo values changed");
    }
}

TEST_CASE("scenes: flythrough moves the camera and changes the light, with the same meshes in every frame")
{
    scene::Scene first = scene::make_builtin_scene("flythrough", 1);
    scene::Scene last = scene::make_builtin_scene("flythrough", 48);
    CHECK(scene::length(first.camera.position - last.camera.position) > 1.0f);
    REQUIRE(first.meshes.size() == last.meshes.size());
    for (size_t m = 0; m < first.meshes.size(); ++m)
        CHECK(first.meshes[m].triangle_count() == last.meshes[m].triangle_count());
    // The light is warm (red > blue) at the start and cool (blue > red) a third in.
    scene::Vec3 warm = first.meshes.back().material.emission;
    scene::Vec3 cool = scene::make_builtin_scene("flythrough", 17).meshes.back().material.emission;
    CHECK(warm.x > warm.z);
    CHECK(cool.z > cool.x);
}
