// `modestack render --scene NAME|FILE.gltf -o SEQ`: the command line of the
// companion path tracer. Parses the options, checks them into a RenderJob and
// calls render() (app/render_job.h), then writes the --json summary.
#include "app/command.h"
#include "app/render_job.h"
#include "app/run_context.h"
#include "io/text_output.h"

namespace modestack::app {
namespace {


struct RenderCommand {
    RenderCommandOptions options;
    std::string json_path;
    CommonOptions common;
};

int run_render(const RenderCommand& command)
{
    if (command.options.scene == "list") {
        list_scenes();
        return 0;
    }
    RenderResult result = render(make_render_job(command.options), command.common);
    if (!result.nothing_to_do && !command.json_path.empty())
        io::write_text_file(command.json_path, render_json(result).dump(2) + "\n");
    return 0;
}

}  // namespace

Subcommand add_render_command(CLI::App& parent)
{
    auto command_options = std::make_shared<RenderCommand>();
    RenderCommandOptions* options = &command_options->options;
    CLI::App* command = parent.add_subcommand(
        "render",
        "Render a built-in animated scene or a glTF 2.0 file with the path tracer (one multi-layer EXR per frame)");
    command->add_option(
        "--scene", options->scene,
        "Built-in scene: static, orbit, switch, spin, flythrough, sweep, cross (list: print them), or a glTF "
        "2.0 file FILE.gltf|FILE.glb (meshes, animation, first camera, KHR_lights_punctual; what is "
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
    command->add_option("--json", command_options->json_path, "Write per-frame times, paths/s and rays/s as JSON");
    command->add_flag("--skip-existing", options->skip_existing,
                      "Do not render frames whose output exists already (farm re-runs; outputs appear only "
                      "when complete)");
    add_common_options(*command, command_options->common);
    return {command, [command_options] { return run_render(*command_options); }};
}

}  // namespace modestack::app
