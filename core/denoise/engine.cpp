#include "core/denoise/engine.h"

#include "core/common/error.h"
#include "core/denoise/layer_runs.h"
#include "core/denoise/passes.h"

#include <fmt/format.h>

#include <chrono>

namespace modestack::denoise {
namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point start)
{
    return std::chrono::duration<double>(Clock::now() - start).count();
}

} // namespace

Solver parse_solver(const std::string& name)
{
    if (name == "auto")
        return Solver::Auto;
    if (name == "gram")
        return Solver::Gram;
    if (name == "rsvd")
        return Solver::RandomizedSvd;
    throw usage_error(fmt::format("--method '{}' is not one of auto, gram, rsvd", name));
}

std::string solver_name(Solver solver)
{
    switch (solver) {
    case Solver::Gram:
        return "gram";
    case Solver::RandomizedSvd:
        return "rsvd";
    default:
        return "auto";
    }
}

Report run_denoise(FrameSource& source, FrameSink& sink, const Settings& settings, Progress& progress)
{
    const ShotShape shape = source.shape();
    if (settings.layer_channels.size() > 1)
        return merge_layer_reports(run_layers(source, sink, settings, progress), shape);
    const PassContext context{source, sink, settings, progress};
    check_settings(settings, shape);
    RunPlan plan = plan_run(context, true);
    plan.repeating = measure_repeating_noise(source, progress); // a few more frames read
    Report report;
    report.repeating_noise = plan.repeating;
    report.shape = shape;
    report.plan = plan.bands;
    report.solver = solver_name(plan.solver);
    if (plan.features)
        report.feature_guide = plan.features->summary();
    ShotStream stream(source, settings.outliers, plan.bands, progress);

    // Statistics and solve (the randomized SVD's passes do both).
    auto start = Clock::now();
    const Solution solution =
        plan.solver == Solver::Gram ? gram_solution(context, stream) : randomized_solution(context, stream);
    report.seconds_statistics = seconds_since(start) - solution.seconds;
    report.outliers = stream.outliers();

    // Survey: the mode filter's choice of filters and (auto N) of N.
    start = Clock::now();
    Survey survey = unfiltered_survey(solution);
    if (settings.mode_filter.enabled) {
        const auto survey_start = Clock::now();
        survey = finish_survey(settings, shape, plan, solution,
                               survey_rows(context, stream, plan, solution, 0, shape.height, false));
        report.seconds_filter_survey = seconds_since(survey_start);
    }
    const RebuildBasis modes = chosen_modes(settings, shape, solution, survey, report);
    report.seconds_solve = seconds_since(start) - report.seconds_filter_survey + solution.seconds;

    // Modes and write: pass 2.
    start = Clock::now();
    const RebuildReport rebuilt = rebuild_shot(context, stream, plan, solution, survey, modes);
    report.non_negative = rebuilt.non_negative;
    report.rank_map = rebuilt.rank_map;
    report.estimator_choice = rebuilt.estimator_choice;
    report.frame_noise_factors = rebuilt.frame_noise_factors;
    report.passes = stream.passes();
    report.seconds_rebuild = seconds_since(start);
    return report;
}

} // namespace modestack::denoise
