// The denoise as passes over explicit state (docs/design.md, "The passes and
// their data"). A whole run calls them in order,
//   statistics → solve → survey → modes → write,
// each a function of what the ones before returned; a farm task (farm_tasks.h)
// runs one of them over its share and hands the typed result on to be written
// to a stage file. Settings are never changed; the Report is assembled from the
// results and only reports.
#pragma once

#include "core/denoise/band_rebuild.h"
#include "core/denoise/engine.h"
#include "core/denoise/shot_stream.h"
#include "core/denoise/stage_task.h"
#include "core/denoise/training.h"

#include <optional>

namespace modestack::denoise {

/// What every pass of one run shares: the shot's two ends, the settings and progress.
struct PassContext {
    FrameSource& source;
    FrameSink& sink;
    const Settings& settings;
    Progress& progress;
};

/// What is decided before the first read.
struct RunPlan {
    BandPlan bands;
    Solver solver = Solver::Gram;
    ModeFilterOptions filter;             ///< the settings' with the feature channels found
    std::optional<FeatureGuide> features; ///< the mode filter's feature guide (none: unguided)
};

/// Checks the settings against the shot: a usage error for what the data
/// decides (too few frames, no pixels, training frames outside the shot), an
/// internal error for what the command's validation step must have refused
/// (N out of range, options that need each other).
void check_settings(const Settings& settings, const ShotShape& shape);

/// Plans the bands and picks the solver for checked settings; `with_features`:
/// open the mode filter's feature guide (a run or task that filters).
RunPlan plan_run(const PassContext& context, bool with_features);

/// The temporal modes and N.
struct Solution {
    lowrank::Basis basis;
    lowrank::RankDecision rank_decision;
    std::optional<TrainingGram> training; ///< --train-frames: the projection and the rebuild differ
    double seconds = 0;                   ///< the eigensolve or randomized SVD
};

/// The mode filter's choice: a filter per mode and N (its SURE choice for auto
/// N; without the mode filter, the solution's).
struct Survey {
    int modes = 0; ///< modes surveyed (0: no mode filter)
    ModeFilterPlan plan;
    lowrank::RankDecision rank_decision;
};

/// Pass 1 of a whole run with the Gram solver (or --train-frames) and the solve.
Solution gram_solution(const PassContext& context, ShotStream& stream);
/// The randomized SVD's passes over the shot and the solve.
Solution randomized_solution(const PassContext& context, ShotStream& stream);
/// The solve from merged Gram sums (a farm's solve and later tasks).
Solution solution_from_gram(const Settings& settings, const lowrank::GramAccumulator& gram);

/// Pass 1 of a farm statistics task: rows [row_begin, row_end), each block's sums kept apart.
Statistics block_statistics(const PassContext& context, ShotStream& stream, int row_begin, int row_end);

/// Modes the mode filter surveys (and the K of its noise estimate): at most F − 2
/// so that the noise estimate has two degrees of freedom, at least a fixed N.
int survey_modes(const Settings& settings, const ShotShape& shape, const lowrank::Basis& basis);

/// The survey's sums of image rows [row_begin, row_end) (SureSurvey::row_sums):
/// the kept shot or bands with their halo of a whole run, or (`task`) bands read
/// by a farm task.
std::vector<std::vector<double>> survey_rows(const PassContext& context, ShotStream& stream,
                                             const RunPlan& plan, const Solution& solution, int row_begin,
                                             int row_end, bool task);

/// The filters and (auto N) N from the sums of every row.
Survey finish_survey(const Settings& settings, const ShotShape& shape, const RunPlan& plan,
                     const Solution& solution, std::vector<std::vector<double>> rows);
/// Without the mode filter: N as the solution chose it.
Survey unfiltered_survey(const Solution& solution);

/// Pass 2's temporal matrices for the survey's N, and what the report says of
/// the chosen modes: N and why, the filters, the spectrum, shrinkage and
/// weight smoothing. A whole run and the farm's modes and write tasks alike.
RebuildBasis chosen_modes(const Settings& settings, const ShotShape& shape, const Solution& solution,
                          const Survey& survey, Report& report);

/// The estimator choice of rows [row, end) of one frame (estimator_choice.h),
/// with --non-negative's floor applied to the chosen values: pass 2 of a whole
/// run and a farm's write task alike.
ChoiceCounts choose_frame_rows(const Settings& settings, const ChoiceFrame& frame, int row, int end,
                               float* values, float* sigma, std::uint8_t* chosen);

/// What pass 2 reports besides the outputs.
struct RebuildReport {
    NonNegativeCounts non_negative;
    RankMapSummary rank_map;
    std::vector<ChoiceCounts> estimator_choice; ///< per frame (--estimators; empty: none)
};

/// Pass 2 of a whole run: every frame rebuilt band by band into the sink.
RebuildReport rebuild_shot(const PassContext& context, ShotStream& stream, const RunPlan& plan,
                           const Solution& solution, const Survey& survey, const RebuildBasis& modes);

/// The report's description of the modes: singular values, explained energy,
/// pt(t, j) for j < N and the preview beyond it.
void describe_solution(const Settings& settings, const ShotShape& shape, const Solution& solution,
                       int kept_modes, Report& report);

} // namespace modestack::denoise
