// `modestack refine --scene NAME --denoised SEQ -o SEQ`: re-render what the
// denoiser is unsure of ([0088]–[0095]). Reads the denoised indirect layer and
// its sigma channels, selects the pixels with a high relative error (a fixed
// --threshold, or the --budget P % worst pixels of the whole shot), grows and
// feathers the selection, re-renders those pixels at high spp with the built-in
// tracer (core/render, no subprocess) and blends them in. Every other channel,
// Combined included, is copied untouched: the final beauty is composited by
// `modestack run` (beauty = DiffCol × (DiffDir + DiffInd) + Emit, [0017]).
#include "app/command.h"
#include "app/exr_codec_option.h"
#include "app/option_values.h"
#include "app/run_context.h"
#include "core/common/error.h"
#include "core/refine/refine_frame.h"
#include "core/scene/builtin_scenes.h"
#include "io/frame_header.h"
#include "io/frame_output.h"
#include "io/layers.h"
#include "io/sequence.h"
#include "io/sequence_reader.h"
#include "io/text_output.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>

namespace modestack::app {
namespace {

// A whole number of at least 1; CLI::PositiveNumber would print "not in range 0
// to" the largest double, in full.
const CLI::Range kAtLeastOne(1, std::numeric_limits<int>::max(), "at least 1");

struct RefineOptions {
    std::string scene;
    std::string denoised;
    std::string output;
    std::string frames;
    std::string size = "320x240";
    std::string layer = "DiffInd";
    std::string masks;
    std::string json_path;
    double threshold = 0.2;
    double budget_percent = -1; ///< < 0: use the threshold
    refine::RefineSettings settings;
    CommonOptions common;
    io::ExrCodec exr_codec = io::ExrCodec::Libdeflate;
};

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
    for (const auto& group : io::group_layers(header.channel_names))
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
Pass1 budget_threshold(const io::SequenceReader& reader, const RefineOptions& options, Progress& progress)
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
        refine::relative_error_scores(value.data(), sigma.data(), pixels, 3, options.settings.dark_floor,
                                      scores.data());
        histogram.add(scores.data(), pixels);
        progress.advance();
    }
    progress.end();
    pass.threshold = histogram.threshold_for_fraction(options.budget_percent / 100.0);
    pass.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return pass;
}

