// `modestack run`: the main job end to end (issue 6, README command one).
// Renders the noisy pass of a built-in scene, denoises its indirect and its
// direct layer in one run (each on its own modes, auto rank), re-renders the
// indirect pixels where that pays (refine --by-gain, unless --budget or
// --threshold is given) at high spp, composites the final beauty
// = DiffCol × (DiffDir + DiffInd) + Emit ([0017]) and writes a summary and a
// contact sheet. Each stage is the library call behind the subcommand a user
// would type (render_job.h, denoise_job.h, refine_job.h), given the options
// the user would type, so `run` and the stages by hand give the same files; run
// reads what it reports from the results they return. With --reference-spp it
// also renders a reference and measures relMSE, equivalent spp and the
// equal-quality speed-up (docs/design.md, "How we measure quality").
// The contact sheet goes through the OCIO config's display/view.
#include "app/command.h"
#include "app/denoise_job.h"
#include "app/refine_job.h"
#include "app/render_job.h"
#include "app/report/html_report.h"
#include "app/run_composite.h"
#include "app/run_context.h"
#include "app/run_quality.h"
#include "app/run_report.h"
#include "app/run_sheet.h"
#include "core/common/error.h"
#include "core/scene/builtin_scenes.h"
#include "io/color_management.h"
#include "io/frame_output.h"
#include "io/sequence.h"
#include "io/sequence_reader.h"
#include "io/text_output.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <chrono>
#include <filesystem>
#include <optional>

