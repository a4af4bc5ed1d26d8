// The --json summary and the stderr lines of `modestack denoise` (denoise_job.h),
// written from a DenoiseResult: what ran on which frames, N and why, the
// spectrum, the mode filter's choices, timings and memory, and the colour,
// method and farm blocks.
#include "app/denoise_job.h"

#include "app/command.h"
#include "io/sequence.h"

#include <fmt/format.h>

#include <cstdio>

namespace modestack::app {
namespace {

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
            {"rank", plan.kept_modes},
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

// Seconds per phase and the peak memory of the run.
void add_time_and_memory_json(const denoise::Report& report, double seconds_total, std::int64_t peak_memory_bytes,
                              nlohmann::ordered_json& json)
{
    json["seconds"] = {{"statistics", report.seconds_statistics},
                       {"solve", report.seconds_solve},
                       {"rebuild", report.seconds_rebuild},
                       {"total", seconds_total}};
    json["peak_memory_bytes"] = peak_memory_bytes;
}

// N and why, the spectrum, the temporal modes and the outlier counts of a run.
void add_modes_json(const denoise::Report& report, nlohmann::ordered_json& json)
{
    json["rank"] = {{"n", report.rank_decision.kept_modes},
                    {"rule", report.rank_decision.rule},
                    {"reasoning", report.rank_decision.reasoning},
                    {"score", report.rank_decision.score},
                    {"noise_floor", report.rank_decision.noise_floor},
                    {"noise_sigma", report.rank_decision.noise_sigma}};
    json["singular_values"] = report.singular_values;
    json["explained_variance"] = report.explained;
    json["temporal_modes"] = report.temporal_modes;
    json["outliers"] = {{"non_finite", report.outliers.non_finite}, {"fireflies", report.outliers.fireflies}};
}

// The opening fields of the --json summary: what ran on which frames, at what size.
nlohmann::ordered_json run_json(const DenoiseResult& result)
{
    nlohmann::ordered_json json;
    json["version"] = version_string();
    json["command"] = command_line();
    json["input"] = result.input;
    json["output"] = result.output;
    json["frames"] = io::describe_frames(result.frames);
    json["frame_count"] = result.report.shape.frames;
    json["frames_written"] = result.frames_written;
    json["width"] = result.width;
    json["height"] = result.height;
    return json;
}

nlohmann::ordered_json object_space_json(const DenoiseResult& result)
{
    const ObjectSpaceResult& points = *result.object_space;
    const denoise::Report& report = result.report;
    nlohmann::ordered_json json = run_json(result);
    json["object_space"] = {{"points_input", result.points_input},
                            {"points", points.points},
                            {"point_image_width", report.shape.width},
                            {"point_image_height", report.shape.height},
                            {"points_read_again", points.points_read_again}};
    json["surface_filter"] = {{"enabled", result.surface_filter},
                              {"width_spacings", points.filter.width},
                              {"widths", points.filter.widths},
                              {"sure", points.filter.risks},
                              {"mean_neighbours", points.filter.mean_neighbours},
                              {"reasoning", points.filter.reasoning},
                              {"seconds", points.filter.seconds}};
    json["solver"] = report.solver;
    add_modes_json(report, json);
    add_time_and_memory_json(report, result.seconds, result.peak_memory_bytes, json);
    return json;
}

}  // namespace

nlohmann::ordered_json denoise_json(const DenoiseResult& result)
{
    if (result.object_space)
        return object_space_json(result);
    const denoise::Report& report = result.report;
    nlohmann::ordered_json json = run_json(result);
    json["channels"] = result.channel_names;
    nlohmann::ordered_json layers = nlohmann::ordered_json::array();
    for (size_t i = 0; i < result.layers.size(); ++i) {
        const DenoisedLayer& layer = result.layers[i];
        nlohmann::ordered_json entry{
            {"layer", layer.name}, {"channels", layer.channels}, {"sigma", layer.sigma}};
        if (!result.joint && i < report.layers.size()) { // the layer's own modes
            add_modes_json(report.layers[i], entry);
            entry["mode_filter"] = mode_filter_json(report.layers[i]);
            if (!layer.whiten.is_null())
                entry["whiten"] = layer.whiten;
        }
        // Each frame's noise level over the shot's, which scales the estimator
        // choice's one-sided test (core/denoise/frame_noise.h); a layer's own
        // when the layers have their own modes.
        const denoise::Report& own = !result.joint && i < report.layers.size() ? report.layers[i] : report;
        if (!own.frame_noise_factors.empty())
            entry["frame_noise_factors"] = own.frame_noise_factors;
        // The frame scales its modes were fitted with (core/denoise/frame_weighting.h; empty: even).
        entry["frame_scales"] = own.frame_scales;
        // Noise that repeats from frame to frame (core/denoise/repeating_noise.h).
        if (const denoise::RepeatingNoise& noise = own.repeating_noise; noise.measured)
            entry["repeating_noise"] = {
                {"repeats", noise.repeats},         {"share", noise.share},
                {"whiteness", noise.whiteness},     {"level", noise.level},
                {"counted", noise.counted()},       {"counted_share", noise.counted_share()},
                {"temporal_power", noise.temporal}, {"spatial_power", noise.spatial},
                {"coarse_power", noise.coarse},     {"frames_read", noise.frames.size()},
                {"seconds", noise.seconds}};
        layers.push_back(entry);
    }
    json["layers"] = layers;
    // Several layers: one set of modes for all (the top-level rank), or each its own (under "layers", the
    // top level then repeats the first layer's).
    json["joint"] = result.joint;
    if (!result.renderer.is_null())
        json["renderer"] = result.renderer;
    if (!result.beauty.is_null())
        json["beauty"] = result.beauty;
    json["solver"] = report.solver;
    json["passes"] = report.passes;
    json["in_memory"] = report.plan.in_memory;
    json["band_rows"] = report.plan.band_rows;
    json["halo_band_rows"] = report.plan.halo_band_rows;
    add_modes_json(report, json);
    json["mode_filter"] = mode_filter_json(report);
    if (report.rank_map.largest_rank > 0)
        json["rank_map"] = {{"file", result.rank_map},
                            {"largest_rank", report.rank_map.largest_rank},
                            {"mean", report.rank_map.mean},
                            {"smallest", report.rank_map.smallest},
                            {"largest", report.rank_map.largest},
                            {"pixels_per_whole_rank", report.rank_map.histogram}};
    add_time_and_memory_json(report, result.seconds, result.peak_memory_bytes, json);
    json["max_memory_bytes"] = result.max_memory_bytes;
    // What the program and its open files were counted to hold; the rest went to the plan.
    json["memory_held_bytes"] = result.max_memory_bytes - report.plan.budget_bytes;
    json["plan_bytes"] = report.plan.estimated_bytes;
    json["color"] = result.color;
    json["method"] = result.method;
    if (result.stage)
        json["farm"] = result.farm;
    return json;
}

void print_denoise_summary(const DenoiseResult& result)
{
    const denoise::Report& report = result.report;
    if (result.object_space) {
        std::fprintf(
            stderr,
            "denoised %d of %d frames in object space (%lld points) with N = %d modes (%s rule, %s "
            "solver), surface filter: %s, in %.2f s\n",
            result.frames_written, report.shape.frames, static_cast<long long>(result.object_space->points),
            report.rank_decision.kept_modes, report.rank_decision.rule.c_str(), report.solver.c_str(),
            result.surface_filter ? result.object_space->filter.reasoning.c_str() : "off", result.seconds);
        return;
    }
    if (result.stage && !result.writes_frames) {
        if (!result.output_in_memory)
            std::fprintf(stderr, "--stage %s of %d frames written to %s in %.2f s\n",
                         denoise::stage_name(*result.stage), report.shape.frames, result.output.c_str(),
                         result.seconds);
    } else if (!result.joint && report.layers.size() == result.layers.size()) {
        std::string modes;
        for (size_t i = 0; i < result.layers.size(); ++i)
            modes += fmt::format("{}{} N = {}", i ? ", " : "", result.layers[i].name,
                                 report.layers[i].rank_decision.kept_modes);
        std::fprintf(
            stderr,
            "denoised %d of %d frames, each layer on its own modes (%s; %s rule, %s solver) in %.2f s\n",
            result.frames_written, report.shape.frames, modes.c_str(), report.rank_decision.rule.c_str(),
            report.solver.c_str(), result.seconds);
    } else {
        std::fprintf(stderr, "denoised %d of %d frames with N = %d modes (%s rule, %s solver) in %.2f s\n",
                     result.frames_written, report.shape.frames, report.rank_decision.kept_modes,
                     report.rank_decision.rule.c_str(), report.solver.c_str(), result.seconds);
    }
    if (result.non_negative)
        std::fprintf(stderr, "--non-negative changed %lld values in %lld pixel channels\n",
                     static_cast<long long>(report.non_negative.clamped + report.non_negative.scaled),
                     static_cast<long long>(report.non_negative.samples));
    if (result.automatic_segments)
        std::fprintf(stderr, "--segments auto: %zu cut(s), %zu part(s)\n", result.segment_cuts, result.segment_parts);
}

}  // namespace modestack::app