int run_refine(RefineOptions& options)
{
    auto start = std::chrono::steady_clock::now();
    if (options.scene.empty())
        throw usage_error("refine needs --scene NAME (the scene the denoised frames were rendered from)");
    if (options.denoised.empty() || options.output.empty())
        throw usage_error("refine needs --denoised SEQ and -o SEQ");
    render::RenderOptions& render_options = options.settings.render;
    parse_image_size(options.size, render_options.width, render_options.height);
    render::validate_render_options(render_options);
    refine::validate_feather_options(options.settings.feather);
    if (options.budget_percent > 100)
        throw usage_error("--budget is a percentage of the shot's pixels: 0 to 100");
    if (!(options.threshold > 0))
        throw usage_error("--threshold must be above 0 (a relative error, e.g. 0.2)");
    const scene::SceneInfo& info = find_scene(options.scene);

    io::FrameSequence input = io::find_input_sequence(options.denoised, options.frames);
    for (int frame : input.frames)
        if (frame < info.first_frame || frame > info.last_frame)
            throw bad_input(options.denoised,
                            fmt::format("frame {} is outside scene '{}' (frames {}-{})", frame, options.scene,
                                        info.first_frame, info.last_frame));
    check_denoised_header(input.files.front(), options.layer);
    io::FrameSequence output = io::output_sequence(options.output, input.frames);
    io::FrameSequence masks;
    if (!options.masks.empty())
        masks = io::output_sequence(options.masks, input.frames);
    io::SequenceReader reader(input, {options.layer, options.layer + ".sigma"}, options.exr_codec);
    if (reader.width() != render_options.width || reader.height() != render_options.height)
        throw bad_input(
            input.files.front(),
            fmt::format("the frames are {}x{} but --size is {}; pass the size they were rendered at",
                        reader.width(), reader.height(), options.size));
    for (const auto& layer : reader.layers())
        if (layer.channel_names.size() != 3)
            throw bad_input(input.files.front(),
                            fmt::format("layer {} must have R, G and B channels", layer.name));
    std::vector<std::string> all_outputs = output.files;
    all_outputs.insert(all_outputs.end(), masks.files.begin(), masks.files.end());
    io::check_outputs(all_outputs, input.files);

    RunContext context(options.common);
    Pass1 pass1;
    if (options.budget_percent >= 0)
        pass1 = budget_threshold(reader, options, context.progress());
    else
        pass1.threshold = static_cast<float>(options.threshold);

    const int width = reader.width(), height = reader.height();
    const std::size_t pixels = static_cast<std::size_t>(width) * height;
    const std::string weight_channel = reader.layers().front().name + ".refine_weight";
    std::vector<io::HeaderAttribute> attributes{
        io::HeaderAttribute::of_text("modestack:version", MODESTACK_VERSION),
        io::HeaderAttribute::of_text("modestack:command", command_line()),
        io::HeaderAttribute::of_text("modestack:scene", options.scene),
        io::HeaderAttribute::of_integer("modestack:refine_spp", render_options.spp),
        io::HeaderAttribute::of_real("modestack:refine_threshold", pass1.threshold),
    };
    std::vector<std::unique_ptr<io::FrameOutput>> outputs;
    nlohmann::ordered_json per_frame = nlohmann::ordered_json::array();
    std::vector<float> rows(pixels * 6), value(pixels * 3), sigma(pixels * 3), weights(pixels);
    std::vector<unsigned char> native;
    std::int64_t selected = 0, rendered = 0, paths = 0;
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
            scene::make_builtin_scene(options.scene, frame), frame, pass1.threshold, options.settings,
            value.data(), sigma.data(), weights.data(), context.progress());
        for (std::size_t p = 0; p < pixels; ++p)
            for (int c = 0; c < 3; ++c) {
                rows[p * 6 + c] = value[p * 3 + c];
                rows[p * 6 + 3 + c] = sigma[p * 3 + c];
            }
        reader.read_native(i, 0, height, native);
        outputs.push_back(std::make_unique<io::FrameOutput>(
            output.files[i], reader, i, std::vector<std::string>{weight_channel}, attributes, options.exr_codec));
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
        selected += report.selected_pixels;
        rendered += report.rendered_pixels;
        paths += report.stats.paths;
        render_seconds += report.seconds_render;
        estimated_before += report.estimated_before;
        estimated_after += report.estimated_after;
        per_frame.push_back({{"frame", frame},
                             {"pixels_selected", report.selected_pixels},
                             {"pixels_rendered", report.rendered_pixels},
                             {"percent_rendered", 100.0 * report.rendered_pixels / report.pixels},
                             {"seconds_render", report.seconds_render},
                             {"estimated_relmse_before", report.estimated_before},
                             {"estimated_relmse_after", report.estimated_after}});
    }
    context.progress().end();
    for (auto& file : outputs)
        file->commit();

    const double frames = static_cast<double>(input.frames.size());
    const double total_pixels = frames * static_cast<double>(pixels);
    double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (!options.json_path.empty()) {
        nlohmann::ordered_json json;
        json["version"] = version_string();
        json["command"] = command_line();
        json["scene"] = options.scene;
        json["input"] = input.printf_pattern;
        json["output"] = output.printf_pattern;
        json["frames"] = io::describe_frames(input.frames);
        json["layer"] = reader.layers().front().name;
        json["spp"] = render_options.spp;
        json["selection"] = options.budget_percent >= 0 ? "budget" : "threshold";
        json["budget_percent"] = options.budget_percent >= 0 ? nlohmann::ordered_json(options.budget_percent)
                                                             : nlohmann::ordered_json();
        json["threshold"] = std::isfinite(pass1.threshold) ? nlohmann::ordered_json(pass1.threshold)
                                                           : nlohmann::ordered_json();
        json["dilate"] = options.settings.feather.dilation;
        json["feather"] = options.settings.feather.feather;
        json["pixels_selected"] = selected;
        json["pixels_rendered"] = rendered;
        json["percent_rendered"] = 100.0 * static_cast<double>(rendered) / total_pixels;
        json["paths"] = paths;
        json["estimated_relmse_before"] = estimated_before / frames;
        json["estimated_relmse_after"] = estimated_after / frames;
        json["seconds"] = {{"scoring", pass1.seconds}, {"render", render_seconds}, {"total", seconds}};
        json["per_frame"] = per_frame;
        io::write_text_file(options.json_path, json.dump(2) + "\n");
    }
    if (!options.common.quiet)
        std::fprintf(
            stderr,
            "refined %lld pixels (%.2f %% of %d frames) at %d spp in %.2f s; estimated relMSE %.4g -> %.4g\n",
            static_cast<long long>(rendered), 100.0 * static_cast<double>(rendered) / total_pixels,
            static_cast<int>(frames), render_options.spp, seconds, estimated_before / frames,
            estimated_after / frames);
    return 0;
}

} // namespace

