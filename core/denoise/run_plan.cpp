// What a denoise decides before its first read (passes.h): the checks of the
// settings against the shot, the band plan for the memory budget, the
// solver, and the mode filter's feature guide.
#include "core/denoise/passes.h"

#include "core/common/error.h"

#include <fmt/format.h>
#include <tbb/task_arena.h>

#include <algorithm>

namespace modestack::denoise {
namespace {

// Per-sample images the mode filter's guide holds over a band with its halo: the
// guide and its noise (float) and the smoothing's horizontal pass (double), see
// filter_weights.cpp.
constexpr int kGuideImages = 4;

} // namespace

void check_settings(const Settings& settings, const ShotShape& shape)
{
    // What the data decides: usage errors, whoever calls.
    if (shape.frames < 3)
        throw usage_error(fmt::format("denoising needs at least 3 frames, got {}", shape.frames));
    if (shape.width <= 0 || shape.height <= 0 || shape.channels <= 0)
        throw usage_error("the shot has no pixels");
    if (!settings.training_frames.empty())
        check_training_frames(settings, shape.frames);
    // What the command's validation step already refused (app/denoise_job.cpp,
    // method_options.cpp): reaching here is a bug, so an internal error.
    if (settings.rank_rule.rule == lowrank::RankRule::Fixed &&
        (settings.rank_rule.fixed_modes < 1 || settings.rank_rule.fixed_modes >= shape.frames))
        throw internal_error(fmt::format("--rank {} is out of range: use 1 to {} for {} frames",
                                         settings.rank_rule.fixed_modes, shape.frames - 1, shape.frames));
    if (settings.sigma_radius < 0)
        throw internal_error("--sigma-radius must be 0 or more");
    if (settings.rank_map.enabled && !settings.mode_filter.enabled)
        throw internal_error(
            "--rank-map needs the mode filter: the local estimates use its noise and filters");
    if (settings.optimal_shrinkage && settings.mode_filter.enabled)
        throw internal_error(
            "--shrink optimal needs --no-mode-filter: the mode filter already shrinks each mode");
    if (settings.estimators.enabled() && settings.rank_map.enabled)
        throw internal_error("--estimators and --rank-map do not go together yet");
    if (settings.whitening &&
        settings.whitening->size() != static_cast<size_t>(shape.width) * shape.height * shape.channels)
        throw internal_error("the whitening weights do not match the shot");
}

PassNeeds pass_needs(const Settings& settings, const ShotShape& shape, const ModeFilterOptions& filter,
                     std::int64_t source_row_bytes)
{
    const int largest_rank = settings.rank_rule.rule == lowrank::RankRule::Fixed
                                 ? settings.rank_rule.fixed_modes
                                 : std::min(shape.frames - 1, 32);
    // Sigma's window reads radius + 1 rows around a pixel (see confidence.h); the
    // mode filter reads its kernel and guide around a pixel.
    PassNeeds needs;
    needs.halo_rows = needs.sigma_halo_rows = settings.sigma_radius + 1;
    needs.halo_images = largest_rank; // the projected coefficients
    needs.source_row_bytes = source_row_bytes;
    if (settings.mode_filter.enabled) {
        needs.halo_rows = std::max(needs.halo_rows, mode_filter_halo(filter));
        // Over the halo: the surveyed coefficients, the guide with its noise (a
        // few images) and the feature rows twice (as read and the guide's planar
        // copy); the survey alone also holds its [pixel][mode] copy. Over the
        // band: the filtered coefficients, their gains and one frame's kept
        // noise per worker.
        const int surveyed = std::max(settings.mode_filter.max_modes, largest_rank);
        needs.survey_images = surveyed;
        needs.halo_images =
            surveyed + kGuideImages + 2 * ((filter.feature_channels + shape.channels - 1) / shape.channels);
        needs.band_images = 2 * surveyed + tbb::this_task_arena::max_concurrency();
    }
    // Each worker's residual rows (double) of sigma's windows.
    needs.band_images += 4 * tbb::this_task_arena::max_concurrency();
    // The estimator choice: more rows rebuilt around each band (and so read), and
    // each worker's planes of one frame (about 13 images: estimator_choice.cpp; 3 of them the
    // input's high-pass power that bounds v).
    if (settings.estimators.enabled()) {
        needs.choice_rows = estimator_rebuilt_reach(settings.estimators);
        needs.choice_workers = tbb::this_task_arena::max_concurrency();
        needs.halo_rows =
            std::max(needs.halo_rows + needs.choice_rows, estimator_input_reach(settings.estimators));
        needs.band_images += 13 * needs.choice_workers;
    }
    return needs;
}

Solver plan_solver(const Settings& settings, const ShotShape& shape)
{
    if (settings.solver != Solver::Auto)
        return settings.solver;
    return shape.frames >= settings.randomized_from_frames && settings.training_frames.empty()
               ? Solver::RandomizedSvd
               : Solver::Gram;
}

RunPlan plan_run(const PassContext& context, bool with_features)
{
    const Settings& settings = context.settings;
    const ShotShape shape = context.source.shape();
    RunPlan plan;
    plan.filter = settings.mode_filter;
    if (settings.mode_filter.enabled && !settings.feature_guide.kinds.empty() && with_features) {
        plan.features.emplace(context.source, settings.feature_guide, context.progress);
        plan.filter.feature_channels = plan.features->channels();
    }
    plan.bands = plan_bands(shape, settings.max_memory_bytes,
                            pass_needs(settings, shape, plan.filter, context.source.band_bytes_per_row()));
    plan.solver = plan_solver(settings, shape);
    return plan;
}

} // namespace modestack::denoise
