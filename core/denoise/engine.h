// The temporal low-rank denoiser as a stream (docs/design.md, "The passes and
// their data"): pass 1 reads bands of every frame, cleans NaN/Inf and fireflies
// and accumulates the Gram matrix XᵀX; the small eigenproblem (or the randomized
// SVD) gives the temporal modes; a rank rule picks N; pass 2 reads the bands again
// (with halo rows), rebuilds every frame from the first N modes and estimates the
// standard error of each rebuilt value. With the mode filter (mode_filter.h) a
// survey pass between them chooses each mode's spatial filter by SURE (and N for
// auto rank), and pass 2 filters the coefficient images before the rebuild and
// tells sigma how much noise each filtered sample keeps. When the shot fits the
// memory budget it is read once and kept. Results are bit-identical for any
// thread count and for streaming versus in-memory runs.
//
// This header holds the settings, the report and the whole run; the passes
// themselves are in passes.h, a farm's share of them in farm_tasks.h.
#pragma once

#include "core/common/progress.h"
#include "core/denoise/band_plan.h"
#include "core/denoise/estimator_choice.h"
#include "core/denoise/feature_guide.h"
#include "core/denoise/frame_stream.h"
#include "core/denoise/mode_filter.h"
#include "core/denoise/non_negative.h"
#include "core/denoise/rank_map.h"
#include "core/denoise/repeating_noise.h"
#include "core/denoise/weight_smoothing.h"
#include "core/lowrank/outliers.h"
#include "core/lowrank/randomized_svd.h"
#include "core/lowrank/rank_rule.h"

#include <cstdint>
#include <string>
#include <vector>

