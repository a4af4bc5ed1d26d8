// `modestack refine` as a library call (refine_job.h): re-render what the
// denoiser is unsure of ([0088]–[0095]). Reads the denoised indirect layer and
// its sigma channels, selects the pixels with a high relative error (a fixed
// threshold, or the budget's P % worst pixels of the whole shot) or, with
// --by-gain, those where a re-render pays for its samples, grows and
// feathers the selection, re-renders those pixels at high spp with the built-in
// tracer (core/render, no subprocess) and blends them in. Every other channel,
// Combined included, is copied untouched: the final beauty is composited by
// `modestack run` (beauty = DiffCol × (DiffDir + DiffInd) + Emit, [0017]).
#include "app/refine_job.h"

#include "app/command.h"
#include "app/option_values.h"
#include "app/refine_frames.h"
#include "app/scene_frames.h"
#include "core/common/error.h"
#include "core/scene/builtin_scenes.h"
#include "io/frame_header.h"
#include "io/frame_output.h"
#include "io/sequence.h"
#include "io/sequence_reader.h"

#include <fmt/format.h>

#include <chrono>
#include <cmath>
#include <cstdio>

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

// Checks, from the first frame's header, the things a user most often gets wrong:
// a sequence that was never denoised, or a layer the renderer cannot re-render.
void check_denoised_header(const std::string& file, const std::string& layer)
{
    std::string last = layer.substr(layer.rfind('.') == std::string::npos ? 0 : layer.rfind('.') + 1);
    if (last != "DiffInd")
        throw usage_error(
            fmt::format("--layer {}: refine re-renders the indirect layer DiffInd (the one whose "
                        "noise the renderer measures); other layers: --masks-only and --blend",
                        layer));
    check_sigma_channels(file, layer);
}

}  // namespace

const char* selection_name(RefineSelection selection)
{
    switch (selection) {
    case RefineSelection::Threshold:
        return "threshold";
    case RefineSelection::Budget:
        return "budget";
    case RefineSelection::Gain:
        return "gain";
    }
    return "?";
}

