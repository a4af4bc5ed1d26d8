#include "app/method_options.h"

#include "core/common/error.h"
#include "core/denoise/training.h"
#include "io/sequence.h"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

namespace modestack::app {

void add_method_options(CLI::App& command, MethodOptions& options)
{
    command.add_option(
        "--transform", options.transform,
        "Map the values before the SVD and back after: none (default), log (log(x + e), e = 0.1 x "
        "the shot's mean; log:F sets the fraction), pow:G (x^(1/G), 1 <= G <= 8). Biased: the "
        "inverse of a mean is not the mean of the inverse (see the man page)");
    command.add_flag("--non-negative", options.non_negative,
                     "Never write negative light: correct rebuilt values below 0 (counted in --json)");
    command.add_option(
        "--non-negative-mode", options.non_negative_mode,
        "How --non-negative corrects: clamp (default; negatives to 0) or keep-sum (also lowers the "
        "pixel's positive frames so its sum over time is kept)");
    command.add_option("--shrink", options.shrink,
                       "hard (default): keep the N modes whole; optimal: scale each by the Gavish-Donoho "
                       "Frobenius-optimal shrinkage (needs --no-mode-filter)");
    command.add_option(
        "--segments", options.segments,
        "Denoise parts of the shot on their own: auto (cut where the frame-to-frame change jumps far "
        "above its usual level; one more read) or frame ranges covering the shot, e.g. 1-30,31-60");
    command.add_option(
        "--train-frames", options.train_frames,
        "Compute the modes from these frames only (e.g. 1-48x4) and project every frame on them "
        "(needs --no-mode-filter)");
    command.add_flag(
        "--weight-smoothing", options.weight_smoothing,
        "Smooth each mode's weights over time, as much as its own noise asks (SURE), never across a "
        "jump or a segment boundary: less flicker and error (the default; measured on the Cycles shot "
        "and two of our scenes)");
    command.add_flag("--no-weight-smoothing", options.no_weight_smoothing,
                     "Rebuild from the weights as the SVD gives them");
    command.add_option(
        "--whiten", options.whiten,
        "Weight every pixel by 1/sqrt(its mean noise variance) before the SVD and back after, so that "
        "bright noisy regions do not take the modes: auto (the default: when the input has a variance layer, "
        "named as its renderer names them: DiffIndVar, diffuse_indirect_variance, indirectDiffuse_mse; layers "
        "apart: each layer that has its own), on, off");
    command.add_option(
        "--frame-noise", options.frame_noise,
        "measured (default): fit the modes to each frame's own noise level (measured from the input), so "
        "that a few noisy frames (a large light switched on) do not leave their noise in the clean ones, and "
        "judge fireflies in each frame at its own level; even: count every frame as equally noisy. The fit "
        "needs the Gram solver and no --train-frames (even there)");
    command.add_option(
        "--estimators", options.estimators,
        "Estimators each pixel may take, comma-separated: rebuild (the temporal rebuild), input (the input "
        "as read), spatial (Gaussian blurs of the input, 1 and 2 px), nlmeans (non-local means of the input: "
        "keeps hard shadow edges; only in place of a candidate whose risk shows a bias where the rebuild was "
        "rejected); 'rebuild' alone turns the choice off. "
        "The rebuild is kept unless another's risk (SURE, 7x7) is lower by 2 standard errors, or the input "
        "lies far below it over 3x3 pixels, or the input at a pixel stays put over 4 frames while the "
        "value taken (the rebuild or a blur) is far from it (then the input is taken); noise found to repeat "
        "from frame to frame (a "
        "fixed seed: warned of) counts in every candidate's risk and in the mode filter's noise levels "
        "where it is as white as render noise (indirect light), and there the rebuild must beat the input "
        "by the same test or the input is taken; sigma is the "
        "chosen value's estimated error. Default auto: rebuild,input,spatial,nlmeans, but the rebuild alone "
        "with --rank-map (its map is of the rebuild) and --object-space (no image neighbours)");
}

void apply_training_frames(const MethodOptions& options, const std::vector<int>& frame_numbers,
                           denoise::Settings& settings)
{
    if (options.train_frames.empty())
        return;
    std::vector<int> indices;
    for (int number : io::parse_frame_range(options.train_frames, "--train-frames")) {
        auto found = std::find(frame_numbers.begin(), frame_numbers.end(), number);
        if (found == frame_numbers.end())
            throw usage_error(fmt::format("--train-frames '{}': frame {} is not in the shot",
                                          options.train_frames, number));
        indices.push_back(static_cast<int>(found - frame_numbers.begin()));
    }
    std::sort(indices.begin(), indices.end());
    indices.erase(std::unique(indices.begin(), indices.end()), indices.end());
    settings.training_frames = indices;
    denoise::check_training_frames(settings, static_cast<int>(frame_numbers.size()));
}

SegmentRun plan_segments(const MethodOptions& options, const std::vector<int>& frame_numbers, bool save_modes)
{
    SegmentRun run;
    if (options.segments.empty())
        return run;
    if (save_modes)
        throw usage_error("--segments cannot be combined with --save-modes: each part has modes of its own");
    if (!options.train_frames.empty())
        throw usage_error("--segments cannot be combined with --train-frames");
    run.automatic = options.segments == "auto";
    if (!run.automatic)
        run.segments = denoise::parse_segments(options.segments, frame_numbers);
    return run;
}

denoise::Report run_segmented(SegmentRun& run, denoise::FrameSource& source, denoise::FrameSink& sink,
                              const denoise::Settings& settings, Progress& progress)
{
    if (run.automatic) {
        run.search = denoise::find_cuts(source);
        run.segments = denoise::segments_from_cuts(run.search.cuts, source.shape().frames);
    }
    if (run.segments.empty())
        return denoise::run_denoise(source, sink, settings, progress);
    run.reports = denoise::run_segments(source, sink, settings, run.segments, progress);
    return denoise::merge_reports(run.reports);
}

denoise::Transform apply_method_options(const MethodOptions& options, bool object_space,
                                        denoise::Settings& settings)
{
    denoise::Transform transform = denoise::parse_transform(options.transform);
    if (!options.non_negative_mode.empty() && !options.non_negative)
        throw usage_error("--non-negative-mode needs --non-negative");
    if (options.non_negative) {
        settings.non_negative = options.non_negative_mode.empty()
                                    ? denoise::NonNegativeMode::Clamp
                                    : denoise::parse_non_negative_mode(options.non_negative_mode);
        if (settings.non_negative == denoise::NonNegativeMode::KeepSum &&
            transform.kind != denoise::TransformKind::None)
            throw usage_error(
                fmt::format("--non-negative-mode keep-sum would keep sums of transformed values: use "
                            "clamp with --transform {}",
                            options.transform));
    }
    if (options.shrink != "hard" && options.shrink != "optimal")
        throw usage_error(fmt::format("--shrink '{}' is not one of hard, optimal", options.shrink));
    settings.optimal_shrinkage = options.shrink == "optimal";
    if (options.weight_smoothing && options.no_weight_smoothing)
        throw usage_error("--weight-smoothing and --no-weight-smoothing contradict each other: give one");
    settings.weight_smoothing.enabled = !options.no_weight_smoothing;
    if (options.whiten != "auto" && options.whiten != "on" && options.whiten != "off")
        throw usage_error(fmt::format("--whiten '{}' is not one of auto, on, off", options.whiten));
    if (options.whiten == "on" && transform.kind != denoise::TransformKind::None)
        throw usage_error(fmt::format(
            "--whiten on cannot be combined with --transform {}: the variance layer is of the untransformed values",
            options.transform));
    if (options.frame_noise != "measured" && options.frame_noise != "even")
        throw usage_error(
            fmt::format("--frame-noise '{}' is not one of measured, even", options.frame_noise));
    settings.measured_frame_noise = options.frame_noise == "measured" && options.train_frames.empty();
    // The firefly clamp judges each frame at its own noise level whenever it is
    // measured (the training frames' fit aside: the clamp sees every frame).
    settings.outliers.per_frame_noise = options.frame_noise == "measured";
    if (settings.optimal_shrinkage && settings.mode_filter.enabled)
        throw usage_error(
            "--shrink optimal needs --no-mode-filter: the mode filter already shrinks each mode");
    // auto: the choice wherever it can run (it measured better than the rebuild
    // alone on every shot of bench/results/estimators.md, and the non-local means
    // within 0.4 % or better than without it); not on a rank map (a
    // map of the rebuild) nor on points (no image neighbours to blur).
    settings.estimators = options.estimators != "auto" ? denoise::parse_estimators(options.estimators)
                          : settings.rank_map.enabled || object_space
                              ? denoise::EstimatorOptions{}
                              : denoise::parse_estimators("rebuild,input,spatial,nlmeans");
    if (settings.estimators.enabled() && settings.rank_map.enabled)
        throw usage_error(
            "--estimators cannot be combined with --rank-map yet: the map is of the rebuild alone");
    return transform;
}

TransformStream::TransformStream(const denoise::Transform& transform, denoise::FrameSource& source,
                                 denoise::FrameSink& sink, denoise::Settings& settings,
                                 const VarianceNames& names, const MethodOptions& options)
    : m_transform(transform), m_source(source), m_sink(sink)
{
    m_whitening = choose_whitening(options.whiten, m_transform.kind != denoise::TransformKind::None, source,
                                   settings, names);
    apply_whitening(m_whitening, settings);
    if (m_transform.kind == denoise::TransformKind::None)
        return;
    if (m_transform.kind == denoise::TransformKind::Log) {
        m_shot_mean = denoise::sample_shot_mean(source);
        if (!(m_shot_mean > 0))
            throw bad_input(
                names.input,
                fmt::format("--transform log needs a shot whose mean is above 0 (it is {})", m_shot_mean));
        m_transform.epsilon = m_transform.epsilon_fraction * m_shot_mean;
    }
    settings.non_negative_floor = denoise::transformed_zero(m_transform);
    m_transform_source.emplace(source, m_transform);
    m_inverse_sink.emplace(sink, m_transform, source.shape());
}

namespace {
std::vector<double> smoothing_widths(const denoise::Report& report)
{
    std::vector<double> widths;
    for (const denoise::ModeSmoothing& mode : report.weight_smoothing.modes)
        widths.push_back(mode.width);
    return widths;
}

// Per frame: the share of pixels each estimator won and the RMS of its estimated
// error over them (sigma's own estimate).
nlohmann::ordered_json estimators_json(const denoise::EstimatorOptions& options,
                                       const denoise::Report& report, const std::vector<int>& frame_numbers)
{
    nlohmann::ordered_json names = nlohmann::ordered_json::array({"rebuild"});
    if (options.input)
        names.push_back("input");
    if (options.spatial)
        names.push_back("spatial");
    if (options.non_local)
        names.push_back("nlmeans");
    nlohmann::ordered_json json{
        {"set", names}, {"significance", options.significance}, {"radius", options.radius}};
    nlohmann::ordered_json frames = nlohmann::ordered_json::array();
    const int channels = std::max(report.shape.channels, 1);
    for (size_t t = 0; t < report.estimator_choice.size(); ++t) {
        const denoise::ChoiceCounts& counts = report.estimator_choice[t];
        std::int64_t pixels = 0;
        for (std::int64_t count : counts.pixels)
            pixels += count;
        nlohmann::ordered_json shares, errors;
        for (int k = 0; k < denoise::kEstimators; ++k) {
            const std::string name = denoise::estimator_name(static_cast<denoise::Estimator>(k));
            const std::int64_t won = counts.pixels[static_cast<size_t>(k)];
            shares[name] = pixels > 0 ? static_cast<double>(won) / static_cast<double>(pixels) : 0.0;
            errors[name] = won > 0 ? std::sqrt(counts.squared_error[static_cast<size_t>(k)] /
                                               static_cast<double>(won * channels))
                                   : 0.0;
        }
        frames.push_back(
            {{"frame", frame_numbers.at(t)}, {"share", shares}, {"estimated_rms_error", errors}});
    }
    json["frames"] = frames;
    return json;
}
} // namespace

nlohmann::ordered_json method_json(const TransformStream& stream, const denoise::Settings& settings,
                                   const denoise::Report& report, const SegmentRun& run,
                                   const std::vector<int>& frame_numbers)
{
    const denoise::Transform& transform = stream.transform();
    nlohmann::ordered_json json;
    json["transform"] = {{"name", denoise::transform_name(transform)}};
    if (transform.kind == denoise::TransformKind::Log)
        json["transform"].update({{"epsilon", transform.epsilon},
                                  {"epsilon_fraction", transform.epsilon_fraction},
                                  {"shot_mean", stream.shot_mean()}});
    json["non_negative"] = {{"mode", denoise::non_negative_mode_name(settings.non_negative)},
                            {"clamped_values", report.non_negative.clamped},
                            {"scaled_values", report.non_negative.scaled},
                            {"samples_changed", report.non_negative.samples}};
    json["shrink"] = {{"method", settings.optimal_shrinkage ? "optimal" : "hard"},
                      {"factors", report.shrinkage}};
    json["train_frames"] = {{"frames", settings.training_frames.size()},
                            {"of", report.shape.frames},
                            {"seconds_statistics", report.seconds_statistics}};
    nlohmann::ordered_json smoothing = nlohmann::ordered_json::array();
    for (const denoise::ModeSmoothing& mode : report.weight_smoothing.modes) {
        std::vector<int> jumps;
        for (int jump : mode.jumps)
            jumps.push_back(frame_numbers[static_cast<size_t>(jump)]);
        smoothing.push_back({{"noise", mode.noise},
                             {"width", mode.width},
                             {"sure_gain", mode.sure_gain},
                             {"jumps", jumps}});
    }
    json["whiten"] = whitening_json(stream.whitening());
    json["frame_noise"] = {{"model", report.frame_scales.empty() ? "even" : "measured"},
                           {"scales", report.frame_scales}};
    json["weight_smoothing"] = {{"enabled", settings.weight_smoothing.enabled}, {"modes", smoothing}};
    json["estimators"] = estimators_json(settings.estimators, report, frame_numbers);
    nlohmann::ordered_json parts = nlohmann::ordered_json::array();
    for (size_t k = 0; k < run.reports.size(); ++k) {
        const denoise::FrameSegment& segment = run.segments[k];
        const denoise::Report& part = run.reports[k];
        parts.push_back(
            {{"frames", fmt::format("{}-{}", frame_numbers[static_cast<size_t>(segment.first)],
                                    frame_numbers[static_cast<size_t>(segment.first + segment.count - 1)])},
             {"frame_count", segment.count},
             {"rank", part.rank_decision.kept_modes},
             {"rule", part.rank_decision.rule},
             {"singular_values", part.singular_values},
             {"shrink_factors", part.shrinkage},
             {"weight_smoothing_widths", smoothing_widths(part)}});
    }
    std::vector<int> cuts;
    for (int cut : run.search.cuts)
        cuts.push_back(frame_numbers[static_cast<size_t>(cut)]);
    json["segments"] = {{"mode", run.automatic          ? "auto"
                                 : run.segments.empty() ? "none"
                                                        : "list"},
                        {"cuts", cuts},
                        {"parts", parts}};
    if (run.automatic)
        json["segments"].update({{"distances", run.search.distances},
                                 {"distance_median", run.search.median},
                                 {"threshold", run.search.threshold}});
    return json;
}

} // namespace modestack::app
