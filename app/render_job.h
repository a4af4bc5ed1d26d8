// `modestack render` as a library call: the options as typed
// (RenderCommandOptions), the one validation step that turns them into a
// checked RenderJob, render() that renders the frames and writes the EXRs, and
// the RenderResult it returns, which render_json() writes as the --json summary.
// `modestack run` fills the options and calls the same functions.
#pragma once

#include "app/run_context.h"
#include "app/scene_source.h"
#include "core/render/aov.h"
#include "core/render/render.h"
#include "io/sequence.h"

#include <nlohmann/json.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace modestack::app {

/// --point-count at most: PointLookup stores ids in float channels, exact below 2^24.
inline constexpr std::int64_t kMaxSurfacePoints = std::int64_t{1} << 24;

/// The options of `render` as typed.
struct RenderCommandOptions {
    std::string scene = "orbit";
    std::string output;
    std::string frames;
    std::string size = "320x240";
    std::string mask;
    std::string points;            ///< --points: bake sequence for object space
    std::int64_t point_count = 0;  ///< --point-count: 0 = width × height
    double fps = 0;                ///< glTF scenes: 0 = the file's or 24
    bool skip_existing = false;
    render::RenderOptions render;
};

/// A render checked before any work: the scene opened, the frames in it, the
/// output patterns valid.
struct RenderJob {
    explicit RenderJob(SceneSource scene_source) : scene(std::move(scene_source)) {}
    SceneSource scene;
    std::string scene_name;           ///< as given to --scene
    std::vector<int> frames;
    io::FrameSequence output;
    std::string mask;                 ///< mask sequence ("" = every pixel)
    io::FrameSequence points_output;  ///< object-space bake (no files = none)
    std::int64_t point_count = 0;     ///< 0 = width × height
    bool skip_existing = false;
    render::RenderOptions render;
};

/// One rendered frame's statistics.
struct RenderedFrame {
    int frame = 0;
    render::RenderStats stats;
};

/// What a render did: everything its --json summary holds.
struct RenderResult {
    bool nothing_to_do = false;  ///< --skip-existing found every output
    std::string scene;
    bool gltf = false;
    double fps = 0;
    std::string output;          ///< printf pattern
    bool has_points = false;
    std::string points_output;   ///< printf pattern
    std::int64_t point_count = 0;
    double point_spacing = 0;
    std::vector<int> frames;
    std::vector<int> skipped;    ///< --skip-existing
    render::RenderOptions render;
    double render_seconds = 0;
    long long paths = 0;
    long long rays = 0;
    std::vector<RenderedFrame> per_frame;
};

/// The validation step of `render`: usage errors for a missing -o, a bad size,
/// spp or depth, an unknown scene, frames outside it, --point-count without --points.
RenderJob make_render_job(const RenderCommandOptions& options);

/// Renders the frames of `job` and writes them (and the point bake).
RenderResult render(const RenderJob& job, const CommonOptions& context);

/// The --json summary of a render.
nlohmann::ordered_json render_json(const RenderResult& result);

/// Prints the built-in scenes (`render --scene list`).
void list_scenes();

}  // namespace modestack::app