RefineJob make_refine_job(const RefineCommandOptions& options)
{
    RefineJob job;
    if (options.masks_only && !options.blend.empty())
        throw usage_error("--masks-only and --blend are the two halves of the loop around another renderer: "
                          "give one");
    job.mode = options.masks_only       ? RefineMode::MasksOnly
               : !options.blend.empty() ? RefineMode::Blend
                                        : RefineMode::Render;
    if (job.mode != RefineMode::Render && !options.scene.empty())
        throw usage_error("--scene is for the built-in re-render; --masks-only and --blend render nothing");
    if (job.mode != RefineMode::MasksOnly && !options.windows.empty())
        throw usage_error("--windows is written by --masks-only");
    if (job.mode == RefineMode::Blend && options.budget_percent >= 0)
        throw usage_error("--blend takes the choice of pixels from --masks: drop --budget");
    if (job.mode == RefineMode::Render && options.scene.empty())
        throw usage_error("refine needs --scene NAME (the scene the denoised frames were rendered from), or "
                          "--masks-only / --blend to re-render with another renderer");
    if (options.denoised.empty())
        throw usage_error("refine needs --denoised SEQ");
    if (job.mode == RefineMode::MasksOnly) {
        if (options.masks.empty())
            throw usage_error("--masks-only needs --masks SEQ (where to write the masks)");
        if (!options.output.empty())
            throw usage_error("--masks-only writes masks, not frames: drop -o (refine --blend writes them)");
    } else if (options.output.empty()) {
        throw usage_error(job.mode == RefineMode::Blend ? "refine --blend needs -o SEQ"
                                                        : "refine needs --denoised SEQ and -o SEQ");
    }
    if (job.mode == RefineMode::Blend && options.masks.empty())
        throw usage_error("--blend needs --masks SEQ (the masks refine --masks-only wrote)");
    if (options.window_overhead < 0)
        throw usage_error("--window-overhead is a number of pixels, 0 or more");
    job.settings = options.settings;
    refine::validate_feather_options(job.settings.feather);
    if (options.budget_percent > 100)
        throw usage_error("--budget is a percentage of the shot's pixels: 0 to 100");
    if (options.threshold < 0)
        throw usage_error("--threshold must be above 0 (a relative error, e.g. 0.2)");
    if (job.mode == RefineMode::Render) {
        parse_image_size(options.size, job.settings.render.width, job.settings.render.height);
        render::validate_render_options(job.settings.render);
        const scene::SceneInfo& info = find_scene(options.scene);
        job.scene = options.scene;
        job.scene_first_frame = info.first_frame;
        job.scene_last_frame = info.last_frame;
    }
    job.denoised = options.denoised;
    job.output = options.output;
    job.frames = options.frames;
    job.size = options.size;
    job.layer = options.layer;
    job.masks = options.masks;
    job.exr_codec = options.exr_codec;
    if ((options.budget_percent >= 0) + (options.threshold > 0) + options.by_gain > 1)
        throw usage_error(
            "--threshold, --budget and --by-gain are three ways to choose the pixels: give one");
    if (options.by_gain && job.mode != RefineMode::Render)
        throw usage_error(
            "--by-gain weighs the built-in re-render's samples: not with --masks-only or --blend");
    job.selection = options.budget_percent >= 0 ? RefineSelection::Budget
                    : options.by_gain           ? RefineSelection::Gain
                                                : RefineSelection::Threshold;
    job.threshold = options.threshold > 0 ? options.threshold : kDefaultRefineThreshold;
    job.budget_percent = options.budget_percent;
    job.windows = options.windows;
    job.window_overhead = options.window_overhead;
    job.blend = options.blend;
    job.blend_layer = options.blend_layer.empty() ? options.layer : options.blend_layer;
    job.blend_variance = options.blend_variance.empty() ? job.blend_layer + "Var" : options.blend_variance;
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
    check_colour_layers(reader);
    std::vector<std::string> all_outputs = output.files;
    all_outputs.insert(all_outputs.end(), masks.files.begin(), masks.files.end());
    io::check_outputs(all_outputs, input.files);

    RunContext context(context_options);
    double seconds_scoring = 0;
    refine::RefineSettings settings = job.settings;
    // Gain: the input's variance of the mean. This reader checks that every frame has it and
    // says which channels hold it; the values come from the layer reader's native rows.
    std::unique_ptr<io::SequenceReader> variance_reader;
    float threshold = static_cast<float>(job.threshold);
    if (job.selection == RefineSelection::Budget) {
        threshold = budget_threshold(reader, job.budget_percent, settings.dark_floor, context.progress(),
                                     seconds_scoring);
    } else if (job.selection == RefineSelection::Gain) {
        settings.score = refine::RefineScore::Gain;
        settings.input_spp = recorded_input_spp(input.files.front(), job.layer);
        variance_reader = std::make_unique<io::SequenceReader>(
            input, std::vector<std::string>{job.layer + "Var"}, job.exr_codec);
        threshold = gain_threshold_of_shot(reader, settings, context.progress(), seconds_scoring);
    }

    const int width = reader.width(), height = reader.height();
    const std::size_t pixels = static_cast<std::size_t>(width) * height;
    const std::string weight_channel = reader.layers().front().name + ".refine_weight";
    std::vector<io::HeaderAttribute> attributes{
        io::HeaderAttribute::of_text("modestack:version", MODESTACK_VERSION),
        io::HeaderAttribute::of_text("modestack:command", command_line()),
        io::HeaderAttribute::of_text("modestack:scene", job.scene),
        io::HeaderAttribute::of_integer("modestack:refine_spp", render_options.spp),
        io::HeaderAttribute::of_text("modestack:refine_selection", selection_name(job.selection)),
        io::HeaderAttribute::of_real("modestack:refine_threshold", threshold),
    };
    std::vector<std::unique_ptr<io::FrameOutput>> outputs;
    RefineResult result;
    LayerAndSigma layer(pixels);
    std::vector<float> weights(pixels), variance(variance_reader ? pixels * 3 : 0);
    std::vector<unsigned char> native;
    double render_seconds = 0, estimated_before = 0, estimated_after = 0;
    context.progress().begin(fmt::format("re-rendering unsure pixels of {} frames at {} spp",
                                         input.frames.size(), render_options.spp),
                             static_cast<std::int64_t>(input.frames.size()) *
                                 render::tile_count(render_options));
    for (int i = 0; i < reader.frame_count(); ++i) {
        throw_if_cancelled();
        const int frame = input.frames[i];
        // Decoded once: the layer, its sigma and its variance come from the native rows the
        // output copies its other channels from.
        reader.read_native(i, 0, height, native);
        layer.from_native(reader, i, native.data());
        if (variance_reader)
            reader.channels_from_native(i, native.data(), pixels, variance_reader->selected_channels(i),
                                        variance.data());
        refine::FrameRefineReport report = refine::refine_frame(
            scene::make_builtin_scene(job.scene, frame), frame, threshold, settings, layer.value.data(),
            layer.sigma.data(), variance_reader ? variance.data() : nullptr, weights.data(),
            context.progress());
        layer.store();
        outputs.push_back(std::make_unique<io::FrameOutput>(
            output.files[i], reader, i, std::vector<std::string>{weight_channel}, attributes, job.exr_codec));
        outputs.back()->write_replaced_rows(0, height, native, layer.rows.data(), weights.data());
        if (!masks.files.empty())
            add_mask_output(outputs, masks.files[i], weights, width, height, attributes);
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
    result.selection = job.selection;
    result.budget_percent = job.budget_percent;
    result.threshold = threshold;
    result.input_spp = settings.input_spp;
    result.dilate = job.settings.feather.dilation;
    result.feather = job.settings.feather.feather;
    result.percent_rendered = 100.0 * static_cast<double>(result.pixels_rendered) / total_pixels;
    result.estimated_relmse_before = estimated_before / frames;
    result.estimated_relmse_after = estimated_after / frames;
    result.seconds_scoring = seconds_scoring;
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
    const bool by_budget = result.selection == RefineSelection::Budget;
    json["selection"] = selection_name(result.selection);
    json["budget_percent"] = by_budget ? nlohmann::ordered_json(result.budget_percent) : nlohmann::ordered_json();
    json["input_spp"] = result.selection == RefineSelection::Gain ? nlohmann::ordered_json(result.input_spp)
                                                                  : nlohmann::ordered_json();
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