Subcommand add_refine_command(CLI::App& parent)
{
    auto options = std::make_shared<RefineOptions>();
    options->settings.render.spp = 256;
    options->settings.render.seed = 2;
    CLI::App* command = parent.add_subcommand(
        "refine", "Re-render the pixels the denoiser is unsure of at high spp and blend them in");
    command->add_option("--scene", options->scene, "Built-in scene the denoised frames were rendered from");
    command->add_option("--denoised", options->denoised, "Denoised sequence with <layer>.sigma channels");
    command->add_option("-o,--output", options->output, "Output frame sequence (never an input)");
    command->add_option("--layer", options->layer, "Layer to refine (the renderer's DiffInd, any prefix)");
    command->add_option("--frames", options->frames, "Only these frames: 1-48, 30-36, 1,3,7-9");
    command->add_option("--size", options->size, "Image size WIDTHxHEIGHT the frames were rendered at");
    command->add_option("--spp", options->settings.render.spp, "Samples per pixel of the re-render")
        ->check(kAtLeastOne);
    command->add_option("--seed", options->settings.render.seed,
                        "Seed of the re-render (differs from render's default 1 so that the new samples are "
                        "independent of the noisy pass)");
    command->add_option("--max-depth", options->settings.render.max_depth, "Maximum number of bounces")
        ->check(kAtLeastOne);
    auto* threshold = command->add_option(
        "--threshold", options->threshold,
        "Re-render pixels whose sigma / sqrt(value^2 + floor^2) is at least this (largest over R, G, B)");
    command
        ->add_option("--budget", options->budget_percent,
                     "Instead of --threshold: re-render the P % of the shot's pixels with the largest score "
                     "(before dilation; 0 = nothing)")
        ->check(CLI::Range(0.0, 100.0))
        ->excludes(threshold);
    command
        ->add_option("--floor", options->settings.dark_floor,
                     "Dark floor of the score: values below it are judged on an absolute scale")
        ->check(CLI::PositiveNumber);
    command
        ->add_option("--dilate", options->settings.feather.dilation, "Grow the selection by this many pixels")
        ->check(CLI::Range(0, 64));
    command
        ->add_option("--feather", options->settings.feather.feather,
                     "Fade the re-rendered values out over this many more pixels")
        ->check(CLI::Range(0, 64));
    command->add_option("--masks", options->masks,
                        "Also write the masks: channel 'mask' (1 = re-rendered) and 'weight' (blend weight)");
    command->add_option("--json", options->json_path,
                        "Write per-frame and total pixels re-rendered, times and estimated relMSE as JSON");
    add_common_options(*command, options->common);
    add_exr_codec_option(*command, options->exr_codec);
    return {command, [options] { return run_refine(*options); }};
}

} // namespace modestack::app
