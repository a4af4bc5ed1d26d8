// `refine` for any renderer (refine_job.h): the loop of refine() cut in two
// around the render, so that a studio's own renderer re-renders the unsure
// pixels. refine_masks_only() chooses them exactly as refine() does
// (refine::choose_refine_pixels) and writes per frame a mask (EXR: "mask" 1 =
// re-render, "weight" = the exact float blend weight) and, with --windows, one
// JSON of crop windows per frame in the forms renderers take (crop_windows.h).
// refine_blend() reads those weights back and blends the re-rendered layer
// (full frames, or crops whose EXR data window says where they sit, one per
// frame or one per window with {window} in the pattern) with
// refine::blend_refined_frame, the blend and sigma update of refine().
#include "app/command.h"
#include "app/refine_frames.h"
#include "app/refine_job.h"
#include "core/common/error.h"
#include "core/refine/blend.h"
#include "io/frame_header.h"
#include "io/layers.h"
#include "io/mask_image.h"
#include "io/partial_render.h"
#include "io/sequence.h"
#include "io/text_output.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>

namespace modestack::app {
namespace {

double seconds_since(std::chrono::steady_clock::time_point start)
{
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

nlohmann::ordered_json normalised(const refine::NormalisedWindow& window, bool as_corners)
{
    // RenderMan lists x min, x max, y min, y max; USD's NDC boxes list the two corners.
    if (as_corners)
        return {window.min_x, window.min_y, window.max_x, window.max_y};
    return {window.min_x, window.max_x, window.min_y, window.max_y};
}

nlohmann::ordered_json window_json(std::size_t index, const refine::PixelWindow& window, int width,
                                   int height)
{
    const refine::NormalisedWindow border = refine::cycles_border(window, width, height);
    return {
        {"index", index}, // kWindowToken in a --blend pattern
        {"x0", window.x0},
        {"y0", window.y0},
        {"x1", window.x1},
        {"y1", window.y1},
        {"pixels", window.area()},
        {"arnold",
         {{"region_min_x", window.x0},
          {"region_min_y", window.y0},
          {"region_max_x", window.x1 - 1},
          {"region_max_y", window.y1 - 1}}},
        {"renderman_crop_window", normalised(refine::renderman_crop_window(window, width, height), false)},
        {"karma_data_window_ndc", normalised(refine::ndc_data_window(window, width, height), true)},
        {"cycles_border",
         {{"min_x", border.min_x},
          {"max_x", border.max_x},
          {"min_y", border.min_y},
          {"max_y", border.max_y}}}};
}

// The position in R, G, B of each channel of the reader's layer, in the reader's order.
std::vector<int> rgb_positions(const io::SequenceReader& reader)
{
    std::vector<int> positions;
    for (const std::string& name : reader.layers().front().channel_names) {
        std::string layer, component;
        io::split_channel_name(name, layer, component);
        const auto at = std::string("RGB").find(component);
        if (component.size() != 1 || at == std::string::npos)
            throw bad_input(reader.sequence().files.front(),
                            fmt::format("layer {} must have R, G and B channels", layer));
        positions.push_back(static_cast<int>(at));
    }
    return positions;
}

// The re-rendered files of each frame. Without kWindowToken in the pattern, one
// file per frame, each required. With it, the token stands for the window's
// index in --windows (0, 1, ...): every window file that exists, none required
// here (a frame with weighted pixels and no file fails its coverage check).
std::vector<std::vector<std::string>> find_rendered_files(const std::string& pattern,
                                                          const std::vector<int>& frames)
{
    std::vector<std::vector<std::string>> files(frames.size());
    const std::size_t at = pattern.find(kWindowToken);
    if (at == std::string::npos) {
        const io::FrameSequence sequence = io::find_input_sequence(pattern, io::describe_frames(frames));
        for (std::size_t i = 0; i < frames.size(); ++i)
            files[i].push_back(sequence.files[i]);
        return files;
    }
    for (int window = 0;; ++window) {
        std::string window_pattern = pattern;
        window_pattern.replace(at, std::string(kWindowToken).size(), std::to_string(window));
        const std::vector<std::string> names = io::output_sequence(window_pattern, frames).files;
        bool any = false;
        for (std::size_t i = 0; i < frames.size(); ++i)
            if (std::filesystem::exists(names[i])) {
                files[i].push_back(names[i]);
                any = true;
            }
        if (!any)
            return files;
    }
}

// Throws a bad-input error unless every pixel with a weight lies in the data
// window of one of the frame's re-rendered files (`placements`).
void check_coverage(const std::vector<float>& weights, int width,
                    const std::vector<io::PartialRender>& placements, const std::string& pattern, int frame,
                    const std::string& mask_file)
{
    std::int64_t missing = 0;
    std::size_t first = 0;
    for (std::size_t p = 0; p < weights.size(); ++p) {
        if (!(weights[p] > 0))
            continue;
        const int x = static_cast<int>(p % width), y = static_cast<int>(p / width);
        bool held = false;
        for (const io::PartialRender& placement : placements)
            held = held || placement.contains(x, y);
        if (!held && missing++ == 0)
            first = p;
    }
    if (missing == 0)
        return;
    if (placements.empty()) { // only with kWindowToken: name the first window's file
        std::string first_window = pattern;
        first_window.replace(first_window.find(kWindowToken), std::string(kWindowToken).size(), "0");
        throw bad_input(
            io::output_sequence(first_window, {frame}).files.front(),
            fmt::format("missing: the mask {} blends {} pixels of frame {}; render the frame's crop "
                        "windows, or the whole frame",
                        mask_file, missing, frame));
    }
    std::vector<std::string> described;
    for (const io::PartialRender& placement : placements)
        described.push_back(
            fmt::format("{} with data window {}", placement.file,
                        io::describe_window(placement.x0, placement.y0, placement.width, placement.height)));
    throw bad_input(
        placements.front().file,
        fmt::format("the re-render of frame {} ({}) misses {} pixels that the mask {} blends (the "
                    "first at x {}, y {}): render the frame's crop windows, or the whole frame",
                    frame, fmt::join(described, ", "), missing, mask_file, first % width, first / width));
}

} // namespace

RefineMasksResult refine_masks_only(const RefineJob& job, const CommonOptions& context_options)
{
    auto start = std::chrono::steady_clock::now();
    io::FrameSequence input = io::find_input_sequence(job.denoised, job.frames);
    check_sigma_channels(input.files.front(), job.layer);
    io::FrameSequence masks = io::output_sequence(job.masks, input.frames);
    io::SequenceReader reader(input, {job.layer, job.layer + ".sigma"}, job.exr_codec);
    check_colour_layers(reader);
    std::vector<std::string> all_outputs = masks.files;
    if (!job.windows.empty())
        all_outputs.push_back(job.windows);
    io::check_outputs(all_outputs, input.files);

    RunContext context(context_options);
    double seconds_scoring = 0;
    const float threshold = job.selection == RefineSelection::Budget
                                ? budget_threshold(reader, job.budget_percent, job.settings.dark_floor,
                                                   context.progress(), seconds_scoring)
                                : static_cast<float>(job.threshold);
    const int width = reader.width(), height = reader.height();
    const std::size_t pixels = static_cast<std::size_t>(width) * height;
    const std::vector<io::HeaderAttribute> attributes{
        io::HeaderAttribute::of_text("modestack:version", MODESTACK_VERSION),
        io::HeaderAttribute::of_text("modestack:command", command_line()),
        io::HeaderAttribute::of_real("modestack:refine_threshold", threshold),
    };
    RefineMasksResult result;
    std::vector<std::unique_ptr<io::FrameOutput>> outputs;
    LayerAndSigma layer(pixels);
    std::vector<float> weights(pixels);
    std::vector<std::uint8_t> mask(pixels);
    context.progress().begin(
        fmt::format("choosing the pixels to re-render in {} frames", input.frames.size()),
        reader.frame_count());
    for (int i = 0; i < reader.frame_count(); ++i) {
        throw_if_cancelled();
        layer.read(reader, i);
        MaskedFrame frame;
        frame.frame = input.frames[i];
        frame.mask_file = masks.files[i];
        frame.report =
            refine::choose_refine_pixels(width, height, threshold, job.settings, layer.value.data(),
                                         layer.sigma.data(), nullptr, weights.data());
        add_mask_output(outputs, masks.files[i], weights, width, height, attributes);
        for (std::size_t p = 0; p < pixels; ++p)
            mask[p] = weights[p] > 0 ? 1 : 0;
        frame.windows = refine::crop_windows(mask.data(), width, height, job.window_overhead);
        result.pixels_to_render += frame.report.rendered_pixels;
        result.window_count += static_cast<std::int64_t>(frame.windows.size());
        result.window_pixels += refine::windows_cost(frame.windows, 0);
        result.per_frame.push_back(std::move(frame));
        context.progress().advance();
    }
    context.progress().end();
    for (auto& file : outputs)
        file->commit();

    result.input = input.printf_pattern;
    result.masks = masks.printf_pattern;
    result.frames = input.frames;
    result.layer = reader.layers().front().name;
    result.width = width;
    result.height = height;
    result.selection = job.selection;
    result.budget_percent = job.budget_percent;
    result.threshold = threshold;
    result.settings = job.settings;
    result.window_overhead = job.window_overhead;
    result.seconds_total = seconds_since(start);
    if (!job.windows.empty())
        io::write_text_file(job.windows, refine_windows_json(result).dump(2) + "\n");
    return result;
}

nlohmann::ordered_json refine_windows_json(const RefineMasksResult& result)
{
    nlohmann::ordered_json json;
    json["version"] = version_string();
    json["command"] = command_line();
    json["input"] = result.input;
    json["masks"] = result.masks;
    json["frames"] = io::describe_frames(result.frames);
    json["layer"] = result.layer;
    json["width"] = result.width;
    json["height"] = result.height;
    const bool by_budget = result.selection == RefineSelection::Budget;
    json["selection"] = selection_name(result.selection);
    json["budget_percent"] =
        by_budget ? nlohmann::ordered_json(result.budget_percent) : nlohmann::ordered_json();
    json["threshold"] =
        std::isfinite(result.threshold) ? nlohmann::ordered_json(result.threshold) : nlohmann::ordered_json();
    json["floor"] = result.settings.dark_floor;
    json["dilate"] = result.settings.feather.dilation;
    json["feather"] = result.settings.feather.feather;
    json["window_overhead_pixels"] = result.window_overhead;
    json["conventions"] = {
        {"pixels", "x0, y0 inclusive; x1, y1 exclusive; y = 0 at the top row (EXR data window: x0, y0 to "
                   "x1 - 1, y1 - 1)"},
        {"arnold", "options region_min_x, region_min_y, region_max_x, region_max_y: inclusive pixels, y = 0 "
                   "at the top"},
        {"renderman_crop_window", "Ri CropWindow [xmin, xmax, ymin, ymax], 0 to 1, y = 0 at the top"},
        {"karma_data_window_ndc", "RenderSettings dataWindowNDC [xmin, ymin, xmax, ymax], 0 to 1, y = 0 at "
                                  "the bottom"},
        {"cycles_border", "render.border_min_x, border_max_x, border_min_y, border_max_y (use_border, "
                          "use_crop_to_border), 0 to 1, y = 0 at the bottom"}};
    json["pixels_to_render"] = result.pixels_to_render;
    json["percent_to_render"] = result.frames.empty()
                                    ? 0.0
                                    : 100.0 * static_cast<double>(result.pixels_to_render) /
                                          (static_cast<double>(result.width) * result.height *
                                           static_cast<double>(result.frames.size()));
    json["window_count"] = result.window_count;
    json["window_pixels"] = result.window_pixels;
    json["seconds"] = result.seconds_total;
    json["per_frame"] = nlohmann::ordered_json::array();
    for (const MaskedFrame& frame : result.per_frame) {
        nlohmann::ordered_json windows = nlohmann::ordered_json::array();
        for (std::size_t k = 0; k < frame.windows.size(); ++k)
            windows.push_back(window_json(k, frame.windows[k], result.width, result.height));
        json["per_frame"].push_back({{"frame", frame.frame},
                                     {"mask", frame.mask_file},
                                     {"pixels_selected", frame.report.selected_pixels},
                                     {"pixels_to_render", frame.report.rendered_pixels},
                                     {"window_pixels", refine::windows_cost(frame.windows, 0)},
                                     {"windows", windows}});
    }
    return json;
}

void print_masks_summary(const RefineMasksResult& result)
{
    const double total =
        static_cast<double>(result.width) * result.height * static_cast<double>(result.frames.size());
    std::fprintf(stderr,
                 "chose %lld pixels to re-render (%.2f %% of %d frames) in %lld crop windows of %lld pixels "
                 "in all, in %.2f s\n",
                 static_cast<long long>(result.pixels_to_render),
                 total > 0 ? 100.0 * static_cast<double>(result.pixels_to_render) / total : 0.0,
                 static_cast<int>(result.frames.size()), static_cast<long long>(result.window_count),
                 static_cast<long long>(result.window_pixels), result.seconds_total);
}

RefineBlendResult refine_blend(const RefineJob& job, const CommonOptions& context_options)
{
    auto start = std::chrono::steady_clock::now();
    io::FrameSequence input = io::find_input_sequence(job.denoised, job.frames);
    check_sigma_channels(input.files.front(), job.layer);
    const std::string frame_list = io::describe_frames(input.frames);
    io::FrameSequence masks = io::find_input_sequence(job.masks, frame_list);
    const std::vector<std::vector<std::string>> rendered = find_rendered_files(job.blend, input.frames);
    io::FrameSequence output = io::output_sequence(job.output, input.frames);
    io::SequenceReader reader(input, {job.layer, job.layer + ".sigma"}, job.exr_codec);
    check_colour_layers(reader);
    const std::vector<int> rgb = rgb_positions(reader);
    const int width = reader.width(), height = reader.height();
    // Every input before the first output: a wrong file fails the run with nothing written.
    for (std::size_t i = 0; i < input.frames.size(); ++i) {
        std::vector<io::PartialRender> placements;
        for (const std::string& file : rendered[i])
            placements.push_back(
                io::check_partial_render(file, job.blend_layer, job.blend_variance, width, height));
        check_coverage(io::read_mask_weights(masks.files[i], width, height), width, placements, job.blend,
                       input.frames[i], masks.files[i]);
    }
    std::vector<std::string> inputs = input.files;
    inputs.insert(inputs.end(), masks.files.begin(), masks.files.end());
    for (const auto& files : rendered)
        inputs.insert(inputs.end(), files.begin(), files.end());
    io::check_outputs(output.files, inputs);

    RunContext context(context_options);
    const std::size_t pixels = static_cast<std::size_t>(width) * height;
    const std::string weight_channel = reader.layers().front().name + ".refine_weight";
    const std::vector<io::HeaderAttribute> attributes{
        io::HeaderAttribute::of_text("modestack:version", MODESTACK_VERSION),
        io::HeaderAttribute::of_text("modestack:command", command_line()),
        io::HeaderAttribute::of_text("modestack:refine_source", job.blend),
    };
    RefineBlendResult result;
    std::vector<std::unique_ptr<io::FrameOutput>> outputs;
    LayerAndSigma layer(pixels);
    std::vector<float> values(pixels * 3), variances(pixels * 3);
    std::vector<std::uint8_t> filled(pixels);
    std::vector<unsigned char> native;
    double estimated_before = 0, estimated_after = 0;
    context.progress().begin(fmt::format("blending re-rendered pixels into {} frames", input.frames.size()),
                             reader.frame_count());
    for (int i = 0; i < reader.frame_count(); ++i) {
        throw_if_cancelled();
        layer.read(reader, i);
        const std::vector<float> weights = io::read_mask_weights(masks.files[i], width, height);
        BlendedFrame frame;
        frame.frame = input.frames[i];
        frame.sources = rendered[i];
        frame.report.pixels = static_cast<std::int64_t>(pixels);
        // Each weighted pixel from the first file whose data window holds it (crops may overlap).
        std::fill(filled.begin(), filled.end(), 0);
        for (const std::string& file : rendered[i]) {
            const io::PartialRender render =
                io::read_partial_render(file, job.blend_layer, job.blend_variance, width, height);
            for (int y = render.y0; y < render.y0 + render.height; ++y)
                for (int x = render.x0; x < render.x0 + render.width; ++x) {
                    const std::size_t p = static_cast<std::size_t>(y) * width + x;
                    if (!(weights[p] > 0) || filled[p])
                        continue;
                    filled[p] = 1;
                    ++frame.report.rendered_pixels;
                    const std::size_t q =
                        static_cast<std::size_t>(y - render.y0) * render.width + (x - render.x0);
                    for (int c = 0; c < 3; ++c) {
                        values[p * 3 + c] = render.value[q * 3 + rgb[c]];
                        variances[p * 3 + c] = render.variance[q * 3 + rgb[c]];
                    }
                }
        }
        frame.report.estimated_before = refine::estimated_relative_mse(layer.value.data(), layer.sigma.data(),
                                                                       pixels, 3, job.settings.dark_floor);
        refine::blend_refined_frame(weights.data(), values.data(), variances.data(), job.settings.dark_floor,
                                    layer.value.data(), layer.sigma.data(), frame.report);
        layer.store();
        reader.read_native(i, 0, height, native);
        outputs.push_back(std::make_unique<io::FrameOutput>(
            output.files[i], reader, i, std::vector<std::string>{weight_channel}, attributes, job.exr_codec));
        outputs.back()->write_replaced_rows(0, height, native, layer.rows.data(), weights.data());
        result.pixels_blended += frame.report.rendered_pixels;
        estimated_before += frame.report.estimated_before;
        estimated_after += frame.report.estimated_after;
        result.per_frame.push_back(frame);
        context.progress().advance();
    }
    context.progress().end();
    for (auto& file : outputs)
        file->commit();

    const double frames = static_cast<double>(input.frames.size());
    result.input = input.printf_pattern;
    result.masks = masks.printf_pattern;
    result.blend = job.blend;
    result.output = output.printf_pattern;
    result.frames = input.frames;
    result.layer = reader.layers().front().name;
    result.blend_layer = job.blend_layer;
    result.blend_variance = job.blend_variance;
    result.percent_blended =
        100.0 * static_cast<double>(result.pixels_blended) / (frames * static_cast<double>(pixels));
    result.estimated_relmse_before = estimated_before / frames;
    result.estimated_relmse_after = estimated_after / frames;
    result.seconds_total = seconds_since(start);
    return result;
}

nlohmann::ordered_json refine_blend_json(const RefineBlendResult& result)
{
    nlohmann::ordered_json json;
    json["version"] = version_string();
    json["command"] = command_line();
    json["input"] = result.input;
    json["masks"] = result.masks;
    json["blend"] = result.blend;
    json["output"] = result.output;
    json["frames"] = io::describe_frames(result.frames);
    json["layer"] = result.layer;
    json["blend_layer"] = result.blend_layer;
    json["blend_variance"] = result.blend_variance;
    json["pixels_blended"] = result.pixels_blended;
    json["percent_blended"] = result.percent_blended;
    json["estimated_relmse_before"] = result.estimated_relmse_before;
    json["estimated_relmse_after"] = result.estimated_relmse_after;
    json["seconds"] = result.seconds_total;
    json["per_frame"] = nlohmann::ordered_json::array();
    for (const BlendedFrame& frame : result.per_frame)
        json["per_frame"].push_back({{"frame", frame.frame},
                                     {"sources", frame.sources},
                                     {"pixels_blended", frame.report.rendered_pixels},
                                     {"estimated_relmse_before", frame.report.estimated_before},
                                     {"estimated_relmse_after", frame.report.estimated_after}});
    return json;
}

void print_blend_summary(const RefineBlendResult& result)
{
    std::fprintf(
        stderr,
        "blended %lld re-rendered pixels (%.2f %% of %d frames) in %.2f s; estimated relMSE %.4g -> %.4g\n",
        static_cast<long long>(result.pixels_blended), result.percent_blended,
        static_cast<int>(result.frames.size()), result.seconds_total, result.estimated_relmse_before,
        result.estimated_relmse_after);
}

} // namespace modestack::app
