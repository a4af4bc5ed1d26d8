#include "core/denoise/farm_tasks.h"

#include "core/common/error.h"
#include "core/denoise/band_rebuild.h"
#include "core/denoise/block_gram.h"
#include "core/denoise/frame_noise.h"
#include "core/denoise/frame_weighting.h"
#include "core/denoise/stage_modes.h"
#include "core/denoise/temporal_misfit.h"
#include "core/denoise/temporal_spread.h"
#include "core/lowrank/confidence.h"
#include "core/lowrank/projection.h"

#include <fmt/format.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <map>
#include <mutex>
#include <set>

namespace modestack::denoise {
namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point start)
{
    return std::chrono::duration<double>(Clock::now() - start).count();
}

// What no farm task can do (each needs the whole shot in one process). The
// command refuses these first (app/denoise_stages.cpp, denoise_job.cpp), so
// here they are internal errors.
void check_task(const Settings& settings, Stage stage)
{
    const std::string name = stage_name(stage);
    if (settings.solver == Solver::RandomizedSvd)
        throw internal_error(
            fmt::format("--stage {}: the farm stages use the gram solver, not --method rsvd", name));
    if (!settings.training_frames.empty())
        throw internal_error(fmt::format("--stage {} cannot be combined with --train-frames", name));
    if (stage != Stage::Statistics && stage != Stage::Solve &&
        settings.non_negative == NonNegativeMode::KeepSum)
        throw internal_error(
            fmt::format("--stage {} cannot be combined with --non-negative-mode keep-sum: it "
                        "needs every frame of a pixel; use clamp or run on one machine",
                        name));
}

// The checks, the plan and the first report fields of a task of `stage` over
// rows [row_begin, row_end) (stats, survey and modes; the others ignore them).
RunPlan plan_task(const PassContext& context, Stage stage, Report& report, int row_begin = 0, int row_end = 0)
{
    const ShotShape shape = context.source.shape();
    check_settings(context.settings, shape);
    check_task(context.settings, stage);
    if (stage == Stage::Statistics)
        check_statistics_rows(row_begin, row_end, shape.height);
    if (stage == Stage::Survey || stage == Stage::Modes)
        check_task_rows(row_begin, row_end, shape.height);
    RunPlan plan = plan_run(context, stage != Stage::Statistics && stage != Stage::Solve);
    plan.solver = Solver::Gram;
    report.shape = context.source.shape();
    report.plan = plan.bands;
    report.solver = solver_name(plan.solver);
    if (plan.features)
        report.feature_guide = plan.features->summary();
    return plan;
}

// What the modes and write tasks start from: the modes from the merged sums,
// the survey's choice (filters and N) from every row's sums, and pass 2's
// temporal matrices.
struct Solved {
    Solution solution;
    Survey survey;
    RebuildBasis modes;
};

Solved solved_from(const PassContext& context, const RunPlan& plan, const SolvedSums& solved,
                   const SurveyRows& survey, Report& report)
{
    const ShotShape shape = context.source.shape();
    Solved result{solution_from_gram(context.settings, solved.gram, solved.frame_scale_factors), {}, {}};
    report.outliers = solved.outliers;
    if (context.settings.mode_filter.enabled) {
        if (static_cast<int>(survey.sums.size()) != shape.height)
            throw internal_error("the modes and write stages need the mode filter's survey of every row");
        result.survey = finish_survey(context.settings, shape, plan, result.solution, survey.sums);
    } else {
        result.survey = unfiltered_survey(result.solution);
    }
    result.modes = chosen_modes(context.settings, shape, result.solution, result.survey, report);
    return result;
}

} // namespace

TaskResult<Statistics> statistics_task(const PassContext& context, int row_begin, int row_end)
{
    TaskResult<Statistics> result;
    const RunPlan plan = plan_task(context, Stage::Statistics, result.report, row_begin, row_end);
    const auto start = Clock::now();
    ShotStream stream(context.source, context.settings.outliers, plan.bands, context.progress);
    result.output = block_statistics(context, stream, row_begin, row_end);
    result.report.passes = stream.passes();
    result.report.outliers = stream.outliers();
    result.report.seconds_statistics = seconds_since(start);
    return result;
}

