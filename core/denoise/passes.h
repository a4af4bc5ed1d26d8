// The denoise as passes over explicit state (docs/design.md, "The passes and
// their data"). A whole run calls them in order,
//   statistics → solve → survey → modes → write,
// each a function of what the ones before returned; a farm task (farm_tasks.h)
// runs one of them over its share and hands the typed result on to be written
// to a stage file. Settings are never changed; the Report is assembled from the
// results and only reports.
#pragma once

#include "core/denoise/band_rebuild.h"
#include "core/denoise/block_gram.h"
#include "core/denoise/engine.h"
#include "core/denoise/shot_stream.h"
#include "core/denoise/stage_task.h"
#include "core/denoise/training.h"

#include <tbb/enumerable_thread_specific.h>

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
    RepeatingNoise
        repeating; ///< noise that repeats, measured by the run or its solve task (repeating_noise.h)
};

/// Checks the settings against the shot: a usage error for what the data
/// decides (too few frames, no pixels, training frames outside the shot), an
/// internal error for what the command's validation step must have refused
/// (N out of range, options that need each other).
void check_settings(const Settings& settings, const ShotShape& shape);

/// What pass 2 and the survey hold for a band (band_plan.h) of `shape` with
/// these settings and mode filter, the source keeping `source_row_bytes` per
/// row of a streamed band.
PassNeeds pass_needs(const Settings& settings, const ShotShape& shape, const ModeFilterOptions& filter,
                     std::int64_t source_row_bytes);
/// The solver the settings ask for, or auto's choice for the shot.
Solver plan_solver(const Settings& settings, const ShotShape& shape);

/// Plans the bands and picks the solver for checked settings; `with_features`:
/// open the mode filter's feature guide (a run or task that filters).
RunPlan plan_run(const PassContext& context, bool with_features);

/// The temporal modes and N.
struct Solution {
    lowrank::Basis basis;
    lowrank::RankDecision rank_decision;
    std::optional<TrainingGram> training; ///< --train-frames: the projection and the rebuild differ
    double seconds = 0;                   ///< the eigensolve or randomized SVD
    /// D, each frame's noise level the modes were fitted with (frame_weighting.h); empty: even.
    Eigen::VectorXd frame_scales;
};

/// The mode filter's choice: a filter per mode and N (its SURE choice for auto
/// N; without the mode filter, the solution's).
struct Survey {
    int modes = 0; ///< modes surveyed (0: no mode filter)
    ModeFilterPlan plan;
    lowrank::RankDecision rank_decision;
};

/// Pass 1 with the Gram solver (or --train-frames) band by band, and the solve.
class GramPass {
public:
    GramPass(const Settings& settings, const ShotShape& shape);
    /// Adds a band of a pass over the shot (ShotStream::BandPass), in row order.
    void add(Band& band);
    /// The modes and N from every band's sums and each frame's noise factor
    /// (frame_noise.h, of the pass's first read as cleaned: the sums' samples).
    Solution finish(const std::vector<double>& noise_factors);

private:
    const Settings& m_settings;
    ShotShape m_shape;
    BlockGram m_gram;
    std::optional<TrainingGram> m_training;
    std::vector<float> m_scratch;
};

/// Pass 1 of a whole run with the Gram solver (or --train-frames) and the solve.
Solution gram_solution(const PassContext& context, ShotStream& stream);
/// The randomized SVD's passes over the shot and the solve.
Solution randomized_solution(const PassContext& context, ShotStream& stream);
/// The solve from merged Gram sums and the frames' noise factors (a farm's solve and later tasks).
Solution solution_from_gram(const Settings& settings, const lowrank::GramAccumulator& gram,
                            const std::vector<double>& noise_factors);

/// Pass 1 of a farm statistics task: rows [row_begin, row_end), each block's sums kept apart.
Statistics block_statistics(const PassContext& context, ShotStream& stream, int row_begin, int row_end);

