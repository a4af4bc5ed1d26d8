// `modestack refine` as a library call (refine_job.h): re-render what the
// denoiser is unsure of ([0088]–[0095]). Reads the denoised indirect layer and
// its sigma channels, selects the pixels with a high relative error (a fixed
// threshold, or the budget's P % worst pixels of the whole shot), grows and
// feathers the selection, re-renders those pixels at high spp with the built-in
// tracer (core/render, no subprocess) and blends them in. Every other channel,
// Combined included, is copied untouched: the final beauty is composited by
// `modestack run` (beauty = DiffCol × (DiffDir + DiffInd) + Emit, [0017]).
#include "app/refine_job.h"

#include "app/command.h"
#include "app/option_values.h"
#include "app/scene_frames.h"
#include "core/common/error.h"
#include "core/scene/builtin_scenes.h"
#include "io/frame_header.h"
#include "io/frame_output.h"
#include "io/layers.h"
#include "io/sequence.h"
#include "io/sequence_reader.h"

#include <fmt/format.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>

namespace modestack::app {
namespace {

const scene::SceneInfo& find_scene(const std::string& name)
{
    for (const auto& info : scene::builtin_scenes())
        if (info.name == name)
            return info;
    scene::make_builtin_scene(name, 1); // throws the error that lists the scenes
    throw internal_error("unknown scene accepted");
}

bool layer_is(const std::string& layer, const std::string& wanted)
{
    return layer == wanted || (layer.size() > wanted.size() &&
                               layer.compare(layer.size() - wanted.size(), wanted.size(), wanted) == 0 &&
                               layer[layer.size() - wanted.size() - 1] == '.');
}

// Checks, from the first frame's header, the things a user most often gets wrong:
// a sequence that was never denoised, or a layer the renderer cannot re-render.
void check_denoised_header(const std::string& file, const std::string& layer)
{
    std::string last = layer.substr(layer.rfind('.') == std::string::npos ? 0 : layer.rfind('.') + 1);
    if (last != "DiffInd")
        throw usage_error(
            fmt::format("--layer {}: refine re-renders the indirect layer DiffInd (the one whose "
                        "noise the renderer measures)",
                        layer));
    io::FrameHeader header = io::read_frame_header(file);
    bool has_sigma = false;
    for (const auto& group : io::group_layers(io::channels_as_read(header)))
        has_sigma = has_sigma || layer_is(group.name, layer + ".sigma");
    if (!has_sigma)
        throw bad_input(file,
                        fmt::format("no {}.sigma channels: refine needs the output of 'modestack denoise "
                                    "--layer {}'",
                                    layer, layer));
}

struct Pass1 {
    float threshold = std::numeric_limits<float>::infinity();
    double seconds = 0;
};

// --budget: one read of every frame's value and sigma to find the shot-wide threshold.
Pass1 budget_threshold(const io::SequenceReader& reader, const RefineJob& job, Progress& progress)
{
    auto start = std::chrono::steady_clock::now();
    Pass1 pass;
    const int width = reader.width(), height = reader.height();
    const std::size_t pixels = static_cast<std::size_t>(width) * height;
    refine::ScoreHistogram histogram;
    std::vector<float> rows(pixels * 6), value(pixels * 3), sigma(pixels * 3), scores(pixels);
    progress.begin("scoring the denoised frames", reader.frame_count());
    for (int i = 0; i < reader.frame_count(); ++i) {
        throw_if_cancelled();
        reader.read_selected(i, 0, height, rows.data());
        for (std::size_t p = 0; p < pixels; ++p)
            for (int c = 0; c < 3; ++c) {
                value[p * 3 + c] = rows[p * 6 + c];
                sigma[p * 3 + c] = rows[p * 6 + 3 + c];
            }
        refine::relative_error_scores(value.data(), sigma.data(), pixels, 3, job.settings.dark_floor,
                                      scores.data());
        histogram.add(scores.data(), pixels);
        progress.advance();
    }
    progress.end();
    pass.threshold = histogram.threshold_for_fraction(job.budget_percent / 100.0);
    pass.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return pass;
}

}  // namespace

RefineJob make_refine_job(const RefineCommandOptions& options)
{
    if (options.scene.empty())
        throw usage_error("refine needs --scene NAME (the scene the denoised frames were rendered from)");
    if (options.denoised.empty() || options.output.empty())
        throw usage_error("refine needs --denoised SEQ and -o SEQ");
    RefineJob job;
    job.settings = options.settings;
    parse_image_size(options.size, job.settings.render.width, job.settings.render.height);
    render::validate_render_options(job.settings.render);
    refine::validate_feather_options(job.settings.feather);
    if (options.budget_percent > 100)
        throw usage_error("--budget is a percentage of the shot's pixels: 0 to 100");
    if (!(options.threshold > 0))
        throw usage_error("--threshold must be above 0 (a relative error, e.g. 0.2)");
    const scene::SceneInfo& info = find_scene(options.scene);
    job.scene = options.scene;
    job.scene_first_frame = info.first_frame;
    job.scene_last_frame = info.last_frame;
    job.denoised = options.denoised;
    job.output = options.output;
    job.frames = options.frames;
    job.size = options.size;
    job.layer = options.layer;
    job.masks = options.masks;
    job.exr_codec = options.exr_codec;
    job.threshold = options.threshold;
    job.budget_percent = options.budget_percent;
    return job;
}

RefineResult refine(const RefineJob& job, const CommonOptions& context_options)
{
    auto start = std::chrono::steady_clock::now();
    const render::RenderOptions& render_options = job.settings.render;
    io::FrameSequence input = io::find_input_sequence(job.denoised, job.frames);
    for (int frame : input.frames)
        if (frame < job.scene_first_frame || frame > job.scene_last_frame)
            throw bad_input(job.denoised,
                            frame_outside_scene(frame, job.scene, job.scene_first_frame, job.scene_last_frame));
    check_denoised_header(input.files.front(), job.layer);
    io::FrameSequence output = io::output_sequence(job.output, input.frames);
    io::FrameSequence masks;
    if (!job.masks.empty())
        masks = io::output_sequence(job.masks, input.frames);
    io::SequenceReader reader(input, {job.layer, job.layer + ".sigma"}, job.exr_codec);
    if (reader.width() != render_options.width || reader.height() != render_options.height)
        throw bad_input(
            input.files.front(),
            fmt::format("the frames are {}x{} but --size is {}; pass the size they were rendered at",
                        reader.width(), reader.height(), job.size));
    for (const auto& layer : reader.layers())
        if (layer.channel_names.size() != 3)
            throw bad_input(input.files.front(),
                            fmt::format("layer {} must have R, G and B channels", layer.name));
    std::vector<std::string> all_outputs = output.files;
    all_outputs.insert(all_outputs.end(), masks.files.begin(), masks.files.end());
    io::check_outputs(all_outputs, input.files);

    RunContext context(context_options);
    Pass1 pass1;
    if (job.budget_percent >= 0)
        pass1 = budget_threshold(reader, job, context.progress());
    else
        pass1.threshold = static_cast<float>(job.threshold);

    const int width = reader.width(), height = reader.height();
    const std::size_t pixels = static_cast<std::size_t>(width) * height;
    const std::string weight_channel = reader.layers().front().name + ".refine_weight";
    std::vector<io::HeaderAttribute> attributes{
        io::HeaderAttribute::of_text("modestack:version", MODESTACK_VERSION),
        io::HeaderAttribute::of_text("modestack:command", command_line()),
        io::HeaderAttribute::of_text("modestack:scene", job.scene),
        io::HeaderAttribute::of_integer("modestack:refine_spp", render_options.spp),
        io::HeaderAttribute::of_real("modestack:refine_threshold", pass1.threshold),
    };
    std::vector<std::unique_ptr<io::FrameOutput>> outputs;
    RefineResult result;
    std::vector<float> rows(pixels * 6), value(pixels * 3), sigma(pixels * 3), weights(pixels);
    std::vector<unsigned char> native;
    double render_seconds = 0, estimated_before = 0, estimated_after = 0;
    context.progress().begin(fmt::format("re-rendering unsure pixels of {} frames at {} spp",
                                         input.frames.size(), render_options.spp),
                             static_cast<std::int64_t>(input.frames.size()) *
                                 render::tile_count(render_options));
    for (int i = 0; i < reader.frame_count(); ++i) {
        throw_if_cancelled();
        const int frame = input.frames[i];
        reader.read_selected(i, 0, height, rows.data());
        for (std::size_t p = 0; p < pixels; ++p)
            for (int c = 0; c < 3; ++c) {
                value[p * 3 + c] = rows[p * 6 + c];
                sigma[p * 3 + c] = rows[p * 6 + 3 + c];
            }
        refine::FrameRefineReport report = refine::refine_frame(
            scene::make_builtin_scene(job.scene, frame), frame, pass1.threshold, job.settings, value.data(),
            sigma.data(), weights.data(), context.progress());
        for (std::size_t p = 0; p < pixels; ++p)
            for (int c = 0; c < 3; ++c) {
                rows[p * 6 + c] = value[p * 3 + c];
                rows[p * 6 + 3 + c] = sigma[p * 3 + c];
            }
        reader.read_native(i, 0, height, native);
        outputs.push_back(std::make_unique<io::FrameOutput>(
            output.files[i], reader, i, std::vector<std::string>{weight_channel}, attributes, job.exr_codec));
        outputs.back()->write_replaced_rows(0, height, native, rows.data(), weights.data());
        if (!masks.files.empty()) {
            io::NewImageDescription image;
            image.width = width;
            image.height = height;
            image.channel_names = {"mask", "weight"};
            image.channel_types = {"half", "half"};
            std::vector<float> mask_pixels(pixels * 2);
            for (std::size_t p = 0; p < pixels; ++p) {
                mask_pixels[p * 2] = weights[p] > 0 ? 1.0f : 0.0f;
                mask_pixels[p * 2 + 1] = weights[p];
            }
            outputs.push_back(std::make_unique<io::FrameOutput>(masks.files[i], image, attributes));
            outputs.back()->write_float_rows(0, height, mask_pixels.data());
        }
        result.pixels_selected += report.selected_pixels;
        result.pixels_rendered += report.rendered_pixels;
        result.paths += report.stats.paths;
        render_seconds += report.seconds_render;
        estimated_before += report.estimated_before;
        estimated_after += report.estimated_after;
        result.per_frame.push_back({frame, report});
    }
    context.progress().end();
    for (auto& file : outputs)
        file->commit();

    const double frames = static_cast<double>(input.frames.size());
    const double total_pixels = frames * static_cast<double>(pixels);
    result.scene = job.scene;
    result.input = input.printf_pattern;
    result.output = output.printf_pattern;
    result.frames = input.frames;
    result.layer = reader.layers().front().name;
    result.spp = render_options.spp;
    result.budget_percent = job.budget_percent;
    result.threshold = pass1.threshold;
    result.dilate = job.settings.feather.dilation;
    result.feather = job.settings.feather.feather;
    result.percent_rendered = 100.0 * static_cast<double>(result.pixels_rendered) / total_pixels;
    result.estimated_relmse_before = estimated_before / frames;
    result.estimated_relmse_after = estimated_after / frames;
    result.seconds_scoring = pass1.seconds;
    result.seconds_render = render_seconds;
    result.seconds_total = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return result;
}

nlohmann::ordered_json refine_json(const RefineResult& result)
{
    nlohmann::ordered_json json;
    json["version"] = version_string();
    json["command"] = command_line();
    json["scene"] = result.scene;
    json["input"] = result.input;
    json["output"] = result.output;
    json["frames"] = io::describe_frames(result.frames);
    json["layer"] = result.layer;
    json["spp"] = result.spp;
    const bool by_budget = result.budget_percent >= 0;
    json["selection"] = by_budget ? "budget" : "threshold";
    json["budget_percent"] = by_budget ? nlohmann::ordered_json(result.budget_percent) : nlohmann::ordered_json();
    json["threshold"] =
        std::isfinite(result.threshold) ? nlohmann::ordered_json(result.threshold) : nlohmann::ordered_json();
    json["dilate"] = result.dilate;
    json["feather"] = result.feather;
    json["pixels_selected"] = result.pixels_selected;
    json["pixels_rendered"] = result.pixels_rendered;
    json["percent_rendered"] = result.percent_rendered;
    json["paths"] = result.paths;
    json["estimated_relmse_before"] = result.estimated_relmse_before;
    json["estimated_relmse_after"] = result.estimated_relmse_after;
    json["seconds"] = {
        {"scoring", result.seconds_scoring}, {"render", result.seconds_render}, {"total", result.seconds_total}};
    json["per_frame"] = nlohmann::ordered_json::array();
    for (const RefinedFrame& frame : result.per_frame)
        json["per_frame"].push_back({{"frame", frame.frame},
                                     {"pixels_selected", frame.report.selected_pixels},
                                     {"pixels_rendered", frame.report.rendered_pixels},
                                     {"percent_rendered", 100.0 * frame.report.rendered_pixels / frame.report.pixels},
                                     {"seconds_render", frame.report.seconds_render},
                                     {"estimated_relmse_before", frame.report.estimated_before},
                                     {"estimated_relmse_after", frame.report.estimated_after}});
    return json;
}

void print_refine_summary(const RefineResult& result)
{
    std::fprintf(stderr,
                 "refined %lld pixels (%.2f %% of %d frames) at %d spp in %.2f s; estimated relMSE %.4g -> %.4g\n",
                 static_cast<long long>(result.pixels_rendered), result.percent_rendered,
                 static_cast<int>(result.frames.size()), result.spp, result.seconds_total,
                 result.estimated_relmse_before, result.estimated_relmse_after);
}

}  // namespace modestack::app