TaskResult<SolvedSums> solve_task(const PassContext& context, const Statistics& shot)
{
    TaskResult<SolvedSums> result;
    plan_task(context, Stage::Solve, result.report);
    if (static_cast<int>(shot.blocks.size()) != stage_blocks(result.report.shape.height))
        throw internal_error("the solve stage needs every block's sums");
    const auto start = Clock::now();
    result.output.gram = BlockGram::merge(shot.blocks, result.report.shape.frames);
    result.output.outliers = shot.outliers;
    result.output.frame_noise_factors = frame_noise_factors(shot.roughness, result.report.shape.frames);
    result.output.frame_scale_factors =
        frame_scale_factors(shot.cleaned_roughness, result.report.shape.frames);
    // Once for the shot, here rather than in every write task (which then reads only its frames' reach).
    result.output.repeating = result.report.repeating_noise =
        measure_repeating_noise(context.source, context.progress);
    const Solution solution =
        solution_from_gram(context.settings, result.output.gram, result.output.frame_scale_factors);
    result.report.outliers = shot.outliers;
    result.report.rank_decision = solution.rank_decision;
    describe_solution(context.settings, result.report.shape, solution, solution.rank_decision.kept_modes,
                      result.report);
    result.report.seconds_solve = seconds_since(start);
    return result;
}

TaskResult<SurveyRows> survey_task(const PassContext& context, const SolvedSums& solved, int row_begin,
                                   int row_end)
{
    TaskResult<SurveyRows> result;
    const RunPlan plan = plan_task(context, Stage::Survey, result.report, row_begin, row_end);
    const auto start = Clock::now();
    const Solution solution = solution_from_gram(context.settings, solved.gram, solved.frame_scale_factors);
    result.report.outliers = solved.outliers;
    result.report.rank_decision = solution.rank_decision;
    result.output.row_begin = row_begin;
    result.output.row_end = row_end;
    if (context.settings.mode_filter.enabled) {
        const auto survey_start = Clock::now();
        ShotStream stream(context.source, context.settings.outliers, plan.bands, context.progress);
        result.output.sums = survey_rows(context, stream, plan, solution, row_begin, row_end, true);
        result.report.passes = stream.passes();
        result.report.seconds_filter_survey = seconds_since(survey_start);
    } else { // nothing to survey: the task reports the modes as the solve did
        describe_solution(context.settings, result.report.shape, solution, solution.rank_decision.kept_modes,
                          result.report);
    }
    result.report.seconds_solve =
        seconds_since(start) - result.report.seconds_filter_survey + solution.seconds;
    return result;
}