namespace modestack::app {
namespace {

namespace stdfs = std::filesystem;
using Json = nlohmann::ordered_json;

struct RunOptions {
    std::string scene = "orbit";
    std::string directory = "out/run";
    std::string size = "320x240";
    std::string frames;
    int spp = 8;
    int refine_spp = 256;
    // Refine by gain unless one of these is given (docs/design.md, "Which
    // pixels refine re-renders"): at a few spp the samples pay more in the noisy
    // pass than in re-rendered pixels, and the gain rule says where they do not.
    double budget_percent = -1; ///< >= 0: re-render this % of the shot's pixels
    double threshold = -1;      ///< > 0: re-render pixels whose relative sigma is at least this
    int reference_spp = 0;
    double exposure = 0.0;
    std::string display;
    std::string view;
    std::string ocio_config;
    CommonOptions common;
};

// Writes a stage's --json summary into run's json/ directory.
void write_json(const std::string& path, const Json& json) { io::write_text_file(path, json.dump(2) + "\n"); }

double seconds_since(std::chrono::steady_clock::time_point start)
{
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

std::string sequence_path(const RunOptions& options, const std::string& kind)
{
    return (stdfs::path(options.directory) / kind / (options.scene + ".####.exr")).string();
}

// The render stage's options: the shot as run renders it.
RenderCommandOptions render_options(const RunOptions& options, const std::string& output, int spp, int seed,
                                    const std::string& frame_range)
{
    RenderCommandOptions render;
    render.scene = options.scene;
    render.size = options.size;
    render.frames = frame_range;
    render.output = output;
    render.render.spp = spp;
    render.render.seed = static_cast<std::uint64_t>(seed);
    return render;
}

int run_run(const RunOptions& options)
{
    auto start = std::chrono::steady_clock::now();
    const scene::SceneInfo* info = nullptr;
    for (const auto& candidate : scene::builtin_scenes())
        if (candidate.name == options.scene)
            info = &candidate;
    if (!info)
        scene::make_builtin_scene(options.scene, 1); // throws the error listing the scenes
    std::vector<int> frames = io::parse_frame_range(
        options.frames.empty() ? fmt::format("{}-{}", info->first_frame, info->last_frame) : options.frames);
    if (frames.size() < kMinimumShotFrames)
        throw usage_error("--frames: " + too_few_frames(frames.size()));
    const std::string frame_range = io::describe_frames(frames);
    // Checked before any work: a bad config, display or view fails at once.
    const io::ColorConfig color_config(io::locate_color_config(options.ocio_config));
    const io::DisplayConverter display(color_config, options.display, options.view, options.exposure);
    const stdfs::path directory(options.directory);
    const stdfs::path json_directory = directory / "json";
    std::error_code directory_error;
    stdfs::create_directories(json_directory, directory_error);
    if (directory_error)
        throw bad_input(options.directory,
                        fmt::format("cannot create output directory ({})", directory_error.message()));
    const std::string noisy = sequence_path(options, "noisy"), denoised = sequence_path(options, "denoised"),
                      refined = sequence_path(options, "refined"),
                      final_path = sequence_path(options, "final"), masks = sequence_path(options, "masks"),
                      reference = sequence_path(options, "reference");
    auto json_file = [&](const char* name) { return (json_directory / name).string(); };

    Json seconds;
    auto stage_start = std::chrono::steady_clock::now();
    const RenderResult noisy_render =
        render(make_render_job(render_options(options, noisy, options.spp, 1, frame_range)), options.common);
    write_json(json_file("render.json"), render_json(noisy_render));
    seconds["render"] = seconds_since(stage_start);

    stage_start = std::chrono::steady_clock::now();
    // The renderer writes scene-linear Rec.709, which the denoiser reads as such.
    const std::string report_path = (directory / "report.html").string();
    // The indirect and the direct light, each on its own modes (the direct
    // light left at 4 spp kept the final beauty's shadows noisy; the per-pixel
    // estimator choice keeps it no worse than its input where its shadows
    // move), in one run: the shot is read and written once. DiffInd is
    // whitened by its DiffIndVar and DiffDir, which has no variance layer, is
    // not, so the files have the bits of the two layers denoised one after the
    // other. DiffInd first: the report page and the summary's rank are its.
    DenoiseCommandOptions denoise_options;
    denoise_options.input = noisy;
    denoise_options.frames = frame_range;
    denoise_options.layers = {"DiffInd", "DiffDir"};
    denoise_options.output = denoised;
    denoise_options.ocio_config = color_config.path();
    denoise_options.no_update_beauty = true; // run composites the final beauty from the passes itself
    denoise_options.report_path = report_path;
    // The stage writes its page already; run completes it below (with refine and the reference).
    DenoiseResult denoise_result = denoise(make_denoise_job(denoise_options, nullptr), options.common);
    write_json(json_file("denoise.json"), denoise_json(denoise_result));
    if (!options.common.quiet)
        print_denoise_summary(denoise_result);
    seconds["denoise"] = seconds_since(stage_start);

    stage_start = std::chrono::steady_clock::now();
    RefineCommandOptions refine_options;
    refine_options.scene = options.scene;
    refine_options.size = options.size;
    refine_options.frames = frame_range;
    refine_options.denoised = denoised;
    refine_options.output = refined;
    refine_options.masks = masks;
    refine_options.settings.render.spp = options.refine_spp;
    if (options.threshold > 0)
        refine_options.threshold = options.threshold;
    else if (options.budget_percent >= 0)
        refine_options.budget_percent = options.budget_percent;
    else
        refine_options.by_gain = true;
    const RefineResult refine_result = refine(make_refine_job(refine_options), options.common);
    write_json(json_file("refine.json"), refine_json(refine_result));
    if (!options.common.quiet)
        print_refine_summary(refine_result);
    seconds["refine"] = seconds_since(stage_start);

    RunContext context(options.common);
    stage_start = std::chrono::steady_clock::now();
    io::FrameSequence refined_sequence = io::find_input_sequence(refined, frame_range);
    io::FrameSequence final_sequence = io::output_sequence(final_path, frames);
    io::check_outputs(final_sequence.files, refined_sequence.files);
    write_final(refined_sequence, final_sequence, context.progress());
    seconds["composite"] = seconds_since(stage_start);
    double our_seconds = seconds["render"].get<double>() + seconds["denoise"].get<double>() +
                         seconds["refine"].get<double>() + seconds["composite"].get<double>();
    seconds["total"] = our_seconds;

    std::optional<RenderResult> reference_render;
    if (options.reference_spp > 0) {
        stage_start = std::chrono::steady_clock::now();
        reference_render = render(
            make_render_job(render_options(options, reference, options.reference_spp, 3, frame_range)),
            options.common);
        write_json(json_file("reference.json"), render_json(*reference_render));
        seconds["reference"] = seconds_since(stage_start);
    }

    const int kept_modes = denoise_result.report.rank_decision.kept_modes;
    Json summary;
    summary["version"] = version_string();
    summary["command"] = command_line();
    summary["scene"] = options.scene;
    summary["frames"] = frame_range;
    summary["size"] = options.size;
    summary["spp"] = options.spp;
    summary["refine_spp"] = options.refine_spp;
    summary["rank"] = kept_modes;
    summary["rank_rule"] = denoise_result.report.rank_decision.rule;
    summary["direct_rank"] = denoise_result.report.layers.at(1).rank_decision.kept_modes;
    const bool by_budget = refine_result.selection == RefineSelection::Budget;
    summary["refine_selection"] = selection_name(refine_result.selection);
    summary["refine_budget_percent"] = by_budget ? Json(refine_result.budget_percent) : Json();
    summary["refine_threshold"] = std::isfinite(refine_result.threshold) ? Json(refine_result.threshold) : Json();
    summary["pixels_refined"] = refine_result.pixels_rendered;
    summary["percent_pixels_refined"] = refine_result.percent_rendered;
    summary["seconds"] = seconds;
    summary["outputs"] = {{"noisy", noisy},
                          {"denoised", denoised},
                          {"refined", refined},
                          {"final", final_path},
                          {"masks", masks},
                          {"contact_sheet", (directory / "contact_sheet.png").string()},
                          {"report", report_path}};

    // Measurements against the reference, and the contact sheet.
    RunSequences sequences{io::find_input_sequence(noisy, frame_range), io::find_input_sequence(denoised, frame_range),
                           final_sequence, std::nullopt};
    if (reference_render)
        sequences.reference = io::find_input_sequence(reference, frame_range);
    const RunMeasurements measured = measure_and_write_sheet(sequences, frames, info->highlight_frames, display,
                                                             (directory / "contact_sheet.png").string());
    summary["contact_sheet"] = {{"frames", measured.shown_frames},
                                {"columns", reference_render
                                                ? Json::array({"noisy", "denoised", "refined", "reference"})
                                                : Json::array({"noisy", "denoised", "refined"})},
                                {"ocio_config", color_config.path()},
                                {"ocio_config_from", io::describe(color_config.source())},
                                {"display", display.display()},
                                {"view", display.view()},
                                {"exposure", options.exposure}};

    if (reference_render)
        summary["quality"] =
            quality_summary(info->highlight_frames, frames, measured.errors, seconds,
                            {options.spp, noisy_render.render_seconds},
                            {options.reference_spp, reference_render->render_seconds});
    if (denoise_result.report_page) {
        const io::SequenceReader final_indirect(final_sequence, {"DiffInd"});
        complete_report(*denoise_result.report_page, options.scene, final_indirect,
                        io::find_input_sequence(masks, frame_range), measured.errors, seconds);
        app::report::write_report(report_path, *denoise_result.report_page);
    }
    summary["seconds"]["wall"] = seconds_since(start);
    io::write_text_file((directory / "summary.json").string(), summary.dump(2) + "\n");
    if (!options.common.quiet) {
        std::fprintf(stderr,
                     "run: %s, %zu frames, N = %d modes, %.2f %% of pixels refined, %.1f s (render %.1f, "
                     "denoise %.1f, refine %.1f, composite %.1f)\n",
                     options.scene.c_str(), frames.size(), kept_modes, refine_result.percent_rendered,
                     our_seconds, seconds["render"].get<double>(), seconds["denoise"].get<double>(),
                     seconds["refine"].get<double>(), seconds["composite"].get<double>());
        std::fprintf(stderr, "run: results in %s (summary.json, contact_sheet.png, final/, refined/, ...)\n",
                     options.directory.c_str());
    }
    return 0;
}

} // namespace

Subcommand add_run_command(CLI::App& parent)
{
    auto options = std::make_shared<RunOptions>();
    CLI::App* command = parent.add_subcommand(
        "run",
        "The main job: render the noisy pass, denoise its indirect and direct light, refine, composite, "
        "summarize");
    command->add_option("--scene", options->scene, "Built-in scene (see render --scene list)");
    command->add_option("-o,--output", options->directory,
                        "Output directory: noisy/, denoised/, refined/, final/, masks/, summary.json, "
                        "contact_sheet.png");
    command->add_option("--size", options->size, "Image size WIDTHxHEIGHT");
    command->add_option("--frames", options->frames, "Frames (default: all of the scene's frames)");
    command->add_option("--spp", options->spp, "Samples per pixel of the noisy pass")
        ->check(CLI::PositiveNumber);
    command->add_option("--refine-spp", options->refine_spp, "Samples per pixel of the re-rendered pixels")
        ->check(CLI::PositiveNumber);
    auto* budget = command
                       ->add_option("--budget", options->budget_percent,
                                    "Instead of by gain: re-render this % of the shot's pixels (the most "
                                    "unsure ones)")
                       ->check(CLI::Range(0.0, 100.0))
                       ->default_str("");
    auto* threshold =
        command
            ->add_option("--threshold", options->threshold,
                         "Instead of by gain: re-render pixels whose relative sigma is at least this")
            ->check(CLI::PositiveNumber)
            ->default_str("")
            ->excludes(budget);
    // The default since 2026-12-05; the flag stays for the scripts that name it.
    command
        ->add_flag("--by-gain",
                   "The default: refine's --by-gain (re-render where that removes more error than the same "
                   "samples spread over the shot)")
        ->excludes(budget)
        ->excludes(threshold);
    command
        ->add_option("--reference-spp", options->reference_spp,
                     "Also render a reference at this spp and measure relMSE, equivalent spp and speed-up "
                     "(0 = no reference)")
        ->check(CLI::NonNegativeNumber);
    command->add_option("--exposure", options->exposure,
                        "Exposure of the contact sheet, in stops (scene-linear, before the display/view)");
    command->add_option("--display", options->display,
                        "OCIO display of the contact sheet (default: the config's default display)");
    command->add_option("--view", options->view,
                        "OCIO view of the contact sheet (default: the display's default)");
    command->add_option("--ocio-config", options->ocio_config,
                        "OpenColorIO config file; wins over $OCIO, which wins over the config shipped with "
                        "modestack");
    add_common_options(*command, options->common);
    return {command, [options] { return run_run(*options); }};
}

} // namespace modestack::app
