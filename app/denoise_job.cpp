// `modestack denoise` as a library call (denoise_job.h): the temporal low-rank
// denoiser on an EXR sequence. The validation step checks every option before
// any work; denoise() checks the inputs and outputs, runs the streaming engine
// (core/denoise), writes each output frame atomically with its sigma channels
// and provenance; denoise_json() writes the summary. Inputs that are not
// scene-linear are converted for the engine and back on output
// (app/color_adapters.h).
#include "app/denoise_job.h"

#include "app/beauty_update.h"
#include "app/color_adapters.h"
#include "app/command.h"
#include "app/memory_budget.h"
#include "app/renderer_detection.h"
#include "app/report/denoise_report.h"
#include "app/report/html_report.h"
#include "app/sequence_adapters.h"
#include "core/common/error.h"
#include "core/denoise/feature_guide.h"
#include "io/frame_header.h"
#include "io/sequence.h"
#include "io/sequence_reader.h"
#include "io/text_output.h"

#include <fmt/format.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <sys/resource.h>

namespace modestack::app {
namespace {

// --mode-filter-guides: auto (every feature the input has), none, or a list.
std::vector<denoise::Auxiliary> parse_feature_guides(const std::vector<std::string>& names)
{
    using denoise::Auxiliary;
    if (names.size() == 1 && names[0] == "auto")
        return {Auxiliary::Albedo, Auxiliary::Normal, Auxiliary::Depth};
    if (names.size() == 1 && names[0] == "none")
        return {};
    std::vector<Auxiliary> kinds;
    for (const std::string& name : names) {
        Auxiliary kind;
        if (name == "albedo")
            kind = Auxiliary::Albedo;
        else if (name == "normal")
            kind = Auxiliary::Normal;
        else if (name == "depth")
            kind = Auxiliary::Depth;
        else
            throw usage_error(fmt::format("--mode-filter-guides '{}' is not one of auto, none, albedo, normal, depth",
                                          name));
        if (std::find(kinds.begin(), kinds.end(), kind) != kinds.end())
            throw usage_error(fmt::format("--mode-filter-guides names '{}' twice", name));
        kinds.push_back(kind);
    }
    return kinds;
}

denoise::Settings make_settings(const DenoiseCommandOptions& options)
{
    denoise::Settings settings;
    settings.solver = denoise::parse_solver(options.method);
    if (options.rank == "auto") {
        settings.rank_rule.rule = lowrank::parse_rank_rule(options.rank_rule);
        if (settings.rank_rule.rule == lowrank::RankRule::Fixed)
            throw usage_error("--rank-rule fixed needs a number: use --rank N");
    } else {
        try {
            size_t used = 0;
            settings.rank_rule.fixed_modes = std::stoi(options.rank, &used);
            if (used != options.rank.size())
                throw std::invalid_argument("trailing characters");
        } catch (const std::exception&) {
            throw usage_error(fmt::format("--rank '{}': write auto or a number of modes", options.rank));
        }
        settings.rank_rule.rule = lowrank::RankRule::Fixed;
        if (settings.rank_rule.fixed_modes < 1)
            throw usage_error(fmt::format("--rank {}: the number of modes must be at least 1",
                                          settings.rank_rule.fixed_modes));
    }
    settings.outliers.fireflies = !options.no_firefly_clamp;
    settings.outliers.firefly_k = options.firefly_k;
    if (options.sigma_radius < 0)
        throw usage_error("--sigma-radius must be 0 or more");
    settings.sigma_radius = options.sigma_radius;
    if (options.mode_filter && options.no_mode_filter)
        throw usage_error("--mode-filter and --no-mode-filter contradict each other: give one");
    // On by default: it won on both shots of the quality benchmark (man page, DENOISE).
    settings.mode_filter.enabled = !options.no_mode_filter && options.object_space.empty();
    if (settings.mode_filter.enabled && options.rank == "auto" && options.rank_rule != "press")
        throw usage_error(fmt::format("--rank-rule {} needs --no-mode-filter: with the mode filter, --rank auto is "
                                      "chosen by its SURE survey",
                                      options.rank_rule));
    settings.mode_filter.max_modes = options.mode_filter_modes;
    settings.mode_filter.widths = options.mode_filter_widths;
    settings.feature_guide.kinds = parse_feature_guides(options.mode_filter_guides);
    settings.rank_map.enabled = !options.rank_map.empty();
    if (settings.rank_map.enabled && !settings.mode_filter.enabled)
        throw usage_error("--rank-map needs the mode filter: the local estimates use its noise and filters");
    if (settings.rank_map.enabled && !options.method_options.segments.empty())
        throw usage_error("--rank-map cannot be combined with --segments: each part has a map of its own");
    settings.max_memory_bytes = parse_memory_budget(options.max_memory, "--max-memory");
    return settings;
}

std::int64_t peak_resident_bytes()
{
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    return static_cast<std::int64_t>(usage.ru_maxrss) * 1024;
}

// The --report page of a finished run (one engine run, or one per --segments part).
report::ReportData denoise_report_page(const DenoiseJob& job, const io::SequenceReader& reader,
                                       const report::Collector& collector, const denoise::Report& merged,
                                       const SegmentRun& segments, const std::vector<int>& frame_numbers,
                                       double seconds)
{
    std::vector<report::EngineRun> runs;
    if (segments.reports.empty())
        runs.push_back({0, merged.shape.frames, &merged});
    for (size_t k = 0; k < segments.reports.size() && k < segments.segments.size(); ++k)
        runs.push_back({segments.segments[k].first, segments.segments[k].count, &segments.reports[k]});
    report::ReportData data = report::gather_report(collector, runs, frame_numbers);
    data.title = fmt::format("modestack denoise: {}", reader.sequence().printf_pattern);
    data.version = version_string();
    data.command = command_line();
    data.input = reader.sequence().printf_pattern;
    data.channel_names = reader.selected_channel_names();
    data.seconds.push_back({"denoise: total", seconds});
    if (!job.method_options.transform.empty() && job.method_options.transform != "none")
        data.notes.push_back(fmt::format("The engine worked under --transform {}; the rank slider projects the "
                                         "linear frames on its modes, an approximation.",
                                         job.method_options.transform));
    return data;
}

// Provenance every output frame records.
std::vector<io::HeaderAttribute> provenance_attributes(const io::FrameSequence& input)
{
    return {
        io::HeaderAttribute::of_text("modestack:version", MODESTACK_VERSION),
        io::HeaderAttribute::of_text("modestack:command", command_line()),
        io::HeaderAttribute::of_text("modestack:input", input.printf_pattern),
        io::HeaderAttribute::of_text("modestack:frames", io::describe_frames(input.frames)),
    };
}

// The one line for a guide --mode-filter-guides names that the input does not have.
std::string missing_guide(denoise::Auxiliary kind, const RendererChoice& renderer,
                          const SequenceSource& source, const std::string& file)
{
    const std::string name = denoise::auxiliary_name(kind);
    return fmt::format(
        "--mode-filter-guides {}: {} has no {} layer in every frame (looked for {}; renderer {}, {}); "
        "use --renderer, --conventions, or leave {} out",
        name, file, name, describe_candidates(source.auxiliary_candidates(kind)), renderer.name,
        renderer.detected_by, name);
}

// Clears the paths not to write (already empty, or existing with --skip-existing)
// and returns how many are left.
int keep_frames_to_write(std::vector<std::string>& paths, bool skip_existing)
{
    int frames_written = 0;
    for (std::string& path : paths) {
        if (path.empty() || (skip_existing && std::filesystem::exists(path)))
            path.clear();
        else
            ++frames_written;
    }
    return frames_written;
}

void warn_nothing_to_do(RunContext& context, const std::string& output)
{
    context.progress().warn(
        fmt::format("every output of {} exists already (--skip-existing): nothing to do", output));
}

// What --object-space cannot be combined with: everything that needs image
// neighbours or a second pass over files the points job does not have.
void check_object_space_options(const DenoiseCommandOptions& options)
{
    auto refuse = [](const char* option, const char* why) {
        throw usage_error(fmt::format("--object-space cannot be combined with {}: {}", option, why));
    };
    if (!options.stage.stage.empty())
        refuse("--stage", "the points job runs in one process");
    if (!options.rank_map.empty())
        refuse("--rank-map", "it needs the mode filter");
    if (!options.save_modes.empty())
        refuse("--save-modes", "the modes are point images, not frames");
    if (!options.report_path.empty())
        refuse("--report", "the report shows image modes");
    if (!options.colorspace.empty())
        refuse("--colorspace", "points are baked scene-linear");
    if (!options.method_options.segments.empty())
        refuse("--segments", "the points are denoised as one shot");
    if (options.method_options.transform != "none")
        refuse("--transform", "the points are denoised as baked");
    if (options.method_options.estimators != "auto" &&
        denoise::parse_estimators(options.method_options.estimators).enabled())
        refuse("--estimators", "the choice blurs image neighbours, which points do not have");
}

// What needs one set of modes for the whole shot, so several layers each on
// their own modes cannot have it: --joint gives them one.
void check_layers_apart(const DenoiseCommandOptions& options)
{
    const auto refuse_option = [&](const char* option, const char* why) {
        throw usage_error(fmt::format("{} with {} layers each on its own modes: {}; add --joint to share one "
                                      "set of modes, or run one layer per job",
                                      option, options.layers.size(), why));
    };
    if (!options.stage.stage.empty())
        refuse_option("--stage", "the farm's stage files hold one set of modes");
    if (!options.save_modes.empty())
        refuse_option("--save-modes", "it writes one set of modes");
    if (!options.rank_map.empty())
        refuse_option("--rank-map", "it writes one map of N");
    if (!options.object_space.empty())
        refuse_option("--object-space", "the points job shares its modes between layers");
}

DenoiseResult denoise_object_space(const DenoiseJob& job, const denoise::Settings& settings,
                                   const io::FrameSequence& input, const std::vector<std::string>& paths,
                                   int frames_written, std::chrono::steady_clock::time_point start,
                                   RunContext& context)
{
    ObjectSpaceJob points_job;
    points_job.frames = input;
    points_job.points = job.object_space;
    points_job.exr_codec = job.exr_codec;
    points_job.part_layout = job.part_layout;
    points_job.output_format = job.output_format;
    points_job.layers = job.layers;
    points_job.conventions = job.conventions;
    points_job.renderer = job.renderer;
    points_job.outputs = paths;
    points_job.surface_filter = job.surface_filter;
    points_job.filter_widths = job.filter_widths;
    points_job.sigma_radius = job.settings.sigma_radius;
    points_job.attributes = provenance_attributes(input);
    DenoiseResult result;
    result.object_space = run_object_space(points_job, settings, context.progress());
    result.report = result.object_space->report;
    result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    result.peak_memory_bytes = peak_resident_bytes();
    result.input = input.printf_pattern;
    result.output = job.output;
    result.frames = input.frames;
    result.frames_written = frames_written;
    result.width = result.object_space->frame_width;
    result.height = result.object_space->frame_height;
    result.points_input = job.object_space;
    result.surface_filter = job.surface_filter;
    return result;
}

// --compression, --data-type, --only-denoised checked (output_format.h has the compression rule).
io::OutputFormat make_output_format(const DenoiseCommandOptions& options)
{
    io::OutputFormat format;
    if (!options.compression.empty() && !io::is_compression_name(options.compression))
        throw usage_error(
            fmt::format("--compression '{}' is not one of {} (dwaa and dwab may take a level: dwaa:45)",
                        options.compression, io::compression_names()));
    format.compression = options.compression;
    if (options.data_type == "half")
        format.written_type = io::WrittenType::Half;
    else if (options.data_type == "float")
        format.written_type = io::WrittenType::Float;
    else if (!options.data_type.empty())
        throw usage_error(fmt::format("--data-type '{}' is not one of half, float", options.data_type));
    format.only_written = options.only_denoised;
    return format;
}

}  // namespace

std::string too_few_frames(std::size_t frame_count)
{
    return fmt::format("denoising needs at least {} frames, found {}", kMinimumShotFrames, frame_count);
}

DenoiseJob make_denoise_job(const DenoiseCommandOptions& options, const CLI::App* command)
{
    if (!options.object_space.empty())
        check_object_space_options(options);
    DenoiseJob job;
    job.settings = make_settings(options);
    job.transform = apply_method_options(options.method_options, !options.object_space.empty(), job.settings);
    job.input = options.input;
    job.output = options.output;
    job.layers = options.layers;
    job.frames = options.frames;
    job.save_modes = options.save_modes;
    job.report_path = options.report_path;
    job.rank_map = options.rank_map;
    job.skip_existing = options.skip_existing;
    job.colorspace = options.colorspace;
    job.ocio_config = options.ocio_config;
    job.object_space = options.object_space;
    job.conventions = std::make_shared<const ConventionTable>(load_conventions(options.conventions));
    check_renderer_name(*job.conventions, options.renderer);
    job.renderer = options.renderer;
    // An explicit list asks for each guide; auto takes what the input has.
    job.guides_required = options.mode_filter_guides != std::vector<std::string>{"auto"} &&
                          options.mode_filter_guides != std::vector<std::string>{"none"};
    if (options.update_beauty && options.no_update_beauty)
        throw usage_error("--update-beauty and --no-update-beauty contradict each other: give one");
    job.update_beauty = options.update_beauty ? "on" : options.no_update_beauty ? "off" : "auto";
    job.exr_codec = options.exr_codec;
    job.part_layout = options.single_part ? io::PartLayout::SinglePart : io::PartLayout::AsInput;
    job.joint = options.joint || options.layers.size() < 2;
    if (!job.joint)
        check_layers_apart(options);
    job.output_format = make_output_format(options);
    job.surface_filter = !options.no_mode_filter;
    job.filter_widths = options.mode_filter_widths;
    job.method_options = options.method_options;
    job.stage = options.stage;
    job.stage_command = command;
    return job;
}

namespace {

// One warning per layer whose noise repeats from frame to frame
// (core/denoise/repeating_noise.h): the temporal rebuild cannot remove it, and
// a farm that renders with a fixed seed should hear so from the run itself.
void warn_of_repeating_noise(const denoise::Report& report, const io::SequenceReader& reader,
                             const DenoiseJob& job, bool spatial, Progress& progress)
{
    std::vector<std::pair<std::string, const denoise::RepeatingNoise*>> found;
    const std::vector<io::SelectedLayer>& layers = reader.layers();
    if (report.layers.size() == layers.size() && layers.size() > 1) {
        for (size_t i = 0; i < layers.size(); ++i)
            found.emplace_back(layers[i].name, &report.layers[i].repeating_noise);
    } else {
        std::string names;
        for (const io::SelectedLayer& layer : layers)
            names += (names.empty() ? "" : ", ") + layer.name;
        found.emplace_back(names, &report.repeating_noise);
    }
    for (const auto& [name, noise] : found)
        if (noise->repeats)
            progress.warn(fmt::format(
                "{}: the noise of {} repeats from frame to frame ({:.0f} % of its pixel-scale variation "
                "stays put): "
                "the temporal rebuild cannot remove it{}; render with a seed that changes per frame for the "
                "full gain",
                job.input, name, 100 * noise->share,
                !noise->counted()
                    ? " and, with edges in it, the estimators do not count it (sigma is too small)"
                : spatial ? ", so the spatial estimators take over where they measure better"
                          : " (--estimators without spatial leaves it in)"));
}

DenoiseResult denoise_in_arena(const DenoiseJob& job, const CommonOptions& context_options)
{
    auto start = std::chrono::steady_clock::now();
    denoise::Settings settings = job.settings;
    RunContext context(context_options);
    io::use_single_threaded_exr_files();  // F files open at once, frames read in parallel by us
    reuse_freed_memory();

    // --stage: a farm task (denoise_stages.h); stats and solve write one file, -o.
    std::optional<StageRun> staged;
    if (!job.stage.stage.empty()) {
        if (job.stage_command == nullptr)
            throw internal_error("a --stage task needs its command for the shot's fingerprint");
        staged.emplace(job.stage, *job.stage_command);
        if (settings.solver == denoise::Solver::RandomizedSvd)
            throw usage_error(fmt::format("--stage {}: the farm stages use the gram solver, not --method rsvd",
                                          denoise::stage_name(staged->stage())));
    }
    const bool writes_frames = !staged || staged->writes_frames();
    io::FrameSequence input =
        io::find_input_sequence(job.input, staged ? staged->shot_frames(job.frames) : job.frames);
    io::FrameSequence output = writes_frames ? io::output_sequence(job.output, input.frames) : io::FrameSequence{};
    if (input.frames.size() < kMinimumShotFrames)
        throw bad_input(job.input, too_few_frames(input.frames.size()));
    if (settings.rank_rule.rule == lowrank::RankRule::Fixed &&
        settings.rank_rule.fixed_modes >= static_cast<int>(input.frames.size()))
        throw bad_input(job.input, fmt::format("--rank {} needs more than {} frames (use 1 to {})",
                                               settings.rank_rule.fixed_modes, input.frames.size(),
                                               input.frames.size() - 1));
    apply_training_frames(job.method_options, input.frames, settings);
    SegmentRun segments = plan_segments(job.method_options, input.frames, !job.save_modes.empty());
    const bool output_in_memory = staged && staged->output_in_memory();  // an MPI rank
    if (!output_in_memory)
        io::check_outputs(writes_frames ? output.files : std::vector<std::string>{job.output}, input.files);
    if (!job.report_path.empty())
        report::check_report_path(job.report_path, input.files);
    if (!job.save_modes.empty())
        io::check_outputs({(std::filesystem::path(job.save_modes) / "mode.01.exr").string()}, input.files);
    if (!job.rank_map.empty())
        io::check_outputs({job.rank_map}, input.files);
    if (!job.object_space.empty()) {
        std::vector<std::string> inputs = input.files;
        for (const std::string& file :
             io::find_input_sequence(job.object_space, io::describe_frames(input.frames)).files)
            inputs.push_back(file);
        io::check_outputs(output.files, inputs);
        std::vector<std::string> paths = output.files;
        const int frames_written = keep_frames_to_write(paths, job.skip_existing);
        if (frames_written == 0) {
            warn_nothing_to_do(context, job.output);
            DenoiseResult nothing;
            nothing.nothing_to_do = true;
            return nothing;
        }
        return denoise_object_space(job, settings, input, paths, frames_written, start, context);
    }
    io::SequenceReader reader(input, job.layers, job.exr_codec);
    if (!job.joint)
        for (const io::SelectedLayer& layer : reader.layers())
            settings.layer_channels.push_back(static_cast<int>(layer.channel_names.size()));
    DenoiseColor color = choose_denoise_color(job.ocio_config, job.colorspace, reader);

    if (staged)
        staged->prepare(input, reader);

    std::vector<std::string> paths = writes_frames ? output.files : std::vector<std::string>(input.files.size());
    if (staged && writes_frames)
        staged->keep_written_frames(job.frames, input.frames, paths);
    const int frames_written = keep_frames_to_write(paths, job.skip_existing);
    if (frames_written == 0 && job.save_modes.empty() && writes_frames) {
        warn_nothing_to_do(context, job.output);
        DenoiseResult nothing;
        nothing.nothing_to_do = true;
        return nothing;
    }

    const RendererChoice renderer =
        choose_renderer(*job.conventions, job.renderer, io::read_frame_header(input.files.front()));
    SequenceSource source(reader, auxiliary_candidates(renderer, reader.layers()),
                          job.joint ? std::vector<std::vector<std::vector<std::string>>>{}
                                    : layer_variance_candidates(renderer, reader.layers()));
    // --max-memory bounds the whole process: the engine gets what the program and
    // open files leave. The mode filter's guide layers are opened now so that
    // what they hold is counted too.
    GuideFiles guides;
    if (settings.mode_filter.enabled) {
        for (denoise::Auxiliary kind : settings.feature_guide.kinds)
            if (const io::SequenceReader* guide = source.auxiliary_reader(kind))
                guides.readers.push_back(guide);
            else if (job.guides_required)
                throw usage_error(missing_guide(kind, renderer, source, input.files.front()));
        guides.frames = settings.feature_guide.frames;
    }
    SequenceSink sink(reader, paths, job.save_modes);
    sink.write_rank_map_to(job.rank_map);
    sink.set_part_layout(job.part_layout);
    sink.set_output_format(job.output_format);
    BeautyPlan beauty = plan_beauty_update(renderer, reader, job.update_beauty, color.converter == nullptr);
    std::vector<io::HeaderAttribute> attributes = provenance_attributes(input);
    if (beauty.update && writes_frames) {
        attributes.push_back(
            io::HeaderAttribute::of_text("modestack:beauty", beauty_formula(beauty.targets.front())));
        sink.update_beauty(std::make_unique<BeautyUpdate>(reader, beauty));
    }
    const std::int64_t max_memory_bytes = settings.max_memory_bytes;
    settings.max_memory_bytes =
        engine_memory_budget(settings.max_memory_bytes, reader, sink.open_output_bytes(), guides);
    append_color_attributes(attributes, color);
    if (job.transform.kind != denoise::TransformKind::None)
        attributes.push_back(
            io::HeaderAttribute::of_text("modestack:transform", denoise::transform_name(job.transform)));
    sink.set_attributes(std::move(attributes));
    ColorStream stream(color, source, sink);
    // --report: the collector sees scene-linear rows, outside --transform (report/report_collector.h).
    std::optional<report::Collector> collector;
    if (!job.report_path.empty()) {
        settings.report_modes = report::kReportModes;
        collector.emplace(stream.source(), stream.sink(), report::collector_options(reader.frame_count()));
    }
    VarianceNames variance_names{
        job.input, describe_candidates(source.auxiliary_candidates(denoise::Auxiliary::Variance)), {}, {}};
    for (size_t i = 0; i < reader.layers().size(); ++i) {
        variance_names.layers.push_back(reader.layers()[i].name);
        if (!job.joint)
            variance_names.layer_shots.push_back(
                describe_candidates(source.layer_variance_candidates(static_cast<int>(i))));
    }
    TransformStream transformed(job.transform, collector ? collector->source() : stream.source(),
                                collector ? collector->sink() : stream.sink(), settings, variance_names,
                                job.method_options);
    DenoiseResult result;
    result.report =
        staged ? staged->run(transformed.source(), transformed.sink(), settings, context.progress())
               : run_segmented(segments, transformed.source(), transformed.sink(), settings, context.progress());
    const denoise::Report& report = result.report;
    sink.commit();
    if (staged)
        staged->finish(job.output);
    if (report.outliers.non_finite > 0)
        context.progress().warn(fmt::format("{} NaN/Inf values in {} were replaced by their pixel's temporal median",
                                            report.outliers.non_finite, job.input));
    warn_of_repeating_noise(report, reader, job, settings.estimators.spatial, context.progress());
    result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (!job.save_modes.empty()) {
        nlohmann::ordered_json modes;
        modes["singular_values"] = report.singular_values;
        modes["frames"] = input.frames;
        modes["temporal_modes"] = report.temporal_modes;
        // Frame t is Σ_j ps_j σ_j pt(t, j) D_t (core/denoise/frame_weighting.h); empty: D = 1.
        modes["frame_scales"] = report.frame_scales;
        io::write_text_file((std::filesystem::path(job.save_modes) / "temporal_modes.json").string(),
                            modes.dump(2) + "\n");
        std::string csv = "frame";
        for (size_t j = 0; j < report.temporal_modes.size(); ++j)
            csv += fmt::format(",mode{}", j + 1);
        const bool scaled = !report.frame_scales.empty();
        csv += scaled ? ",frame_scale\n" : "\n";
        for (size_t t = 0; t < input.frames.size(); ++t) {
            csv += std::to_string(input.frames[t]);
            for (const auto& mode : report.temporal_modes)
                csv += fmt::format(",{:.9g}", mode[t]);
            if (scaled)
                csv += fmt::format(",{:.9g}", report.frame_scales[t]);
            csv += "\n";
        }
        io::write_text_file((std::filesystem::path(job.save_modes) / "temporal_modes.csv").string(), csv);
    }
    if (collector) {
        result.report_page =
            denoise_report_page(job, reader, *collector, report, segments, input.frames, result.seconds);
        report::write_report(job.report_path, *result.report_page);
    }
    result.peak_memory_bytes = peak_resident_bytes();
    result.input = reader.sequence().printf_pattern;
    result.output = job.output;
    result.frames = input.frames;
    result.frames_written = frames_written;
    result.width = report.shape.width;
    result.height = report.shape.height;
    result.channel_names = reader.selected_channel_names();
    for (const auto& layer : reader.layers())
        result.layers.push_back({layer.name, layer.channel_names, layer.sigma_names, nullptr});
    result.joint = settings.layer_channels.size() < 2;
    if (!result.joint) // one part per layer, in order
        for (size_t i = 0; i < result.layers.size() && i < transformed.whitening().size(); ++i)
            result.layers[i].whiten = whitened_part_json(transformed.whitening()[i]);
    result.renderer = renderer_json(renderer, source.auxiliary_lookups());
    result.beauty = beauty_json(beauty);
    result.rank_map = job.rank_map;
    result.max_memory_bytes = max_memory_bytes;
    result.non_negative = settings.non_negative != denoise::NonNegativeMode::Off;
    result.automatic_segments = segments.automatic;
    result.segment_cuts = segments.search.cuts.size();
    result.segment_parts = segments.segments.size();
    result.color = color_json(color);
    result.method = method_json(transformed, settings, report, segments, input.frames);
    if (staged) {
        result.farm = staged->json();
        result.stage = staged->stage();
    }
    result.writes_frames = writes_frames;
    result.output_in_memory = output_in_memory;
    return result;
}

} // namespace

DenoiseResult denoise(const DenoiseJob& job, const CommonOptions& context_options)
{
    // The engine's tasks run in an arena of their own, which gives every task the
    // floating-point settings of this thread (oneTBB captures them when the arena
    // is made). `run` renders in this process first, and a TBB worker came out
    // of the render with denormals-are-zero and flush-to-zero set (Embree's:
    // modestack sets neither); that worker decoded the half subnormals of the
    // frames it read (DiffDir's darkest pixels) as 0, so the files depended on
    // which thread read which frame, not only on the input.
    tbb::task_arena arena;
    return arena.execute([&] { return denoise_in_arena(job, context_options); });
}

}  // namespace modestack::app