TaskResult<ModeImages> modes_task(const PassContext& context, const SolvedSums& solved,
                                  const SurveyRows& survey, int row_begin, int row_end)
{
    TaskResult<ModeImages> result;
    Report& report = result.report;
    RunPlan plan = plan_task(context, Stage::Modes, report, row_begin, row_end);
    plan.repeating = report.repeating_noise = solved.repeating; // the survey's noise scales count it
    const ShotShape& shape = report.shape;
    const Solved modes_of = solved_from(context, plan, solved, survey, report);
    const Settings& settings = context.settings;
    const RebuildBasis& modes = modes_of.modes;
    const auto start = Clock::now();
    BandRebuilder rebuilder(settings, shape, modes, plan.filter, modes_of.survey.plan, modes_of.survey.modes,
                            plan.features ? &*plan.features : nullptr);
    ShotStream stream(context.source, settings.outliers, plan.bands, context.progress);
    const std::int64_t row_samples = stream.row_samples();
    const std::int64_t samples = row_samples * (row_end - row_begin);
    const std::int64_t pixels = samples / shape.channels;
    ModeImages& images = result.output;
    images.row_begin = row_begin;
    images.row_end = row_end;
    images.residual_modes = modes.kept_modes;
    images.output_modes = modes.output_modes;
    images.gain_modes = settings.mode_filter.enabled ? modes.rebuild_modes : 0;
    images.residual.resize(static_cast<size_t>(samples) * images.residual_modes);
    images.output.resize(static_cast<size_t>(samples) * images.output_modes);
    images.noise_variance.resize(static_cast<size_t>(samples));
    images.gains.resize(static_cast<size_t>(pixels) * images.gain_modes);
    stream.count_pass();
    context.progress.begin(
        fmt::format("modes of rows {}-{}: reading {} frames", row_begin, row_end - 1, shape.frames),
        row_end - row_begin);
    Band band;
    for (int row = row_begin; row < row_end; row += plan.bands.halo_band_rows) {
        const int end = std::min(row_end, row + plan.bands.halo_band_rows);
        stream.record_patches(row, end, row_begin, &images.patches);
        stream.read_task_band(band, row, end);
        stream.record_patches(0, 0, 0, nullptr);
        // The band's own rows go into the task's images, mode by mode.
        const std::int64_t valid = (end - row) * row_samples, first = (row - row_begin) * row_samples;
        const std::int64_t offset = (row - band.row_begin) * row_samples;
        const lowrank::MutableBandView residual{images.residual.data() + first, valid, images.residual_modes,
                                                samples};
        // Each frame's windowed residual mean goes over the band's own input
        // rows (a task band is read afresh, nothing reads them again): the
        // rows' bias priors need every frame's.
        float* means = band.data + offset;
        rebuilder.prepare(band, row, end, &residual, nullptr, means, band.stride);
        const auto [residual_begin, residual_end] = rebuilder.sigma_rows(band, row, end);
        const lowrank::ImageBandShape residual_shape{shape.width, residual_end - residual_begin,
                                                     shape.channels};
        const std::vector<lowrank::BiasPosterior> posteriors = lowrank::row_bias_posteriors(
            residual_shape, row - residual_begin, end - residual_begin, rebuilder.confidence(),
            rebuilder.noise_variance().data(), modes.leverages, means, band.stride, modes.frame_scales);
        images.bias.insert(images.bias.end(), posteriors.begin(), posteriors.end());
        for (int j = 0; j < images.output_modes; ++j)
            std::copy_n(rebuilder.coefficients().begin() + j * band.rows + offset, valid,
                        images.output.begin() + j * samples + first);
        std::copy_n(rebuilder.noise_variance().begin(), valid, images.noise_variance.begin() + first);
        const std::int64_t valid_pixels = valid / shape.channels, first_pixel = first / shape.channels;
        for (int j = 0; j < images.gain_modes; ++j)
            std::copy_n(rebuilder.gains().begin() + j * valid_pixels, valid_pixels,
                        images.gains.begin() + j * pixels + first_pixel);
        context.progress.advance(end - row);
    }
    context.progress.end();
    report.passes = stream.passes();
    report.seconds_rebuild = seconds_since(start);
    return result;
}

