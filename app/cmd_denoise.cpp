// `modestack denoise SEQ -o SEQ`: the command line of the temporal low-rank
// denoiser. Parses the options, checks them into a DenoiseJob and calls
// denoise() (app/denoise_job.h), then writes the --json summary and prints the
// summary lines; under mpirun each rank runs the farm stages (app/mpi_job.h).
#include "app/command.h"
#include "app/exr_codec_option.h"
#include "app/denoise_job.h"
#include "app/mpi_job.h"
#include "app/run_context.h"
#include "core/common/error.h"
#include "io/text_output.h"

namespace modestack::app {
namespace {

struct DenoiseCommand {
    DenoiseCommandOptions options;
    std::string json_path;
    CommonOptions common;
    const CLI::App* command = nullptr;  ///< for the fingerprint of --stage
};

int run_denoise(const DenoiseCommand& command)
{
    DenoiseResult result = denoise(make_denoise_job(command.options, command.command), command.common);
    if (result.nothing_to_do)
        return 0;
    if (!command.json_path.empty())
        io::write_text_file(command.json_path, denoise_json(result).dump(2) + "\n");
    if (!command.common.quiet)
        print_denoise_summary(result);
    return 0;
}

}  // namespace

Subcommand add_denoise_command(CLI::App& parent)
{
    auto command_options = std::make_shared<DenoiseCommand>();
    DenoiseCommandOptions* options = &command_options->options;
    CLI::App* command = parent.add_subcommand(
        "denoise", "Denoise the selected layers of an EXR sequence with its temporal low-rank modes");
    command
        ->add_option("SEQ", options->input,
                     "Input frame sequence: name.####.exr, name.%04d.exr, name.%d.exr (unpadded), name.@.exr")
        ->required();
    command->add_option("-o,--output", options->output,
                        "Output frame sequence (never an input); with --stage stats or solve, the task's file")
        ->required();
    command->add_option("--layer", options->layers,
                        "Layer to denoise: NAME.R/G/B or <prefix>.NAME.<ch> (Cycles DiffInd); repeatable. "
                        "Default: the only RGB layer")
        ->allow_extra_args(false);  // one value per --layer, so that `--layer DiffInd in.####.exr` works
    command->add_flag("--joint", options->joint,
                      "With several --layer: denoise them on one shared set of modes and one N (layers lit "
                      "alike); default: each layer on its own modes and N, in one pass over the files");
    command->add_option("--rank", options->rank, "Number of modes N, or auto to let --rank-rule choose");
    command->add_option("--rank-rule", options->rank_rule,
                        "How auto chooses N with --no-mode-filter: press (cross-validation), variance (the seed's "
                        "rule), noise-floor (Gavish-Donoho)");
    command->add_option("--method", options->method, "Solver: auto, gram (exact F x F eigenproblem) or rsvd "
                                                      "(randomized SVD)");
    command->add_option("--max-memory", options->max_memory,
                        "Memory of the whole process (512M, 2G; default auto: a quarter of the machine's or "
                        "container's): the shot is kept if it fits in what the program and open files leave, "
                        "else streamed in bands");
    command->add_option("--frames", options->frames,
                        "Only these frames: 1-48, 1001-1100, 1-100x2, 1,3,7-9; with --stage write, the frames of "
                        "the solve file's shot to write (a range or I/K)");
    command->add_option("--json", command_options->json_path, "Write a JSON summary: N and why, spectrum, counts, timings");
    command->add_option("--save-modes", options->save_modes,
                        "Write the spatial modes (mode.NN.exr) and temporal weights (CSV, JSON) to this directory");
    command->add_option("--report", options->report_path,
                        "Write one self-contained HTML report (opens offline; images embedded as PNG data: URIs): "
                        "spectrum and rank reasoning, temporal weights, spatial modes, a rank slider, "
                        "noisy/denoised/sigma side by side with zoom and exposure, per-frame error, counts, timings");
    command->add_flag("--no-firefly-clamp", options->no_firefly_clamp,
                      "Keep fireflies as they are (default: clamp them, spreading their energy over the pixel's "
                      "frames)");
    command
        ->add_option(
            "--firefly-k", options->firefly_k,
            "Firefly threshold: temporal median + k x 1.4826 x MAD of the pixel (with --frame-noise "
            "measured, scaled to each frame's noise level), raised by light its row neighbours share in "
            "that frame")
        ->check(CLI::PositiveNumber);
    command->add_option("--sigma-radius", options->sigma_radius,
                        "Spatial pooling radius of sigma, in pixels (0 or more)");
    command->add_flag("--mode-filter", options->mode_filter,
                      "Filter the spatial modes in space before the rebuild (the default): per mode, the width (and "
                      "edge-aware guided filter from the first mode) with the lowest SURE risk; with --rank auto, N "
                      "is the number of filtered modes that lowers the estimated error most");
    command->add_flag("--no-mode-filter", options->no_mode_filter,
                      "Rebuild from the unfiltered modes; --rank auto then uses --rank-rule");
    command->add_option("--mode-filter-modes", options->mode_filter_modes,
                        "Modes the mode filter surveys (at most F - 2)")
        ->check(CLI::PositiveNumber);
    command->add_option("--mode-filter-widths", options->mode_filter_widths,
                        "Gaussian widths (pixels) the mode filter tries, comma-separated; no filter is always tried")
        ->delimiter(',')
        ->allow_extra_args(false)
        ->check(CLI::Range(0.1, 16.0));
    command->add_option("--rank-map", options->rank_map,
                        "Let the number of modes vary per pixel (fractional: blends N and N + 1) by the local "
                        "signal of each filtered mode against its noise, and write the map to this EXR "
                        "(channel 'rank'); needs the mode filter");
    command
        ->add_option(
            "--mode-filter-guides", options->mode_filter_guides,
            "Features that may guide the mode filter's edges: auto (default: those the input has, under "
            "its renderer's names: DiffCol/Denoising Albedo, Normal, Depth for Cycles, diffuse_albedo, N, "
            "Z for Arnold, ...), none, or a list of albedo, normal, depth, each of which must be found "
            "(else exit 2); SURE decides per mode whether they help")
        ->delimiter(',')
        ->allow_extra_args(false);
    command->add_option(
        "--renderer", options->renderer,
        "Whose AOV names to look for guides and variance under: auto (default: detected from the "
        "first frame's header attributes and layers) or a renderer of the conventions table: "
        "modestack, cycles, arnold, renderman, karma, vray, redshift");
    command->add_option("--conventions", options->conventions,
                        "Renderer conventions table (JSON) to use instead of the one shipped with modestack "
                        "(share/modestack/conventions.json; man page, RENDERER CONVENTIONS)");
    command->add_flag(
        "--single-part", options->single_part,
        "Write a multi-part input's outputs as single-part files, every channel named by its layer "
        "(default: the input's parts, names and headers, each sigma in its layer's part)");
    command
        ->add_option("--compression", options->compression,
                     "Compression of the outputs: none, rle, zips, zip, piz, pxr24, b44, b44a, dwaa, dwab "
                     "(dwaa:45: with a level). Default: the input's (per part) if lossless (none, rle, zips, "
                     "zip, piz), else zip, so that no channel passed through is degraded; a lossy one given "
                     "here applies to every channel")
        ->option_text("NAME");
    command
        ->add_option("--data-type", options->data_type,
                     "Pixel type of the denoised channels and their sigma: half or float (default: the "
                     "input's); the other channels keep theirs")
        ->option_text("half|float");
    command->add_flag("--only-denoised", options->only_denoised,
                      "Write only the denoised layers and their sigma (and the beauty and its sigma when "
                      "--update-beauty rewrites it), no other channel; a multi-part input keeps only the "
                      "parts that still hold channels");
    command->add_flag(
        "--update-beauty", options->update_beauty,
        "Keep the beauty in step with the denoised layers: beauty + sum of colour x (denoised - "
        "noisy), alpha untouched, and its sigma <beauty>.sigma (default: on when the renderer "
        "conventions compose the beauty of the denoised layers; else off, and --json says why)");
    command->add_flag("--no-update-beauty", options->no_update_beauty,
                      "Copy the beauty untouched, like every channel that is not denoised");
    command->add_flag("--skip-existing", options->skip_existing,
                      "Do not rewrite output frames that exist already (farm re-runs)");
    command->add_option("--colorspace", options->colorspace,
                        "OCIO colour space of the input (name, alias or role), instead of what the files record "
                        "(EXR: scene-linear unless their chromaticities say otherwise). A non-linear space is "
                        "denoised in the config's scene_linear space and written back in its own; sigma stays in "
                        "scene-linear units");
    command->add_option("--ocio-config", options->ocio_config,
                        "OpenColorIO config file; wins over $OCIO, which wins over the config shipped with "
                        "modestack");
    command->add_option("--object-space", options->object_space,
                        "Denoise in object space, for moving cameras and objects: the points sequence render "
                        "--points baked (same frames) is denoised as points x frames with the same solver and rank "
                        "rule, filtered over the surfaces instead of the mode filter (SURE width in lattice spacings; "
                        "--no-mode-filter: off), and each frame's layer is rebuilt from the points its PointLookup "
                        "layer names");
    add_exr_codec_option(*command, options->exr_codec);
    add_method_options(*command, options->method_options);
    add_stage_options(*command, options->stage);
    add_common_options(*command, command_options->common);
    command_options->command = command;
    return {command, [command_options] {
                const DenoiseCommand& given = *command_options;
                if (!started_by_mpirun())
                    return run_denoise(given);
                if (!given.options.stage.stage.empty())
                    throw usage_error("--stage is for farm tasks, one process each: under mpirun the ranks run "
                                      "every stage themselves");
                if (given.options.layers.size() > 1 && !given.options.joint)
                    throw usage_error(
                        "under mpirun the ranks run the farm stages, which hold one set of modes: "
                        "with several --layer add --joint, or run one layer per job");
                // mpirun -n K: each rank runs the farm stages on its share (mpi_job.h).
                return run_mpi_denoise(given.options.frames, [&](const StageOptions& stage,
                                                                 const std::string& frames, bool lead) {
                    DenoiseCommand task = given;
                    task.options.stage = stage;
                    task.options.frames = frames;
                    task.common.quiet = given.common.quiet || !lead;
                    if (!lead || stage.stage != "write")
                        task.json_path.clear();
                    return run_denoise(task);
                });
            }};
}

}  // namespace modestack::app
