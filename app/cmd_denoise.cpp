// `modestack denoise SEQ -o SEQ`: the temporal low-rank denoiser on an EXR
// sequence. Validates every input and output before any work, runs the
// streaming engine (core/denoise), writes each output frame atomically with
// its sigma channels and provenance, and a JSON summary when asked. Inputs
// that are not scene-linear are converted for the engine and back on output
// (app/color_adapters.h).
#include "app/color_adapters.h"
#include "app/command.h"
#include "app/denoise_stages.h"
#include "app/exr_codec_option.h"
#include "app/memory_budget.h"
#include "app/method_options.h"
#include "app/mpi_job.h"
#include "app/object_space.h"
#include "app/option_values.h"
#include "app/report/denoise_report.h"
#include "app/report/html_report.h"
#include "app/run_context.h"
#include "app/sequence_adapters.h"
#include "core/common/error.h"
#include "core/denoise/engine.h"
#include "io/sequence.h"
#include "io/sequence_reader.h"
#include "io/text_output.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <optional>
#include <sys/resource.h>

namespace modestack::app {
namespace {

struct DenoiseOptions {
    std::string input;
    std::string output;
    std::vector<std::string> layers;
    std::string rank = "auto";
    std::string rank_rule = "press";
    std::string method = "auto";
    std::string max_memory = "auto";
    std::string frames;
    std::string json_path;
    std::string save_modes;
    std::string report_path;
    bool no_firefly_clamp = false;
    double firefly_k = 6.0;
    int sigma_radius = 2;
    bool mode_filter = false;
    bool no_mode_filter = false;
    int mode_filter_modes = 16;
    std::vector<double> mode_filter_widths{0.75, 1.0, 1.5, 2.0, 3.0};
    std::vector<std::string> mode_filter_guides{"auto"};
    std::string rank_map;
    bool skip_existing = false;
    std::string colorspace;
    std::string ocio_config;
    std::string object_space;  ///< --object-space: the points sequence
    MethodOptions method_options;
    StageOptions stage;
    CommonOptions common;
    io::ExrCodec exr_codec = io::ExrCodec::Libdeflate;
    const CLI::App* command = nullptr;  ///< for the fingerprint of --stage
};

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

denoise::Settings make_settings(const DenoiseOptions& options)
{
    denoise::Settings settings;
    settings.solver = denoise::parse_solver(options.method);
    if (options.rank == "auto") {
        settings.rank.rule = lowrank::parse_rank_rule(options.rank_rule);
        if (settings.rank.rule == lowrank::RankRule::Fixed)
            throw usage_error("--rank-rule fixed needs a number: use --rank N");
    } else {
        try {
            size_t used = 0;
            settings.rank.fixed_rank = std::stoi(options.rank, &used);
            if (used != options.rank.size())
                throw std::invalid_argument("trailing characters");
        } catch (const std::exception&) {
            throw usage_error(fmt::format("--rank '{}': write auto or a number of modes", options.rank));
        }
        settings.rank.rule = lowrank::RankRule::Fixed;
    }
    settings.outliers.fireflies = !options.no_firefly_clamp;
    settings.outliers.firefly_k = options.firefly_k;
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

// Per surveyed mode: the filter SURE chose, its risk, the signal it estimates and
// whether the mode is kept; null when the filter is off.
nlohmann::ordered_json mode_filter_json(const denoise::Report& report)
{
    const denoise::ModeFilterPlan& plan = report.mode_filter;
    if (plan.modes.empty())
        return nullptr;
    nlohmann::ordered_json modes = nlohmann::ordered_json::array();
    for (size_t j = 0; j < plan.modes.size(); ++j) {
        const denoise::ModeFilterChoice& choice = plan.modes[j];
        modes.push_back({{"mode", j + 1},
                         {"width", choice.width},
                         {"guided", choice.range > 0},
                         {"range", choice.range},
                         {"feature_range", choice.feature_range},
                         {"sure", choice.sure},
                         {"sure_unfiltered", choice.unfiltered_sure},
                         {"signal", choice.signal},
                         {"noise_scale", choice.noise_scale},
                         {"kept", choice.kept}});
    }
    return {{"enabled", true},
            {"rank", plan.rank},
            {"guide", "first spatial mode"},
            {"feature_guides", report.feature_guide.features},
            {"feature_scales", report.feature_guide.scales},
            {"feature_frames", report.feature_guide.frames},
            {"guide_smoothing", plan.guide_smoothing},
            {"survey_stride", plan.survey_stride},
            {"reasoning", plan.reasoning},
            {"seconds_survey", report.seconds_filter_survey},
            {"modes", modes}};
}

// The opening fields of the --json summary: what ran on which frames, at what size.
nlohmann::ordered_json run_json(const DenoiseOptions& options, const io::FrameSequence& input,
                                const denoise::Report& report, int frames_written, int width, int height)
{
    nlohmann::ordered_json json;
    json["version"] = version_string();
    json["command"] = command_line();
    json["input"] = input.printf_pattern;
    json["output"] = options.output;
    json["frames"] = io::describe_frames(input.frames);
    json["frame_count"] = report.shape.frames;
    json["frames_written"] = frames_written;
    json["width"] = width;
    json["height"] = height;
    return json;
}

// Seconds per phase and the peak memory of the run.
void add_time_and_memory_json(const denoise::Report& report, double seconds_total, nlohmann::ordered_json& json)
{
    json["seconds"] = {{"statistics", report.seconds_statistics},
                       {"solve", report.seconds_solve},
                       {"rebuild", report.seconds_rebuild},
                       {"total", seconds_total}};
    json["peak_memory_bytes"] = peak_resident_bytes();
}

// N and why, the spectrum, the temporal modes and the outlier counts of a run.
void add_modes_json(const denoise::Report& report, nlohmann::ordered_json& json)
{
    json["rank"] = {{"n", report.rank.rank},
                    {"rule", report.rank.rule},
                    {"reasoning", report.rank.reasoning},
                    {"score", report.rank.score},
                    {"noise_floor", report.rank.noise_floor},
                    {"noise_sigma", report.rank.noise_sigma}};
    json["singular_values"] = report.singular_values;
    json["explained_variance"] = report.explained;
    json["temporal_modes"] = report.temporal_modes;
    json["outliers"] = {{"non_finite", report.outliers.non_finite}, {"fireflies", report.outliers.fireflies}};
}

nlohmann::ordered_json summary_json(const DenoiseOptions& options, const io::SequenceReader& reader,
                                    const denoise::Report& report, double seconds_total, int frames_written,
                                    std::int64_t max_memory_bytes)
{
    nlohmann::ordered_json json =
        run_json(options, reader.sequence(), report, frames_written, report.shape.width, report.shape.height);
    json["channels"] = reader.selected_channel_names();
    nlohmann::ordered_json layers = nlohmann::ordered_json::array();
    for (const auto& layer : reader.layers())
        layers.push_back({{"layer", layer.name}, {"channels", layer.channel_names}, {"sigma", layer.sigma_names}});
    json["layers"] = layers;
    json["solver"] = report.solver;
    json["passes"] = report.passes;
    json["in_memory"] = report.plan.in_memory;
    json["band_rows"] = report.plan.band_rows;
    add_modes_json(report, json);
    json["mode_filter"] = mode_filter_json(report);
    if (report.rank_map.largest_rank > 0)
        json["rank_map"] = {{"file", options.rank_map},
                            {"largest_rank", report.rank_map.largest_rank},
                            {"mean", report.rank_map.mean},
                            {"smallest", report.rank_map.smallest},
                            {"largest", report.rank_map.largest},
                            {"pixels_per_whole_rank", report.rank_map.histogram}};
    add_time_and_memory_json(report, seconds_total, json);
    json["max_memory_bytes"] = max_memory_bytes;
    // What the program and its open files were counted to hold; the rest went to the plan.
    json["memory_held_bytes"] = max_memory_bytes - report.plan.budget_bytes;
    json["plan_bytes"] = report.plan.estimated_bytes;
    return json;
}

// The --report page of a finished run; also handed to `modestack run` (report::publish_report).
void write_denoise_report(const DenoiseOptions& options, const io::SequenceReader& reader,
                          const report::Collector& collector, const denoise::Report& merged,
                          const SegmentRun& segments, const std::vector<int>& frame_numbers, double seconds)
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
    if (!options.method_options.transform.empty() && options.method_options.transform != "none")
        data.notes.push_back(fmt::format("The engine worked under --transform {}; the rank slider projects the "
                                         "linear frames on its modes, an approximation.",
                                         options.method_options.transform));
    report::write_report(options.report_path, data);
    report::publish_report(std::move(data));
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
void check_object_space_options(const DenoiseOptions& options)
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
}

int run_object_space_denoise(const DenoiseOptions& options, const denoise::Settings& settings,
                             const io::FrameSequence& input, const std::vector<std::string>& paths, int frames_written,
                             std::chrono::steady_clock::time_point start, RunContext& context)
{
    ObjectSpaceJob job;
    job.frames = input;
    job.points = options.object_space;
    job.layers = options.layers;
    job.outputs = paths;
    job.surface_filter = !options.no_mode_filter;
    job.filter_widths = options.mode_filter_widths;
    job.sigma_radius = options.sigma_radius;
    job.attributes = provenance_attributes(input);
    job.exr_codec = options.exr_codec;
    ObjectSpaceResult result = run_object_space(job, settings, context.progress());
    const denoise::Report& report = result.report;
    double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (!options.json_path.empty()) {
        nlohmann::ordered_json json =
            run_json(options, input, report, frames_written, result.frame_width, result.frame_height);
        json["object_space"] = {{"points_input", options.object_space},
                                {"points", result.points},
                                {"point_image_width", report.shape.width},
                                {"point_image_height", report.shape.height}};
        json["surface_filter"] = {{"enabled", !options.no_mode_filter},
                                  {"width_spacings", result.filter.width},
                                  {"widths", result.filter.widths},
                                  {"sure", result.filter.risks},
                                  {"mean_neighbours", result.filter.mean_neighbours},
                                  {"reasoning", result.filter.reasoning}};
        json["solver"] = report.solver;
        add_modes_json(report, json);
        add_time_and_memory_json(report, seconds, json);
        io::write_text_file(options.json_path, json.dump(2) + "\n");
    }
    if (!options.common.quiet)
        std::fprintf(stderr, "denoised %d of %d frames in object space (%lld points) with N = %d modes (%s rule, %s "
                             "solver), surface filter: %s, in %.2f s\n",
                     frames_written, report.shape.frames, static_cast<long long>(result.points), report.rank.rank,
                     report.rank.rule.c_str(), report.solver.c_str(),
                     options.no_mode_filter ? "off" : result.filter.reasoning.c_str(), seconds);
    return 0;
}

int run_denoise(const DenoiseOptions& options)
{
    auto start = std::chrono::steady_clock::now();
    if (!options.object_space.empty())
        check_object_space_options(options);
    denoise::Settings settings = make_settings(options);
    const denoise::Transform transform = apply_method_options(options.method_options, settings);
    RunContext context(options.common);
    io::use_single_threaded_exr_files();  // F files open at once, frames read in parallel by us
    reuse_freed_memory();

    // --stage: a farm task (denoise_stages.h); stats and solve write one file, -o.
    std::optional<StageRun> staged;
    if (!options.stage.stage.empty())
        staged.emplace(options.stage, *options.command);
    const bool writes_frames = !staged || staged->writes_frames();
    io::FrameSequence input =
        io::find_input_sequence(options.input, staged ? staged->shot_frames(options.frames) : options.frames);
    io::FrameSequence output = writes_frames ? io::output_sequence(options.output, input.frames) : io::FrameSequence{};
    if (input.frames.size() < 3)
        throw bad_input(options.input, fmt::format("denoising needs at least 3 frames, found {}", input.frames.size()));
    if (settings.rank.rule == lowrank::RankRule::Fixed &&
        settings.rank.fixed_rank >= static_cast<int>(input.frames.size()))
        throw bad_input(options.input, fmt::format("--rank {} needs more than {} frames (use 1 to {})",
                                                   settings.rank.fixed_rank, input.frames.size(),
                                                   input.frames.size() - 1));
    if (settings.rank.rule == lowrank::RankRule::Fixed && settings.rank.fixed_rank < 1)
        throw usage_error(fmt::format("--rank {}: the number of modes must be at least 1", settings.rank.fixed_rank));
    apply_training_frames(options.method_options, input.frames, settings);
    SegmentRun segments = plan_segments(options.method_options, input.frames, !options.save_modes.empty());
    const bool output_in_memory = staged && staged->output_in_memory();  // an MPI rank
    if (!output_in_memory)
        io::check_outputs(writes_frames ? output.files : std::vector<std::string>{options.output}, input.files);
    if (!options.report_path.empty())
        report::check_report_path(options.report_path, input.files);
    if (!options.save_modes.empty())
        io::check_outputs({(std::filesystem::path(options.save_modes) / "mode.01.exr").string()}, input.files);
    if (!options.rank_map.empty())
        io::check_outputs({options.rank_map}, input.files);
    if (!options.object_space.empty()) {
        std::vector<std::string> inputs = input.files;
        for (const std::string& file :
             io::find_input_sequence(options.object_space, io::describe_frames(input.frames)).files)
            inputs.push_back(file);
        io::check_outputs(output.files, inputs);
        std::vector<std::string> paths = output.files;
        const int frames_written = keep_frames_to_write(paths, options.skip_existing);
        if (frames_written == 0) {
            warn_nothing_to_do(context, options.output);
            return 0;
        }
        return run_object_space_denoise(options, settings, input, paths, frames_written, start, context);
    }
    io::SequenceReader reader(input, options.layers, options.exr_codec);
    DenoiseColor color = choose_denoise_color(options.ocio_config, options.colorspace, reader);

    if (staged)
        staged->prepare(input, reader);

    std::vector<std::string> paths = writes_frames ? output.files : std::vector<std::string>(input.files.size());
    if (staged && writes_frames)
        staged->keep_written_frames(options.frames, input.frames, paths);
    const int frames_written = keep_frames_to_write(paths, options.skip_existing);
    if (frames_written == 0 && options.save_modes.empty() && writes_frames) {
        warn_nothing_to_do(context, options.output);
        return 0;
    }

    SequenceSource source(reader);
    // --max-memory bounds the whole process: the engine gets what the program and
    // open files leave. The mode filter's guide layers are opened now so that
    // what they hold is counted too.
    GuideFiles guides;
    if (settings.mode_filter.enabled) {
        for (denoise::Auxiliary kind : settings.feature_guide.kinds)
            if (const io::SequenceReader* guide = source.auxiliary_reader(kind))
                guides.readers.push_back(guide);
        guides.frames = settings.feature_guide.frames;
    }
    const std::int64_t max_memory_bytes = settings.max_memory_bytes;
    settings.max_memory_bytes = engine_memory_budget(settings.max_memory_bytes, reader, frames_written,
                                                     reader.selected_channel_count(), guides);
    SequenceSink sink(reader, paths, options.save_modes);
    sink.write_rank_map_to(options.rank_map);
    std::vector<io::HeaderAttribute> attributes = provenance_attributes(input);
    append_color_attributes(attributes, color);
    if (transform.kind != denoise::TransformKind::None)
        attributes.push_back(
            io::HeaderAttribute::of_text("modestack:transform", denoise::transform_name(transform)));
    sink.set_attributes(std::move(attributes));
    ColorStream stream(color, source, sink);
    // --report: the collector sees scene-linear rows, outside --transform (report/report_collector.h).
    std::optional<report::Collector> collector;
    if (!options.report_path.empty()) {
        settings.report_modes = report::kReportModes;
        collector.emplace(stream.source(), stream.sink(), report::collector_options(reader.frame_count()));
    }
    TransformStream transformed(transform, collector ? collector->source() : stream.source(),
                                collector ? collector->sink() : stream.sink(), settings, options.input,
                                options.method_options);
    denoise::Report report =
        staged ? staged->run(transformed.source(), transformed.sink(), settings, context.progress())
               : run_segmented(segments, transformed.source(), transformed.sink(), settings, context.progress());
    sink.commit();
    if (staged)
        staged->finish(options.output);
    if (report.outliers.non_finite > 0)
        context.progress().warn(fmt::format("{} NaN/Inf values in {} were replaced by their pixel's temporal median",
                                            report.outliers.non_finite, options.input));
    double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (!options.save_modes.empty()) {
        nlohmann::ordered_json modes;
        modes["singular_values"] = report.singular_values;
        modes["frames"] = input.frames;
        modes["temporal_modes"] = report.temporal_modes;
        io::write_text_file((std::filesystem::path(options.save_modes) / "temporal_modes.json").string(),
                            modes.dump(2) + "\n");
        std::string csv = "frame";
        for (size_t j = 0; j < report.temporal_modes.size(); ++j)
            csv += fmt::format(",mode{}", j + 1);
        csv += "\n";
        for (size_t t = 0; t < input.frames.size(); ++t) {
            csv += std::to_string(input.frames[t]);
            for (const auto& mode : report.temporal_modes)
                csv += fmt::format(",{:.9g}", mode[t]);
            csv += "\n";
        }
        io::write_text_file((std::filesystem::path(options.save_modes) / "temporal_modes.csv").string(), csv);
    }
    if (collector)
        write_denoise_report(options, reader, *collector, report, segments, input.frames, seconds);
    if (!options.json_path.empty()) {
        nlohmann::ordered_json json = summary_json(options, reader, report, seconds, frames_written, max_memory_bytes);
        json["color"] = color_json(color);
        json["method"] = method_json(transformed, settings, report, segments, input.frames);
        if (staged)
            json["farm"] = staged->json();
        io::write_text_file(options.json_path, json.dump(2) + "\n");
    }
    if (staged && !writes_frames) {
        if (!options.common.quiet && !output_in_memory)
            std::fprintf(stderr, "--stage %s of %d frames written to %s in %.2f s\n",
                         denoise::stage_name(staged->stage()), report.shape.frames, options.output.c_str(), seconds);
    } else if (!options.common.quiet) {
        std::fprintf(stderr, "denoised %d of %d frames with N = %d modes (%s rule, %s solver) in %.2f s\n",
                     frames_written, report.shape.frames, report.rank.rank, report.rank.rule.c_str(),
                     report.solver.c_str(), seconds);
    }
    if (!options.common.quiet && settings.non_negative != denoise::NonNegativeMode::Off)
        std::fprintf(stderr, "--non-negative changed %lld values in %lld pixel channels\n",
                     static_cast<long long>(report.non_negative.clamped + report.non_negative.scaled),
                     static_cast<long long>(report.non_negative.samples));
    if (!options.common.quiet && segments.automatic)
        std::fprintf(stderr, "--segments auto: %zu cut(s), %zu part(s)\n", segments.search.cuts.size(),
                     segments.segments.size());
    return 0;
}

}  // namespace

Subcommand add_denoise_command(CLI::App& parent)
{
    auto options = std::make_shared<DenoiseOptions>();
    CLI::App* command = parent.add_subcommand(
        "denoise", "Denoise the selected layers of an EXR sequence with its temporal low-rank modes");
    command->add_option("SEQ", options->input, "Input frame sequence: name.####.exr, name.%04d.exr, name.@.exr")
        ->required();
    command->add_option("-o,--output", options->output,
                        "Output frame sequence (never an input); with --stage stats or solve, the task's file")
        ->required();
    command->add_option("--layer", options->layers,
                        "Layer to denoise: NAME.R/G/B or <prefix>.NAME.<ch> (Cycles DiffInd); repeatable. "
                        "Default: the only RGB layer")
        ->allow_extra_args(false);  // one value per --layer, so that `--layer DiffInd in.####.exr` works
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
    command->add_option("--json", options->json_path, "Write a JSON summary: N and why, spectrum, counts, timings");
    command->add_option("--save-modes", options->save_modes,
                        "Write the spatial modes (mode.NN.exr) and temporal weights (CSV, JSON) to this directory");
    command->add_option("--report", options->report_path,
                        "Write one self-contained HTML report (opens offline; images embedded as PNG data: URIs): "
                        "spectrum and rank reasoning, temporal weights, spatial modes, a rank slider, "
                        "noisy/denoised/sigma side by side with zoom and exposure, per-frame error, counts, timings");
    command->add_flag("--no-firefly-clamp", options->no_firefly_clamp,
                      "Keep fireflies as they are (default: clamp them, spreading their energy over the pixel's "
                      "frames)");
    command->add_option("--firefly-k", options->firefly_k,
                        "Firefly threshold: temporal median + k x 1.4826 x MAD of the pixel")
        ->check(CLI::PositiveNumber);
    command->add_option("--sigma-radius", options->sigma_radius, "Spatial pooling radius of sigma, in pixels")
        ->check(CLI::NonNegativeNumber);
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
    command->add_option("--mode-filter-guides", options->mode_filter_guides,
                        "Features that may guide the mode filter's edges: auto (default: those the input has: "
                        "DiffCol/Denoising Albedo, Normal, Depth next to the layer), none, or a list of albedo, "
                        "normal, depth; SURE decides per mode whether they help")
        ->delimiter(',')
        ->allow_extra_args(false);
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
    add_method_options(*command, options->method_options);
    add_stage_options(*command, options->stage);
    add_common_options(*command, options->common);
    add_exr_codec_option(*command, options->exr_codec);
    options->command = command;
    return {command, [options] {
                if (!started_by_mpirun())
                    return run_denoise(*options);
                if (!options->stage.stage.empty())
                    throw usage_error("--stage is for farm tasks, one process each: under mpirun the ranks run "
                                      "every stage themselves");
                // mpirun -n K: each rank runs the farm stages on its share (mpi_job.h).
                return run_mpi_denoise(options->frames, [&](const StageOptions& stage, const std::string& frames,
                                                            bool lead) {
                    DenoiseOptions task = *options;
                    task.stage = stage;
                    task.frames = frames;
                    task.common.quiet = options->common.quiet || !lead;
                    if (!lead || stage.stage != "write")
                        task.json_path.clear();
                    return run_denoise(task);
                });
            }};
}

}  // namespace modestack::app