// The outputs are rebuilt with the arithmetic of a whole run's pass 2, so the bits agree.
Report write_task(const PassContext& context, const SolvedSums& solved, const SurveyRows& survey,
                  const std::vector<ModeImages>& bands)
{
    Report report;
    RunPlan plan = plan_task(context, Stage::Write, report);
    plan.repeating = report.repeating_noise = solved.repeating;
    const ShotShape& shape = report.shape;
    const Solved modes_of = solved_from(context, plan, solved, survey, report);
    const Settings& settings = context.settings;
    const RebuildBasis& modes = modes_of.modes;
    const auto start = Clock::now();
    BandRebuilder rebuilder(settings, shape, modes, plan.filter, modes_of.survey.plan, modes_of.survey.modes,
                            nullptr);
    const ShotModes shot = join_modes_bands(bands, shape, modes.kept_modes, modes.output_modes,
                                            settings.mode_filter.enabled ? modes.rebuild_modes : 0);
    std::vector<int> written;
    for (int t = 0; t < shape.frames; ++t)
        if (context.sink.writes_frame(t))
            written.push_back(t);
    const std::int64_t samples = static_cast<std::int64_t>(shape.width) * shape.height * shape.channels;
    const lowrank::ImageBandShape image{shape.width, shape.height, shape.channels};
    const Eigen::MatrixXd output_temporal = modes.temporal.leftCols(std::max(shot.output_modes, 1));
    report.passes = 1;
    context.sink.begin({modes.kept_modes, report.rank_decision.rule, report.solver, {}});
    context.progress.begin(fmt::format("writing {} of {} frames", written.size(), shape.frames),
                           static_cast<std::int64_t>(written.size()));
    struct Buffers {
        std::vector<float> unfiltered, kept_noise, kept_gain, sigma, output, chosen, chosen_sigma;
        std::vector<std::uint8_t> chosen_estimators; // per pixel
        std::vector<float> spread, spread_terms, judged; // the per-pixel test's
        std::vector<float> misfit;                       // the residual's statistics in time
    };
    // A frame as read: cleaned by its patches, and for a written frame also as
    // read with only NaN/Inf cleaned (the choice judges that) and its other channels.
    struct ReadFrame {
        std::vector<float> cleaned, raw;
        // With the input among the estimators, the output before the choice (the
        // misfit test reads it around a written frame, and a written frame's own
        // is its output) and what making it non-negative counted.
        std::vector<float> rebuilt;
        NonNegativeCounts rebuilt_counts;
        PassThroughRows pass_through;
    };
    // The first mode's filter bias, from the coefficients the modes tasks kept
    // (as a whole run's pass 2 makes it: band_rebuild.h).
    std::vector<float> first_mode_bias;
    if (shot.gain_modes > 0 && shot.output_modes > 0 && shot.residual_modes > 0) {
        first_mode_bias.resize(static_cast<size_t>(samples));
        first_mode_filter_bias(shot.output.data(), shot.residual.data(), shot.noise_variance.data(),
                               shot.gains.data(), samples, shape.width, shape.channels,
                               first_mode_bias.data());
    }
    const EstimatorOptions& estimators = settings.estimators;
    std::vector<float> noise_scale; // the same for every frame: made once
    if (estimators.enabled()) {
        report.estimator_choice.assign(static_cast<size_t>(shape.frames), {});
        report.frame_noise_factors = solved.frame_noise_factors;
        noise_scale.resize(static_cast<size_t>(samples / shape.channels));
        noise_scale_rows(shot.noise_variance.data(), samples / shape.channels, shape.channels,
                         noise_scale.data());
    }
    // Frame t's rebuild before the choice, in two steps (sigma reads the first
    // before the second makes it non-negative where the output is unfiltered):
    // the unfiltered rebuild, then the output (filtered where the filter is on,
    // else the unfiltered rebuild) made non-negative.
    auto unfiltered_of = [&](int t, std::vector<float>& unfiltered) {
        unfiltered.resize(static_cast<size_t>(samples));
        lowrank::rebuild_from_coefficients({shot.residual.data(), samples, shot.residual_modes, samples},
                                           modes.temporal_rank.row(t),
                                           {unfiltered.data(), samples, 1, samples});
    };
    auto output_of = [&](int t, std::vector<float>& unfiltered, std::vector<float>& output,
                         NonNegativeCounts& counts) -> std::vector<float>& {
        std::vector<float>& result = shot.output_modes > 0 ? output : unfiltered;
        if (shot.output_modes > 0) {
            output.resize(static_cast<size_t>(samples));
            lowrank::rebuild_from_coefficients({shot.output.data(), samples, shot.output_modes, samples},
                                               output_temporal.row(t), {output.data(), samples, 1, samples});
        }
        counts = make_non_negative({result.data(), samples, 1, samples}, settings.non_negative,
                                   settings.non_negative_floor);
        return result;
    };
    const int reach = estimator_frame_reach(estimators);
    auto read_frame = [&](int t, ReadFrame& frame) {
        const bool own = context.sink.writes_frame(t);
        frame.cleaned.resize(static_cast<size_t>(samples));
        context.source.read_rows(t, 0, shape.height, frame.cleaned.data(),
                                 own ? &frame.pass_through : nullptr);
        if (own && estimators.enabled())
            frame.raw = frame.cleaned;
        for (const ModeImages::Patch& patch : shot.patches[static_cast<size_t>(t)]) {
            frame.cleaned[static_cast<size_t>(patch.sample)] = patch.value;
            if (own && estimators.enabled() && !std::isfinite(frame.raw[static_cast<size_t>(patch.sample)]))
                frame.raw[static_cast<size_t>(patch.sample)] = patch.value;
        }
        if (reach > 0) {
            std::vector<float> unfiltered;
            if (shot.output_modes == 0) // else the output is made from the filtered modes alone
                unfiltered_of(t, unfiltered);
            std::vector<float>& rebuilt = output_of(t, unfiltered, frame.rebuilt, frame.rebuilt_counts);
            if (&rebuilt != &frame.rebuilt)
                frame.rebuilt.swap(rebuilt);
        }
    };
    // The written frames a chunk at a time, with the frames around them that
    // the choice's spread reads: each frame is read once when the frames
    // written are a range, and the frames held are the chunk's and its reach.
    const size_t chunk = static_cast<size_t>(std::max(1, tbb::this_task_arena::max_concurrency()));
    std::map<int, ReadFrame> held; // its nodes stay put as others come and go
    tbb::enumerable_thread_specific<Buffers> thread_buffers;
    std::mutex counts_mutex;
    // One written frame: its rebuild, sigma and choice, written to the sink.
    auto write_frame = [&](int k) {
        throw_if_cancelled();
        const int t = written[static_cast<size_t>(k)];
        Buffers& buffers = thread_buffers.local();
        ReadFrame& own = held.at(t);
        for (std::vector<float>* buffer : {&buffers.kept_noise, &buffers.sigma})
            buffer->resize(static_cast<size_t>(samples));
        unfiltered_of(t, buffers.unfiltered);
        if (shot.gain_modes > 0)
            rebuilder.kept_noise_of_frame(modes.temporal, t, shot.gain_modes, shot.gains.data(), samples,
                                          buffers.kept_noise.data(), KeptNoise::Noise);
        if (shot.gain_modes > 0 && estimators.enabled()) { // the choice's: the gains alone
            buffers.kept_gain.resize(static_cast<size_t>(samples));
            rebuilder.kept_noise_of_frame(modes.temporal, t, shot.gain_modes, shot.gains.data(), samples,
                                          buffers.kept_gain.data(), KeptNoise::Gain);
        }
        lowrank::frame_sigma(own.cleaned.data(), buffers.unfiltered.data(), image, 0, shape.height,
                             rebuilder.confidence(), shot.noise_variance.data(), modes.leverages(t),
                             shot.gain_modes > 0 ? buffers.kept_noise.data() : nullptr, shot.bias.data(),
                             buffers.sigma.data(), first_mode_term(modes.temporal, t, first_mode_bias),
                             lowrank::frame_noise_variance(modes.frame_scales, t));
        // The output: made when the frame was read where the choice reads the
        // frames around (sigma above still needed the unfiltered rebuild as it is).
        NonNegativeCounts counts = own.rebuilt_counts;
        const std::vector<float>& output =
            reach > 0 ? own.rebuilt : output_of(t, buffers.unfiltered, buffers.output, counts);
        {
            std::lock_guard<std::mutex> lock(counts_mutex);
            report.non_negative += counts;
        }
        if (estimators.enabled()) { // the whole frame at once: every row the choice reads is here
            ChoiceFrame frame;
            frame.image = image;
            frame.input = own.raw.data(), frame.input_begin = 0, frame.input_end = shape.height;
            frame.rebuilt = output.data(), frame.sigma = buffers.sigma.data();
            frame.kept_noise = shot.gain_modes > 0 ? buffers.kept_gain.data() : nullptr;
            frame.noise_scale = noise_scale.data();
            frame.noise_factor = frame_noise_factor(modes, solved.frame_noise_factors, t);
            frame.count_repeating(plan.repeating);
            if (reach > 0) { // the per-pixel test's spread, as a whole run makes it
                SpreadWindow window;
                window.image = image, window.rows_begin = 0;
                for (int j = 0; j < static_cast<int>(window.frames.size()); ++j) {
                    const int g = t + j - kSpreadFrames;
                    if (g >= 0 && g < shape.frames && j != kSpreadFrames)
                        window.frames[static_cast<size_t>(j)] = held.at(g).cleaned.data();
                }
                buffers.judged.resize(static_cast<size_t>(samples));
                judged_samples(own.raw.data(), own.cleaned.data(), samples, buffers.judged.data());
                window.frames[kSpreadFrames] = buffers.judged.data();
                const size_t pixels = static_cast<size_t>(image.width) * image.height;
                buffers.spread.resize(pixels * kSpreadEstimates),
                    buffers.spread_terms.resize(pixels * kSpreadEstimates);
                spread_rows(window, 0, shape.height, buffers.spread.data(), buffers.spread_terms.data());
                frame.spread = buffers.spread.data(), frame.spread_terms = buffers.spread_terms.data();
                frame.spread_begin = 0;
                // The residual's statistics in time, from the held frames' rebuilds.
                MisfitWindow misfit_window;
                misfit_window.image = image, misfit_window.rows_begin = 0;
                for (int j = 0; j < static_cast<int>(misfit_window.input.size()); ++j) {
                    const int g = t + j - kMisfitFrames;
                    if (g < 0 || g >= shape.frames)
                        continue;
                    const ReadFrame& around = held.at(g);
                    misfit_window.input[static_cast<size_t>(j)] =
                        j == kMisfitFrames ? own.raw.data() : around.cleaned.data();
                    misfit_window.rebuilt[static_cast<size_t>(j)] =
                        j == kMisfitFrames ? output.data() : around.rebuilt.data();
                }
                buffers.misfit.resize(pixels * kMisfitValues);
                misfit_rows(misfit_window, 0, shape.height, buffers.misfit.data());
                frame.misfit = buffers.misfit.data(), frame.misfit_begin = 0;
            }
            frame.leverage = modes.leverages(t);
            frame.rebuilt_begin = 0, frame.rebuilt_end = shape.height;
            buffers.chosen.resize(static_cast<size_t>(samples)),
                buffers.chosen_sigma.resize(static_cast<size_t>(samples));
            buffers.chosen_estimators.resize(static_cast<size_t>(image.width) * image.height);
            report.estimator_choice[static_cast<size_t>(t)] =
                choose_frame_rows(settings, frame, 0, shape.height, buffers.chosen.data(),
                                  buffers.chosen_sigma.data(), buffers.chosen_estimators.data());
            context.sink.write_rows(t, 0, shape.height, buffers.chosen.data(), buffers.chosen_sigma.data(),
                                    &own.pass_through);
            context.sink.write_choice_rows(t, 0, shape.height, buffers.chosen_estimators.data());
        } else {
            context.sink.write_rows(t, 0, shape.height, output.data(), buffers.sigma.data(),
                                    &own.pass_through);
        }
        context.progress.advance(1);
    };
    for (size_t from = 0; from < written.size(); from += chunk) {
        const size_t to = std::min(written.size(), from + chunk);
        std::set<int> needed;
        for (size_t k = from; k < to; ++k)
            for (int g = std::max(0, written[k] - reach); g <= std::min(shape.frames - 1, written[k] + reach);
                 ++g)
                needed.insert(g);
        for (auto it = held.begin(); it != held.end();)
            it = needed.count(it->first) ? std::next(it) : held.erase(it);
        std::vector<int> missing;
        for (int g : needed)
            if (!held.count(g)) {
                missing.push_back(g);
                held[g]; // made here, filled below in parallel
            }
        tbb::parallel_for(0, static_cast<int>(missing.size()), [&](int i) {
            throw_if_cancelled();
            read_frame(missing[static_cast<size_t>(i)], held.at(missing[static_cast<size_t>(i)]));
        });
        // Isolated: the rebuilds below run parallel loops of their own, and a
        // worker waiting on one must not take another frame of this loop, whose
        // thread_buffers.local() would be the very buffers the waiting frame holds.
        tbb::parallel_for(static_cast<int>(from), static_cast<int>(to),
                          [&](int k) { tbb::this_task_arena::isolate([&] { write_frame(k); }); });
    }
    context.progress.end();
    report.seconds_rebuild = seconds_since(start);
    return report;
}

} // namespace modestack::denoise
