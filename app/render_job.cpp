// `modestack render` as a library call (render_job.h): the validation step, the
// render loop that writes one multi-layer EXR per frame with Cycles-style AOV
// names and provenance, and the --json summary.
#include "app/render_job.h"

#include "app/command.h"
#include "app/option_values.h"
#include "app/scene_frames.h"
#include "core/common/error.h"
#include "core/render/point_bake.h"
#include "core/render/surface_points.h"
#include "core/scene/builtin_scenes.h"
#include "io/frame_output.h"
#include "io/mask_image.h"

#include <fmt/format.h>

#include <cstdio>
#include <filesystem>
#include <optional>

namespace modestack::app {
namespace {


// Channel types written: colour layers in half as renderers write beauty passes;
// geometry and the variance in float, where half's precision would hurt.
const char* channel_type_for(const std::string& layer)
{
    return layer == "Depth" || layer == "Normal" || layer == "Position" || layer == "DiffIndVar" ||
                   layer == "PointLookup"
               ? "float"
               : "half";
}

std::vector<io::HeaderAttribute> provenance(const RenderJob& job, int frame, double seconds)
{
    const render::RenderOptions& render = job.render;
    std::vector<io::HeaderAttribute> attributes{
        io::HeaderAttribute::of_text("modestack:version", MODESTACK_VERSION),
        io::HeaderAttribute::of_text("modestack:command", command_line()),
        io::HeaderAttribute::of_text("modestack:scene", job.scene_name),
        io::HeaderAttribute::of_integer("modestack:frame", frame),
        io::HeaderAttribute::of_integer("modestack:spp", render.spp),
        io::HeaderAttribute::of_integer("modestack:seed", static_cast<long long>(render.seed)),
        io::HeaderAttribute::of_integer("modestack:fixed_seed", render.fixed_seed ? 1 : 0),
        io::HeaderAttribute::of_integer("modestack:max_depth", render.max_depth),
        io::HeaderAttribute::of_real("modestack:render_seconds", seconds),
        io::HeaderAttribute::of_text("modestack:mask", job.mask),
    };
    if (job.scene.is_gltf())
        attributes.push_back(io::HeaderAttribute::of_real("modestack:fps", job.scene.fps()));
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
                  const RenderJob& job, int frame)
{
    const std::vector<std::string> rgb{"R", "G", "B"};
    std::vector<render::AovLayer> layers{{"DiffInd", rgb, &bake.indirect},
                                         {"DiffIndVar", rgb, &bake.variance},
                                         {"Position", {"X", "Y", "Z"}, &bake.position},
                                         {"Normal", {"X", "Y", "Z"}, &bake.normal}};
    std::vector<io::HeaderAttribute> attributes = provenance(job, frame, bake.stats.seconds);
    attributes.push_back(io::HeaderAttribute::of_integer("modestack:points", points.count()));
    attributes.push_back(io::HeaderAttribute::of_real("modestack:point_spacing", points.spacing()));
    write_layers(path, layers, std::move(attributes), true);
}

}  // namespace

void list_scenes()
{
    for (const auto& info : scene::builtin_scenes())
        std::printf("%-8s frames %d-%d  %s\n", info.name.c_str(), info.first_frame, info.last_frame,
                    info.description.c_str());
}

RenderJob make_render_job(const RenderCommandOptions& options)
{
    if (options.output.empty())
        throw usage_error("render needs -o SEQ (e.g. -o noisy/shot.####.exr)");
    render::RenderOptions render_options = options.render;
    parse_image_size(options.size, render_options.width, render_options.height);
    render::validate_render_options(render_options);
    RenderJob job(SceneSource(options.scene, options.fps));
    const SceneSource& source = job.scene;
    job.scene_name = options.scene;
    job.render = render_options;
    job.frames = options.frames.empty()
                     ? io::parse_frame_range(fmt::format("{}-{}", source.first_frame(), source.last_frame()))
                     : io::parse_frame_range(options.frames);
    for (int frame : job.frames)
        if (frame < source.first_frame() || frame > source.last_frame())
            throw usage_error(
                "--frames: " + frame_outside_scene(frame, options.scene, source.first_frame(), source.last_frame()));
    job.output = io::output_sequence(options.output, job.frames);
    job.mask = options.mask;
    if (!options.points.empty())
        job.points_output = io::output_sequence(options.points, job.frames);
    else if (options.point_count > 0)
        throw usage_error("--point-count needs --points SEQ");
    job.point_count = options.point_count;
    job.skip_existing = options.skip_existing;
    return job;
}

RenderResult render(const RenderJob& job, const CommonOptions& context_options)
{
    const SceneSource& source = job.scene;
    const std::vector<int>& frames = job.frames;
    const bool bakes_points = !job.points_output.files.empty();
    std::vector<std::string> mask_files;
    if (!job.mask.empty()) {
        mask_files = io::find_input_sequence(job.mask, io::describe_frames(frames)).files;
        for (const std::string& file : mask_files)  // check every mask before the first frame
            io::read_mask(file, job.render.width, job.render.height);
    }
    std::vector<std::string> all_outputs = job.output.files;
    all_outputs.insert(all_outputs.end(), job.points_output.files.begin(), job.points_output.files.end());
    io::check_outputs(all_outputs, mask_files);
    // Object space: points on the rest pose (the shot's first frame, whatever
    // --frames says, so that farm chunks agree on them).
    std::optional<render::SurfacePoints> points;
    if (bakes_points) {
        scene::Scene rest = source.at(source.first_frame());
        std::int64_t target = job.point_count > 0 ? job.point_count
                                                  : static_cast<std::int64_t>(job.render.width) * job.render.height;
        points.emplace(rest, render::SurfacePoints::spacing_for_count(rest, target), kMaxSurfacePoints);
        for (int frame : frames)  // before the first output
            points->check_topology(source.at(frame), fmt::format("scene {} frame {}", job.scene_name, frame));
    }

    RunContext context(context_options);
    for (const std::string& notice : source.notices())
        context.progress().warn(job.scene_name + ": " + notice);
    RenderResult result;
    // Outputs are renamed into place only when complete, so an existing frame is a
    // finished one: a re-queued farm job renders only what is missing.
    std::vector<size_t> to_render;
    for (size_t i = 0; i < frames.size(); ++i) {
        if (job.skip_existing && std::filesystem::exists(job.output.files[i]))
            result.skipped.push_back(frames[i]);
        else
            to_render.push_back(i);
    }
    if (to_render.empty()) {
        context.progress().warn(fmt::format("every output of {} exists already (--skip-existing): nothing to do",
                                            job.output.pattern));
        result.nothing_to_do = true;
        return result;
    }
    if (points && !context_options.quiet)
        std::fprintf(stderr, "object space: %lld surface points, lattice spacing %.4g m, baked at %d spp\n",
                     static_cast<long long>(points->count()), points->spacing(), job.render.spp);
    const std::int64_t units_per_frame =
        render::tile_count(job.render) + (points ? render::bake_step_count(*points) : 0);
    context.progress().begin(
        fmt::format("rendering {} frames of {} at {} spp", to_render.size(), job.scene_name, job.render.spp),
        static_cast<std::int64_t>(to_render.size()) * units_per_frame);
    render::FrameAovs aovs;
    render::PointBake bake;
    for (size_t i : to_render) {
        std::vector<std::uint8_t> mask;
        if (!mask_files.empty())
            mask = io::read_mask(mask_files[i], job.render.width, job.render.height);
        scene::Scene scene = source.at(frames[i]);
        render::render_frame(scene, frames[i], job.render, mask.empty() ? nullptr : mask.data(), aovs,
                             context.progress(), points ? &*points : nullptr);
        if (points) {
            // The bake first: a frame on disk always has its points.
            render::bake_points(scene, frames[i], *points, job.render, bake, context.progress());
            write_points(job.points_output.files[i], bake, *points, job, frames[i]);
            result.paths += bake.stats.paths;
            result.rays += bake.stats.rays;
            result.render_seconds += bake.stats.seconds;
        }
        write_layers(job.output.files[i], render::aov_layers(aovs), provenance(job, frames[i], aovs.stats.seconds));
        result.paths += aovs.stats.paths;
        result.rays += aovs.stats.rays;
        result.render_seconds += aovs.stats.seconds;
        result.per_frame.push_back({frames[i], aovs.stats});
    }
    context.progress().end();
    result.scene = job.scene_name;
    result.gltf = source.is_gltf();
    result.fps = source.fps();
    result.output = job.output.printf_pattern;
    if (points) {
        result.has_points = true;
        result.points_output = job.points_output.printf_pattern;
        result.point_count = points->count();
        result.point_spacing = points->spacing();
    }
    result.frames = frames;
    result.render = job.render;
    return result;
}

nlohmann::ordered_json render_json(const RenderResult& result)
{
    nlohmann::ordered_json json;
    json["version"] = version_string();
    json["command"] = command_line();
    json["scene"] = result.scene;
    if (result.gltf)
        json["fps"] = result.fps;
    json["output"] = result.output;
    if (result.has_points)
        json["points"] = {{"output", result.points_output},
                          {"count", result.point_count},
                          {"spacing", result.point_spacing}};
    json["frames"] = io::describe_frames(result.frames);
    json["skipped_existing_frames"] = result.skipped.empty() ? std::string() : io::describe_frames(result.skipped);
    json["width"] = result.render.width;
    json["height"] = result.render.height;
    json["spp"] = result.render.spp;
    json["seed"] = result.render.seed;
    json["fixed_seed"] = result.render.fixed_seed;
    json["max_depth"] = result.render.max_depth;
    const double seconds = result.render_seconds;
    json["render_seconds"] = seconds;
    json["paths"] = result.paths;
    json["rays"] = result.rays;
    json["paths_per_second"] = seconds > 0 ? result.paths / seconds : 0.0;
    json["rays_per_second"] = seconds > 0 ? result.rays / seconds : 0.0;
    json["per_frame"] = nlohmann::ordered_json::array();
    for (const RenderedFrame& frame : result.per_frame)
        json["per_frame"].push_back({{"frame", frame.frame},
                                     {"seconds", frame.stats.seconds},
                                     {"paths", frame.stats.paths},
                                     {"rays", frame.stats.rays},
                                     {"paths_per_second", frame.stats.paths_per_second()},
                                     {"rays_per_second", frame.stats.rays_per_second()}});
    return json;
}

}  // namespace modestack::app
