// `modestack refine --scene NAME --denoised SEQ -o SEQ`: the command line of
// re-rendering what the denoiser is unsure of. Parses the options, checks them
// into a RefineJob and calls refine() (app/refine_job.h), then writes the
// --json summary and prints one line.
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
    RefineResult result = refine(make_refine_job(command.options), command.common);
    if (!command.json_path.empty())
        io::write_text_file(command.json_path, refine_json(result).dump(2) + "\n");
    if (!command.common.quiet)
        print_refine_summary(result);
    return 0;
}

} // namespace

Subcommand add_refine_command(CLI::App& parent)
{
    auto command_options = std::make_shared<RefineCommand>();
    RefineCommandOptions* options = &command_options->options;
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
    command->add_option("--json", command_options->json_path,
                        "Write per-frame and total pixels re-rendered, times and estimated relMSE as JSON");
    add_exr_codec_option(*command, options->exr_codec);
    add_common_options(*command, command_options->common);
    return {command, [command_options] { return run_refine(*command_options); }};
}

} // namespace modestack::app