namespace modestack::denoise {

/// How the temporal modes are found.
enum class Solver { Auto, Gram, RandomizedSvd };

/// Parses "auto", "gram" or "rsvd"; throws a usage error otherwise.
Solver parse_solver(const std::string& name);
/// "gram" or "rsvd".
std::string solver_name(Solver solver);

/// Every setting of a denoise run.
struct Settings {
    Solver solver = Solver::Auto;
    lowrank::RankRuleOptions rank_rule; ///< rule (default press) or fixed N
    lowrank::OutlierOptions outliers;
    int sigma_radius = 2; ///< spatial pooling radius of the sigma estimate (pixels)
    std::int64_t max_memory_bytes = std::int64_t(2) << 30;
    /// Randomized SVD: modes computed (the rank rule chooses among them).
    int randomized_modes = 24;
    lowrank::RandomizedSvdOptions randomized;
    /// Auto picks the randomized SVD from this many frames on. bench/denoise.sh measured
    /// gram faster at F = 48, 200 and 800 (each rsvd pass re-reads the shot); the rates
    /// put the break-even near F = 2000.
    int randomized_from_frames = 2000;
    /// Spatial filtering of the modes; when enabled, `auto` rank is chosen by its SURE
    /// survey instead of rank.rule (see mode_filter.h).
    ModeFilterOptions mode_filter;
    /// Features that guide the mode filter when the input has them (feature_guide.h);
    /// no kinds: none.
    FeatureGuideOptions feature_guide;
    /// --non-negative: correction of rebuilt values below non_negative_floor
    /// (non_negative.h); the floor is f(0) under a --transform.
    NonNegativeMode non_negative = NonNegativeMode::Off;
    float non_negative_floor = 0.0f;
    /// --shrink optimal: scale the kept modes by Gavish–Donoho's Frobenius-optimal
    /// factors (lowrank/shrinkage.h) instead of keeping them whole; needs the mode filter off.
    bool optimal_shrinkage = false;
    /// --train-frames: ascending frame indices the modes are computed from (empty:
    /// all); every frame is projected on them (training.h). Gram solver, no mode filter.
    std::vector<int> training_frames;
    /// --rank-map: a per-pixel fractional rank (rank_map.h); needs the mode filter.
    RankMapOptions rank_map;
    /// --weight-smoothing: smooth each rebuilt mode's temporal weights over time
    /// (weight_smoothing.h).
    WeightSmoothingOptions weight_smoothing;
    /// --whiten: a weight per sample of the image ([row][x][channel]); the modes come
    /// from the weighted rows, everything else from the rows as read (whitening.h).
    const std::vector<float>* whitening = nullptr;
    /// --whiten with the layers apart (layer_channels): each layer's own weights
    /// ([row][x][channel of the layer], whitening.h's layer_whitening_weights),
    /// null for a layer that is not whitened; empty: no layer is. `whitening`
    /// (weights of every channel together) is then null.
    std::vector<const std::vector<float>*> layer_whitening;
    /// --estimators: a per-pixel choice among the rebuild and other estimators
    /// (estimator_choice.h); none enabled: the rebuild everywhere.
    EstimatorOptions estimators;
    /// --frame-noise: fit the modes to each frame's measured noise level
    /// (frame_weighting.h; with the Gram solver and no training frames); false: even.
    bool measured_frame_noise = true;
    /// Channels of each layer denoised on its own modes and N, in the order of
    /// the selected channels (layer_runs.h); empty or one layer: every channel
    /// shares the modes (--joint).
    std::vector<int> layer_channels;
    /// --report: also report pt(t, j) for j < max(2N, report_modes), capped at F − 1
    /// and at the modes found (Report::preview_temporal_modes, the rank slider); 0: none.
    int report_modes = 0;
};

/// What a run did and found, for the JSON summary and the report.
struct Report {
    ShotShape shape;
    BandPlan plan;
    std::string solver;
    int passes = 0; ///< reads of the whole shot
    lowrank::RankDecision rank_decision;
    std::vector<double> singular_values;             ///< σ_j, descending
    std::vector<double> explained;                   ///< σ_j² / total energy, per mode
    std::vector<std::vector<double>> temporal_modes; ///< pt(t, j) for j < N: [j][t]
    /// The weights every frame was rebuilt from (pt smoothed over time, more than
    /// N with --rank-map): [j][t]. Each rebuilt frame t is Σ_j c_j B(t, j) for
    /// coefficient images c_j, before --non-negative.
    std::vector<std::vector<double>> rebuild_weights;
    /// pt(t, j) beyond N for the report's rank slider (Settings::report_modes): [j][t].
    std::vector<std::vector<double>> preview_temporal_modes;
    lowrank::OutlierCounts outliers;
    ModeFilterPlan mode_filter;           ///< per-mode filters and SURE (empty when off)
    FeatureGuideSummary feature_guide;    ///< the features that guided it (empty: none)
    NonNegativeCounts non_negative;       ///< what --non-negative changed
    std::vector<double> shrinkage;        ///< per kept mode η(σ_j)/σ_j (empty: hard truncation)
    RankMapSummary rank_map;              ///< the per-pixel ranks (largest_rank 0: no map)
    WeightSmoothingPlan weight_smoothing; ///< what --weight-smoothing did per kept mode
    /// --estimators: per frame, what each estimator won (empty: no choice made).
    std::vector<ChoiceCounts> estimator_choice;
    /// --estimators: per frame, its noise level over the shot's (frame_noise.h; empty: no choice made).
    std::vector<double> frame_noise_factors;
    /// The frame scales D the modes were fitted with (--frame-noise measured,
    /// frame_weighting.h); empty: even noise.
    std::vector<double> frame_scales;
    /// The noise found to repeat from frame to frame (unmeasured: a farm task that writes no frame).
    RepeatingNoise repeating_noise;
    double seconds_filter_survey = 0;     ///< the mode filter's SURE pass
    double seconds_statistics = 0;        ///< pass 1 (read + clean + Gram)
    double seconds_solve = 0;             ///< eigensolve or randomized SVD, and the rank rule
    double seconds_rebuild = 0;           ///< pass 2 (read + rebuild + sigma + write)
    /// Each layer's own report when the layers have their own modes
    /// (Settings::layer_channels), in order; empty otherwise.
    std::vector<Report> layers;
};

/// Denoises `source` into `sink`: every pass of passes.h in order. Throws
/// modestack::Error on bad settings (fewer than 3 frames, N out of range, memory
/// too small) and cancellation.
Report run_denoise(FrameSource& source, FrameSink& sink, const Settings& settings, Progress& progress);

} // namespace modestack::denoise
