// The two built-in scenes made to break a temporal model (issue 29): in `sweep` the
// key light's hard shadows move across the floor from frame to frame (unlike
// `static`), and in `cross` a small box and its shadow exist in frames 20-27 only.
#include "core/render/render.h"
#include "core/scene/builtin_scenes.h"

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

using namespace modestack;

namespace {

render::FrameAovs render_scene_frame(const std::string& name, int frame, const render::RenderOptions& options)
{
    render::FrameAovs aovs;
    render::render_frame(scene::make_builtin_scene(name, frame), frame, options, nullptr, aovs,
                         Progress::silent());
    return aovs;
}

// Pixels whose every sample hit the floor (y = 0, normal up).
bool on_floor(const render::FrameAovs& aovs, int x, int y)
{
    return aovs.position.at(x, y)[1] < 1e-4f && aovs.normal.at(x, y)[1] > 0.999f;
}

float luminance(const float* rgb)
{
    return 0.2126f * rgb[0] + 0.7152f * rgb[1] + 0.0722f * rgb[2];
}

// Share of the floor pixels (of both frames) whose direct light changes by more
// than a factor 2 from frame `a` to frame `b`.
double floor_share_changed(const std::string& name, int a, int b, const render::RenderOptions& options)
{
    render::FrameAovs first = render_scene_frame(name, a, options);
    render::FrameAovs second = render_scene_frame(name, b, options);
    int floor = 0, changed = 0;
    for (int y = 0; y < options.height; ++y)
        for (int x = 0; x < options.width; ++x) {
            if (!on_floor(first, x, y) || !on_floor(second, x, y))
                continue;
            float before = luminance(first.diffuse_direct.at(x, y));
            float after = luminance(second.diffuse_direct.at(x, y));
            ++floor;
            changed += std::max(before, after) > 2 * std::min(before, after);
        }
    REQUIRE(floor > options.width * options.height / 20);
    return static_cast<double>(changed) / floor;
}

bool same_pixels(const render::AovImage& a, const render::AovImage& b)
{
    return a.pixels == b.pixels;
}

} // namespace

TEST_CASE("transient scenes: sweep's hard shadows move across the floor, static's do not")
{
    // Direct light only, with independent noise in each frame (the animated seed):
    // 16 spp keeps the noise well under the factor 2 counted as a change.
    render::RenderOptions options;
    options.width = 40;
    options.height = 30;
    options.spp = 16;
    options.max_depth = 1;
    // Frames 1 and 7 are an eighth of a turn apart, 1 and 25 half a turn.
    double sweep_eighth = floor_share_changed("sweep", 1, 7, options);
    double sweep_half = floor_share_changed("sweep", 1, 25, options);
    double still = floor_share_changed("static", 1, 7, options);
    INFO("floor pixels changing by more than 2x: sweep 1->7 " << sweep_eighth << ", sweep 1->25 "
                                                              << sweep_half << ", static 1->7 " << still);
    CHECK(sweep_eighth > 0.4);
    CHECK(sweep_half > 0.6);
    CHECK(still < 0.1); // noise in the ceiling light's soft penumbrae
}

TEST_CASE("transient scenes: cross changes the image in its crossing frames only, and its box casts a shadow")
{
    // With a fixed seed every frame uses the same random numbers, so a frame differs
    // from frame 1 exactly where its geometry does: only frames 20-27, which hold the box.
    render::RenderOptions options;
    options.width = 40;
    options.height = 30;
    options.spp = 4;
    options.max_depth = 3;
    options.fixed_seed = true;
    const scene::SceneInfo& info = scene::builtin_scenes().back();
    REQUIRE(info.name == "cross");
    CHECK(info.highlight_frames.first == scene::kCrossFirstFrame);
    CHECK(info.highlight_frames.last == scene::kCrossLastFrame);
    CHECK(scene::kCrossLastFrame - scene::kCrossFirstFrame + 1 == 8);
    render::FrameAovs empty_room = render_scene_frame("cross", 1, options);
    int shadowed_frames = 0;
    for (int frame = 2; frame <= 48; ++frame) {
        render::FrameAovs aovs = render_scene_frame("cross", frame, options);
        bool crossing = info.highlight_frames.contains(frame);
        std::vector<render::AovLayer> layers = render::aov_layers(aovs);
        std::vector<render::AovLayer> empty_layers = render::aov_layers(empty_room);
        REQUIRE(layers.size() == empty_layers.size());
        bool identical = true;
        for (std::size_t l = 0; l < layers.size(); ++l)
            identical = identical && same_pixels(*layers[l].image, *empty_layers[l].image);
        CHECK_MESSAGE(identical != crossing, "frame " << frame);
        // The shadow: pixels where the box itself is not seen (same albedo as the empty
        // room) but the direct light falls below half.
        int shadow = 0;
        for (int y = 0; y < options.height; ++y)
            for (int x = 0; x < options.width; ++x) {
                bool same_surface =
                    std::equal(aovs.albedo.at(x, y), aovs.albedo.at(x, y) + 3, empty_room.albedo.at(x, y));
                shadow += same_surface && luminance(aovs.diffuse_direct.at(x, y)) <
                                              0.5f * luminance(empty_room.diffuse_direct.at(x, y));
            }
        if (crossing && shadow >= 3)
            ++shadowed_frames;
    }
    CHECK_MESSAGE(shadowed_frames >= 6, shadowed_frames << " of the 8 crossing frames have a shadow");
}
