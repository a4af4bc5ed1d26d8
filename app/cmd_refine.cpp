// `modestack refine --scene NAME --denoised SEQ -o SEQ`: the command line of
// re-rendering what the denoiser is unsure of; with --masks-only and --blend,
// the two halves of that loop around another renderer. Parses the options,
// checks them into a RefineJob and calls refine(), refine_masks_only() or
// refine_blend() (app/refine_job.h), then writes the --json summary and prints
// one line.
#include "app/command.h"
#include "app/exr_codec_option.h"
#include "app/refine_job.h"
#include "app/run_context.h"
#include "io/text_output.h"

namespace modestack::app {
namespace {


struct RefineCommand {
    RefineCommandOptions options;
    std::string json_path;
    CommonOptions common;
};

int run_refine(const RefineCommand& command)
{
    const RefineJob job = make_refine_job(command.options);
    if (job.mode == RefineMode::MasksOnly) {
        RefineMasksResult result = refine_masks_only(job, command.common);
        if (!command.json_path.empty())
            io::write_text_file(command.json_path, refine_windows_json(result).dump(2) + "\n");
        if (!command.common.quiet)
            print_masks_summary(result);
    } else if (job.mode == RefineMode::Blend) {
        RefineBlendResult result = refine_blend(job, command.common);
        if (!command.json_path.empty())
            io::write_text_file(command.json_path, refine_blend_json(result).dump(2) + "\n");
        if (!command.common.quiet)
            print_blend_summary(result);
    } else {
        RefineResult result = refine(job, command.common);
        if (!command.json_path.empty())
            io::write_text_file(command.json_path, refine_json(result).dump(2) + "\n");
        if (!command.common.quiet)
            print_refine_summary(result);
    }
    return 0;
}

} // namespace

Subcommand add_refine_command(CLI::App& parent)
{
    auto command_options = std::make_shared<RefineCommand>();
    RefineCommandOptions* options = &command_options->options;
    CLI::App* command = parent.add_subcommand(
        "refine", "Re-render the pixels the denoiser is unsure of at high spp and blend them in");
    command->add_option(
        "--scene", options->scene,
        "Built-in scene the denoised frames were rendered from (not with --masks-only or --blend)");
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
    auto* threshold =
        command
            ->add_option(
                "--threshold", options->threshold,
                "Re-render pixels whose sigma / sqrt(value^2 + floor^2) is at least this (largest over "
                "R, G, B)")
            ->default_str("0.2")
            ->check(CLI::PositiveNumber);
    command->add_flag(
        "--by-gain", options->by_gain,
        "Instead of --threshold: re-render the pixels where that removes more relMSE (by sigma) "
        "than the same samples spread over the shot as more spp would (needs <layer>Var and the "
        "input's spp, as modestack's renders write them)");
    command
        ->add_option(
            "--budget", options->budget_percent,
            "Instead of --threshold: re-render the P % of the shot's pixels with the largest relative "
            "sigma (before dilation; 0 = nothing)")
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
    command->add_option(
        "--masks", options->masks,
        "Mask sequence: channel 'mask' (1 = re-rendered, half) and 'weight' (blend weight, float); "
        "written, or with --blend read");
    command->add_flag("--masks-only", options->masks_only,
                      "Another renderer re-renders: only choose the pixels (same rule and options) and write "
                      "--masks and --windows; no --scene, no -o");
    command->add_option(
        "--windows", options->windows,
        "With --masks-only: write the crop windows of every frame as JSON (pixels, Arnold region, "
        "RenderMan crop window, Karma dataWindowNDC, Cycles border)");
    command
        ->add_option("--window-overhead", options->window_overhead,
                     "What one more crop window costs, in pixels: two windows merge while their bounding box "
                     "is smaller than their areas plus this")
        ->default_val(kDefaultWindowOverheadPixels);
    command->add_option(
        "--blend", options->blend,
        "Blend this re-rendered sequence (full frames, or crops placed by their EXR data window; "
        "{window} in the pattern = one file per crop window, its index in --windows) into --denoised by the "
        "weights of --masks; writes -o");
    command->add_option("--blend-layer", options->blend_layer,
                        "With --blend: the re-rendered layer (default: --layer)");
    command->add_option(
        "--blend-variance", options->blend_variance,
        "With --blend: its per-pixel variance of the mean (default: the layer's name + Var, as "
        "Cycles' and modestack's DiffIndVar)");
    command->add_option("--json", command_options->json_path,
                        "Write per-frame and total pixels re-rendered, times and estimated relMSE as JSON");
    add_exr_codec_option(*command, options->exr_codec);
    add_common_options(*command, command_options->common);
    return {command, [command_options] { return run_refine(*command_options); }};
}

} // namespace modestack::app