/// Modes the mode filter surveys (and the K of its noise estimate): at most F − 2
/// so that the noise estimate has two degrees of freedom, at least a fixed N.
int survey_modes(const Settings& settings, const ShotShape& shape, const lowrank::Basis& basis);

/// The mode filter's survey of image rows [row_begin, row_end) band by band:
/// the kept shot or bands with their halo of a whole run, or (`task`) bands
/// read by a farm task.
class SurveyPass {
public:
    SurveyPass(const PassContext& context, ShotStream& stream, const RunPlan& plan, const Solution& solution,
               int row_begin, int row_end, bool task);
    /// Adds rows [row, end): the next band of at most plan.bands.halo_band_rows rows.
    void add_rows(int row, int end);
    /// The survey's sums of every row (SureSurvey::row_sums).
    std::vector<std::vector<double>> finish();

private:
    const PassContext& m_context;
    ShotStream& m_stream;
    const RunPlan& m_plan;
    bool m_task;
    int m_row_begin, m_row_end;
    int m_modes;
    Eigen::MatrixXd m_temporal;     // the projection A
    Eigen::VectorXd m_frame_scales; // D (empty: even)
    SureSurvey m_survey;
    Band m_band;
    std::vector<float> m_coefficients, m_noise_variance, m_features;
};

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
    std::vector<double> frame_noise_factors;    ///< per frame (--estimators; empty: none)
};

/// Pass 2 band by band: every frame rebuilt into the sink. Starts the sink (begin) on construction.
class RebuildPass {
public:
    RebuildPass(const PassContext& context, ShotStream& stream, const RunPlan& plan, const Solution& solution,
                const Survey& survey, const RebuildBasis& modes);
    /// Rebuilds and writes rows [row, end) of every frame: the next band of at
    /// most plan.bands.halo_band_rows rows.
    void add_rows(int row, int end);
    RebuildReport finish();

private:
    struct Chosen { // one frame's estimator choice
        std::vector<float> values, sigma;
        std::vector<std::uint8_t> estimators;    // per pixel
        std::vector<float> spread, spread_terms; // per pixel: the input's spread in time
        std::vector<float> judged;               // the frame's rows the spread judges
        std::vector<float> misfit;               // per pixel: the residual's statistics in time
    };
    const PassContext& m_context;
    ShotStream& m_stream;
    const RunPlan& m_plan;
    const Solution& m_solution;
    const RebuildBasis& m_modes;
    BandRebuilder m_rebuilder;
    RebuildReport m_report;
    Band m_band;
    // Reused from band to band: fresh buffers of this size cost the kernel's page
    // zeroing every band (7.5 % of a 1080p run's time).
    ScratchBuffer<float> m_kept_sigma; // sigma_from_mean writes every value
    tbb::enumerable_thread_specific<std::vector<float>> m_kept_noise_of_worker; // one frame's
    tbb::enumerable_thread_specific<Chosen> m_chosen_of_worker;
    tbb::enumerable_thread_specific<ScratchBuffer<float>> m_raw_of_worker; // one frame's input rows the
                                                                           // choice reads, unclean
    std::vector<float> m_noise_scale; // the choice's noise scale of the band's rebuilt rows
    std::vector<float> m_pair_terms;  // the spread's per-pixel terms of each pair of frames, the band's rows
    std::vector<float> m_ranks;
};

/// Pass 2 of a whole run: every frame rebuilt band by band into the sink.
RebuildReport rebuild_shot(const PassContext& context, ShotStream& stream, const RunPlan& plan,
                           const Solution& solution, const Survey& survey, const RebuildBasis& modes);

/// The report's description of the modes: singular values, explained energy,
/// pt(t, j) for j < N and the preview beyond it.
void describe_solution(const Settings& settings, const ShotShape& shape, const Solution& solution,
                       int kept_modes, Report& report);

} // namespace modestack::denoise
