// The options of `denoise` that change the method itself (issue 8): --transform,
// --non-negative, --non-negative-mode, --shrink, --segments, --train-frames, --weight-smoothing,
// --whiten, --frame-noise and --estimators. Adds them to the command,
// checks their values and combinations before any work (usage errors, exit 2),
// puts them into the engine's settings, wraps the engine's ends in the
// transform's decorators (core/denoise/transform.h) and writes their JSON block.
#pragma once

#include "app/whitening_choice.h"
#include "core/denoise/engine.h"
#include "core/denoise/segments.h"
#include "core/denoise/transform.h"

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <optional>
#include <string>

namespace modestack::app {

/// The values as typed.
struct MethodOptions {
    std::string transform = "none";
    bool non_negative = false;
    std::string non_negative_mode; ///< "" = the default (clamp)
    std::string shrink = "hard";
    std::string segments;     ///< "" = one part, "auto" or a list "1-30,31-60"
    std::string train_frames; ///< "" = all frames, else a frame range
    bool weight_smoothing = false;    ///< --weight-smoothing (the default anyway)
    bool no_weight_smoothing = false; ///< --no-weight-smoothing
    std::string whiten = "auto"; ///< auto, on or off
    std::string frame_noise = "measured"; ///< measured or even
    /// "auto" (every estimator where the choice can run), or comma-separated:
    /// rebuild, input, spatial
    std::string estimators = "auto";
};

/// Adds the options to `command`.
void add_method_options(CLI::App& command, MethodOptions& options);

/// Checks the values and combinations (throws usage errors naming the option) and
/// fills `settings` (after the other options set it, mode filter included);
/// `object_space`: the points job denoises (no image neighbours for the
/// estimator choice). Returns the parsed transform, its log offset not yet known.
denoise::Transform apply_method_options(const MethodOptions& options, bool object_space,
                                        denoise::Settings& settings);

/// The parts of --segments: a list checked against the shot's frame numbers
/// before any work (usage errors), or found from the data when `auto`.
struct SegmentRun {
    std::vector<denoise::FrameSegment> segments; ///< empty until known (auto)
    bool automatic = false;
    denoise::CutSearch search;            ///< what auto saw
    std::vector<denoise::Report> reports; ///< one per part
};

/// Parses --train-frames (frame numbers of the shot) into settings.training_frames
/// (indices); usage errors name the option.
void apply_training_frames(const MethodOptions& options, const std::vector<int>& frame_numbers,
                           denoise::Settings& settings);

/// Checks --segments (and that it is not combined with --save-modes or
/// --train-frames) and parses a list.
SegmentRun plan_segments(const MethodOptions& options, const std::vector<int>& frame_numbers,
                         bool save_modes);

/// Runs the engine once, or once per part (finding auto cuts first); returns the
/// merged report (denoise::merge_reports).
denoise::Report run_segmented(SegmentRun& run, denoise::FrameSource& source, denoise::FrameSink& sink,
                              const denoise::Settings& settings, Progress& progress);

/// The engine's ends with --transform and --whiten in place: for log, ε is set
/// from the mean of a few frames of `source`, and the floor of --non-negative to
/// f(0); --whiten (app/whitening_choice.h has the rule: each layer apart on its
/// own variance) reads the variance layers once for their weights and points
/// settings.whitening or settings.layer_whitening at them.
class TransformStream {
public:
    /// `source` and `sink` must outlive this object; `names.input` names the shot in errors.
    TransformStream(const denoise::Transform& transform, denoise::FrameSource& source,
                    denoise::FrameSink& sink, denoise::Settings& settings, const VarianceNames& names,
                    const MethodOptions& options = {});
    denoise::FrameSource& source() { return m_transform_source ? *m_transform_source : m_source; }
    denoise::FrameSink& sink() { return m_inverse_sink ? *m_inverse_sink : m_sink; }
    const denoise::Transform& transform() const { return m_transform; }
    /// The sampled shot mean behind log's ε (0 when not needed).
    double shot_mean() const { return m_shot_mean; }
    /// What --whiten decided: one part for one set of modes, else one per layer.
    const std::vector<WhitenedPart>& whitening() const { return m_whitening; }

private:
    denoise::Transform m_transform;
    double m_shot_mean = 0;
    denoise::FrameSource& m_source;
    denoise::FrameSink& m_sink;
    std::vector<WhitenedPart> m_whitening;
    std::optional<denoise::TransformSource> m_transform_source;
    std::optional<denoise::InverseTransformSink> m_inverse_sink;
};

/// The "method" block of the --json summary: transform, non-negative counts,
/// shrinkage, segments (cuts as frame numbers, each part's N and spectrum).
nlohmann::ordered_json method_json(const TransformStream& stream, const denoise::Settings& settings,
                                   const denoise::Report& report, const SegmentRun& run,
                                   const std::vector<int>& frame_numbers);

} // namespace modestack::app
