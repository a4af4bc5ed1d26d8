// The mode filter's survey (passes.h): the SURE sums of every candidate filter
// of each surveyed mode, image row by image row, and the choice of a filter per
// mode and of N that follows from all rows' sums.
#include "core/denoise/passes.h"

#include "core/lowrank/projection.h"

#include <fmt/format.h>

#include <algorithm>

namespace modestack::denoise {

int survey_modes(const Settings& settings, const ShotShape& shape, const lowrank::Basis& basis)
{
    int modes = std::min({settings.mode_filter.max_modes, shape.frames - 2, basis.modes()});
    if (settings.rank_rule.rule == lowrank::RankRule::Fixed)
        modes = std::max(modes, settings.rank_rule.fixed_modes);
    return std::max(1, modes);
}

std::vector<std::vector<double>> survey_rows(const PassContext& context, ShotStream& stream,
                                             const RunPlan& plan, const Solution& solution, int row_begin,
                                             int row_end, bool task)
{
    const ShotShape& shape = stream.shape();
    const int modes = survey_modes(context.settings, shape, solution.basis);
    const Eigen::MatrixXd temporal = solution.basis.temporal.leftCols(modes);
    SureSurvey survey(plan.filter, shape.width, shape.height, shape.channels, modes);
    if (!task)
        stream.ensure_whole_shot();
    if (task || !plan.bands.in_memory)
        stream.count_pass();
    context.progress.begin("mode filter: choosing widths", row_end - row_begin);
    Band band;
    std::vector<float> coefficients, noise_variance, features;
    for (int row = row_begin; row < row_end; row += plan.bands.band_rows) {
        const int end = std::min(row_end, row + plan.bands.band_rows);
        Band& data =
            task ? stream.read_task_band(band, row, end) : stream.band_with_halo(band, row, end, false);
        lowrank::BandView noisy = data.view(shape.frames).view();
        coefficients.resize(static_cast<size_t>(data.rows) * modes);
        lowrank::MutableBandView coefficient_view{coefficients.data(), data.rows, modes, data.rows};
        lowrank::project_coefficients(noisy, temporal, coefficient_view);
        lowrank::ImageBandShape band_shape{shape.width, data.row_end - data.row_begin, shape.channels};
        coefficient_noise_variance(noisy, coefficient_view.view(), band_shape,
                                   context.settings.mode_filter.noise_radius, noise_variance);
        survey.add_band(
            coefficient_view.view(), noise_variance, band_shape, data.row_begin, row - data.row_begin,
            end - data.row_begin,
            band_features(plan.filter, plan.features ? &*plan.features : nullptr, data, features));
        context.progress.advance(end - row);
    }
    context.progress.end();
    return survey.row_sums(row_begin, row_end);
}

Survey finish_survey(const Settings& settings, const ShotShape& shape, const RunPlan& plan,
                     const Solution& solution, std::vector<std::vector<double>> rows)
{
    Survey result;
    result.modes = survey_modes(settings, shape, solution.basis);
    SureSurvey survey(plan.filter, shape.width, shape.height, shape.channels, result.modes);
    survey.restore_row_sums(0, std::move(rows));
    const bool fixed = settings.rank_rule.rule == lowrank::RankRule::Fixed;
    result.plan = survey.finish(fixed ? settings.rank_rule.fixed_modes : 0);
    result.rank_decision = solution.rank_decision;
    if (!fixed) {
        result.rank_decision.kept_modes = result.plan.kept_modes;
        result.rank_decision.rule = "sure";
        result.rank_decision.reasoning = result.plan.reasoning;
    }
    return result;
}

Survey unfiltered_survey(const Solution& solution)
{
    Survey result;
    result.rank_decision = solution.rank_decision;
    return result;
}

} // namespace modestack::denoise
