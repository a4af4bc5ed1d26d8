// `modestack render --scene NAME|FILE.gltf -o SEQ`: the companion path tracer.
// Renders the frames of a built-in animated scene or of a glTF 2.0 file at any spp (with a fresh seed per frame,
// or --fixed-seed), optionally only the pixels of a mask sequence, and writes
// one multi-layer EXR per frame with Cycles-style AOV names and provenance.
#include "app/command.h"
#include "app/option_values.h"
#include "app/run_context.h"
#include "app/scene_source.h"
#include "core/common/error.h"
#include "core/render/point_bake.h"
#include "core/render/render.h"
#include "core/render/surface_points.h"
#include "core/scene/builtin_scenes.h"
#include "io/frame_output.h"
#include "io/mask_image.h"
#include "io/sequence.h"
#include "io/text_output.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <chrono>
#include <filesystem>
#include <limits>
#include <optional>
#include <cstdio>

namespace modestack::app {
namespace {

// A whole number of at least 1; CLI::PositiveNumber would print "not in range 0
// to" the largest double, in full.
const CLI::Range kAtLeastOne(1, std::numeric_limits<int>::max(), "at least 1");
// PointLookup stores ids in float channels: exact below 2^24.
constexpr std::int64_t kMaxSurfacePoints = std::int64_t{1} << 24;

struct RenderCommandOptions {
    std::string scene = "orbit";
    std::string output;
    std::string frames;
    std::string size = "320x240";
    std::string mask;
    std::string json_path;
    std::string points;               ///< --points: bake sequence for object space
    std::int64_t point_count = 0;     ///< --point-count: 0 = width × height
    double fps = 0; ///< glTF scenes: 0 = the file's or 24
    bool skip_existing = false;
    render::RenderOptions render;
    CommonOptions common;
};

// Channel types written: colour layers in half as renderers write beauty passes;
// geometry and the variance in float, where half's precision would hurt.
const char* channel_type_for(const std::string& layer)
{
    return layer == "Depth" || layer == "Normal" || layer == "Position" || layer == "DiffIndVar" ||
                   layer == "PointLookup"
               ? "float"
               : "half";
}

std::vector<io::HeaderAttribute> provenance(const render::RenderOptions& render, const RenderCommandOptions& options,
                                            const SceneSource& source, int frame, double seconds)
{
    std::vector<io::HeaderAttribute> attributes{
        io::HeaderAttribute::of_text("modestack:version", MODESTACK_VERSION),
        io::HeaderAttribute::of_text("modestack:command", command_line()),
        io::HeaderAttribute::of_text("modestack:scene", options.scene),
        io::HeaderAttribute::of_integer("modestack:frame", frame),
        io::HeaderAttribute::of_integer("modestack:spp", render.spp),
        io::HeaderAttribute::of_integer("modestack:seed", static_cast<long long>(render.seed)),
        io::HeaderAttribute::of_integer("modestack:fixed_seed", render.fixed_seed ? 1 : 0),
        io::HeaderAttribute::of_integer("modestack:max_depth", render.max_depth),
        io::HeaderAttribute::of_real("modestack:render_seconds", seconds),
        io::HeaderAttribute::of_text("modestack:mask", options.mask),
    };
    if (source.is_gltf())
        attributes.push_back(io::HeaderAttribute::of_real("modestack:fps", source.fps()));
    return attributes;
}

// Writes `layers` (all width × height) as one EXR; in float only if `all_float`.
void write_layers(const std::string& path, const std::vector<render::AovLayer>& layers,
                  std::vector<io::HeaderAttribute> attributes, bool all_float = false)
{
    io::NewImageDescription image;
    image.width = layers.front().image->width;
    image.height = layers.front().image->height;
    for (const auto& layer : layers)
        for (const auto& channel : layer.channel_names) {
            image.channel_names.push_back(layer.name + "." + channel);
            image.channel_types.push_back(all_float ? "float" : channel_type_for(layer.name));
        }
    size_t pixels = static_cast<size_t>(image.width) * image.height, channels = image.channel_names.size();
    std::vector<float> interleaved(pixels * channels);
    size_t first = 0;
    for (const auto& layer : layers) {
        int count = layer.image->channels;
        for (size_t p = 0; p < pixels; ++p)
            for (int c = 0; c < count; ++c)
                interleaved[p * channels + first + c] = layer.image->pixels[p * count + c];
        first += count;
    }
    io::FrameOutput output(path, image, attributes);
    output.write_float_rows(0, image.height, interleaved.data());
    output.commit();
}

// A point image: the baked light and where each point is this frame, all float
// (the denoiser's input; half would round the light it works on).
void write_points(const std::string& path, const render::PointBake& bake, const render::SurfacePoints& points,
                  const RenderCommandOptions& options, const SceneSource& source, int frame)
{
    const std::vector<std::string> rgb{"R", "G", "B"};
    std::vector<render::AovLayer> layers{{"DiffInd", rgb, &bake.indirect},
                                         {"DiffIndVar", rgb, &bake.variance},
                                         {"Position", {"X", "Y", "Z"}, &bake.position},
                                         {"Normal", {"X", "Y", "Z"}, &bake.normal}};
    std::vector<io::HeaderAttribute> attributes =
        provenance(options.render, options, source, frame, bake.stats.seconds);
    attributes.push_back(io::HeaderAttribute::of_integer("modestack:points", points.count()));
    attributes.push_back(io::HeaderAttribute::of_real("modestack:point_spacing", points.spacing()));
    write_layers(path, layers, std::move(attributes), true);
}

void write_frame(const std::string& path, const render::FrameAovs& aovs, const RenderCommandOptions& options,
                 const SceneSource& source, int frame)
{
    write_layers(path, render::aov_layers(aovs), provenance(options.render, options, source, frame, aovs.stats.seconds));
}

int list_scenes()
{
    for (const auto& info : scene::builtin_scenes())
        std::printf("%-8s frames %d-%d  %s\n", info.name.c_str(), info.first_frame, info.last_frame,
                    info.description.c_str());
    return 0;
}

int run_render(RenderCommandOptions& options)
{
    if (options.scene == "list")
        return list_scenes();
    if (options.output.empty())
        throw usage_error("render needs -o SEQ (e.g. -o noisy/shot.####.exr)");
    parse_image_size(options.size, options.render.width, options.render.height);
    render::validate_render_options(options.render);
    SceneSource source(options.scene, options.fps);
    std::vector<int> frames = options.frames.empty()
                                  ? io::parse_frame_range(fmt::format("{}-{}", source.first_frame(), source.last_frame()))
                                  : io::parse_frame_range(options.frames);
    for (int frame : frames)
        if (frame < source.first_frame() || frame > source.last_frame())
            throw usage_error(fmt::format("--frames: scene '{}' has frames {}-{}, not {}", options.scene,
                                          source.first_frame(), source.last_frame(), frame));
    io::FrameSequence output = io::output_sequence(options.output, frames);
    std::vector<std::string> mask_files;
    if (!options.mask.empty()) {
        mask_files = io::find_input_sequence(options.mask, io::describe_frames(frames)).files;
        for (const std::string& file : mask_files)  // check every mask before the first frame
            io::read_mask(file, options.render.width, options.render.height);
    }
    io::FrameSequence points_output;
    if (!options.points.empty()) {
        points_output = io::output_sequence(options.points, frames);
        std::vector<std::string> all = output.files;
        all.insert(all.end(), points_output.files.begin(), points_output.files.end());
        io::check_outputs(all, mask_files);
    } else {
        if (options.point_count > 0)
            throw usage_error("--point-count needs --points SEQ");
        io::check_outputs(output.files, mask_files);
    }
    // Object space: points on the rest pose (the shot's first frame, whatever
    // --frames says, so that farm chunks agree on them).
    std::optional<render::SurfacePoints> points;
    if (!options.points.empty()) {
        scene::Scene rest = source.at(source.first_frame());
        std::int64_t target = options.point_count > 0
                                  ? options.point_count
                                  : static_cast<std::int64_t>(options.render.width) * options.render.height;
        points.emplace(rest, render::SurfacePoints::spacing_for_count(rest, target), kMaxSurfacePoints);
        for (int frame : frames)  // before the first output
            points->check_topology(source.at(frame), fmt::format("scene {} frame {}", options.scene, frame));
    }

    RunContext context(options.common);
    for (const std::string& notice : source.notices())
        context.progress().warn(options.scene + ": " + notice);
    // Outputs are renamed into place only when complete, so an existing frame is a
    // finished one: a re-queued farm job renders only what is missing.
    std::vector<size_t> to_render;
    std::vector<int> skipped;
    for (size_t i = 0; i < frames.size(); ++i) {
        if (options.skip_existing && std::filesystem::exists(output.files[i]))
            skipped.push_back(frames[i]);
        else
            to_render.push_back(i);
    }
    if (to_render.empty()) {
        context.progress().warn(fmt::format("every output of {} exists already (--skip-existing): nothing to do",
                                            options.output));
        return 0;
    }
    if (points && !options.common.quiet)
        std::fprintf(stderr, "object space: %lld surface points, lattice spacing %.4g m, baked at %d spp\n",
                     static_cast<long long>(points->count()), points->spacing(), options.render.spp);
    const std::int64_t units_per_frame =
        render::tile_count(options.render) + (points ? render::bake_step_count(*points) : 0);
    context.progress().begin(fmt::format("rendering {} frames of {} at {} spp", to_render.size(), options.scene,
                                         options.render.spp),
                             static_cast<std::int64_t>(to_render.size()) * units_per_frame);
    nlohmann::ordered_json per_frame = nlohmann::ordered_json::array();
    long long paths = 0, rays = 0;
    double seconds = 0;
    render::FrameAovs aovs;
    render::PointBake bake;
    for (size_t i : to_render) {
        std::vector<std::uint8_t> mask;
        if (!mask_files.empty())
            mask = io::read_mask(mask_files[i], options.render.width, options.render.height);
        scene::Scene scene = source.at(frames[i]);
        render::render_frame(scene, frames[i], options.render, mask.empty() ? nullptr : mask.data(), aovs,
                             context.progress(), points ? &*points : nullptr);
        if (points) {
            // The bake first: a frame on disk always has its points.
            render::bake_points(scene, frames[i], *points, options.render, bake, context.progress());
            write_points(points_output.files[i], bake, *points, options, source, frames[i]);
            paths += bake.stats.paths;
            rays += bake.stats.rays;
            seconds += bake.stats.seconds;
        }
        write_frame(output.files[i], aovs, options, source, frames[i]);
        paths += aovs.stats.paths;
        rays += aovs.stats.rays;
        seconds += aovs.stats.seconds;
        per_frame.push_back({{"frame", frames[i]},
                             {"seconds", aovs.stats.seconds},
                             {"paths", aovs.stats.paths},
                             {"rays", aovs.stats.rays},
                             {"paths_per_second", aovs.stats.paths_per_second()},
                             {"rays_per_second", aovs.stats.rays_per_second()}});
    }
    context.progress().end();
    if (!options.json_path.empty()) {
        nlohmann::ordered_json json;
        json["version"] = version_string();
        json["command"] = command_line();
        json["scene"] = options.scene;
        if (source.is_gltf())
            json["fps"] = source.fps();
        json["output"] = output.printf_pattern;
        if (points)
            json["points"] = {{"output", points_output.printf_pattern},
                              {"count", points->count()},
                              {"spacing", points->spacing()}};
        json["frames"] = io::describe_frames(frames);
        json["skipped_existing_frames"] = skipped.empty() ? std::string() : io::describe_frames(skipped);
        json["width"] = options.render.width;
        json["height"] = options.render.height;
        json["spp"] = options.render.spp;
        json["seed"] = options.render.seed;
        json["fixed_seed"] = options.render.fixed_seed;
        json["max_depth"] = options.render.max_depth;
        json["render_seconds"] = seconds;
        json["paths"] = paths;
        json["rays"] = rays;
        json["paths_per_second"] = seconds > 0 ? paths / seconds : 0.0;
        json["rays_per_second"] = seconds > 0 ? rays / seconds : 0.0;
        json["per_frame"] = per_frame;
        io::write_text_file(options.json_path, json.dump(2) + "\n");
    }
    return 0;
}

}  // namespace

Subcommand add_render_command(CLI::App& parent)
{
    auto options = std::make_shared<RenderCommandOptions>();
    CLI::App* command = parent.add_subcommand(
        "render",
        "Render a built-in animated scene or a glTF 2.0 file with the path tracer (one multi-layer EXR per frame)");
    command->add_option("--scene", options->scene,
                        "Built-in scene: static, orbit, switch, spin, flythrough (list: print them), or a glTF 2.0 file "
                        "FILE.gltf|FILE.glb (meshes, animation, first camera, KHR_lights_punctual; what is "
                        "approximated is reported on stderr)");
    command->add_option("-o,--output", options->output, "Output frame sequence, e.g. noisy/shot.####.exr");
    command->add_option("--frames", options->frames, "Frames to render (default: all of the scene's frames)");
    command->add_option("--fps", options->fps,
                        "glTF scenes: frames per second; frame f is at animation time (f-1)/fps (default: the "
                        "file's scene extras 'fps', else 24)")
        ->check(CLI::PositiveNumber)
        ->default_str("file's, else 24");  // 0 inside means "not given"
    command->add_option("--spp", options->render.spp, "Samples per pixel")->check(kAtLeastOne);
    command->add_option("--size", options->size, "Image size WIDTHxHEIGHT");
    command->add_option("--seed", options->render.seed, "Seed of the sample hash");
    command->add_flag("--fixed-seed", options->render.fixed_seed,
                      "Same random numbers in every frame (temporally correlated noise; a known failure case of "
                      "the denoiser)");
    command->add_option("--max-depth", options->render.max_depth, "Maximum number of bounces (1 = direct light)")
        ->check(kAtLeastOne);
    command->add_option("--mask", options->mask,
                        "Render only the pixels where this mask sequence's first channel is non-zero");
    command->add_option("--points", options->points,
                        "Object space: also bake each frame's indirect light at fixed surface points into this "
                        "sequence (DiffInd, DiffIndVar, Position, Normal; 1024 points per row) and add the PointLookup "
                        "layer to the frames; for denoise --object-space");
    command->add_option("--point-count", options->point_count,
                        "About how many surface points --points places (default: width x height); each "
                        "triangle of the first frame gets a barycentric lattice with cells of equal size")
        ->check(CLI::Range(std::int64_t{1}, kMaxSurfacePoints, "1 to 2^24"));
    command->add_option("--json", options->json_path, "Write per-frame times, paths/s and rays/s as JSON");
    command->add_flag("--skip-existing", options->skip_existing,
                      "Do not render frames whose output exists already (farm re-runs; outputs appear only "
                      "when complete)");
    add_common_options(*command, options->common);
    return {command, [options] { return run_render(*options); }};
}

}  // namespace modestack::app
