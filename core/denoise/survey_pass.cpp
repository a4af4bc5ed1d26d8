// The mode filter's survey (passes.h): the SURE sums of every candidate filter
// of each surveyed mode, image row by image row, and the choice of a filter per
// mode and of N that follows from all rows' sums.
#include "core/denoise/passes.h"

#include "core/denoise/frame_weighting.h"
#include "core/lowrank/projection.h"

#include <fmt/format.h>

#include <algorithm>
#include <limits>

namespace modestack::denoise {

int survey_modes(const Settings& settings, const ShotShape& shape, const lowrank::Basis& basis)
{
    int modes = std::min({settings.mode_filter.max_modes, shape.frames - 2, basis.modes()});
    if (settings.rank_rule.rule == lowrank::RankRule::Fixed)
        modes = std::max(modes, settings.rank_rule.fixed_modes);
    return std::max(1, modes);
}

SurveyPass::SurveyPass(const PassContext& context, ShotStream& stream, const RunPlan& plan,
                       const Solution& solution, int row_begin, int row_end, bool task)
    : m_context(context), m_stream(stream), m_plan(plan), m_task(task), m_row_begin(row_begin),
      m_row_end(row_end), m_modes(survey_modes(context.settings, stream.shape(), solution.basis)),
      m_temporal(projection_weights(solution.basis.temporal.leftCols(m_modes), solution.frame_scales)),
      m_frame_scales(solution.frame_scales),
      m_survey(plan.filter, stream.shape().width, stream.shape().height, stream.shape().channels, m_modes)
{
    if (!task)
        stream.ensure_whole_shot();
    if (task || !plan.bands.in_memory)
        stream.count_pass();
    context.progress.begin("mode filter: choosing widths", row_end - row_begin);
}

void SurveyPass::add_rows(int row, int end)
{
    const ShotShape& shape = m_stream.shape();
    Band& data = m_task ? m_stream.read_task_band(m_band, row, end)
                        : m_stream.band_with_halo(m_band, row, end, false, true);
    lowrank::BandView noisy = data.view(shape.frames).view();
    m_coefficients.resize(static_cast<size_t>(data.rows) * m_modes);
    lowrank::MutableBandView coefficient_view{m_coefficients.data(), data.rows, m_modes, data.rows};
    lowrank::project_coefficients(noisy, m_temporal, coefficient_view);
    lowrank::ImageBandShape band_shape{shape.width, data.row_end - data.row_begin, shape.channels};
    coefficient_noise_variance(noisy, coefficient_view.view(), band_shape,
                               m_context.settings.mode_filter.noise_radius, m_noise_variance, m_frame_scales);
    m_survey.add_band(
        coefficient_view.view(), m_noise_variance, band_shape, data.row_begin, row - data.row_begin,
        end - data.row_begin,
        band_features(m_plan.filter, m_plan.features ? &*m_plan.features : nullptr, data, m_features));
    m_context.progress.advance(end - row);
}

std::vector<std::vector<double>> SurveyPass::finish()
{
    m_context.progress.end();
    return m_survey.row_sums(m_row_begin, m_row_end);
}

std::vector<std::vector<double>> survey_rows(const PassContext& context, ShotStream& stream,
                                             const RunPlan& plan, const Solution& solution, int row_begin,
                                             int row_end, bool task)
{
    SurveyPass survey(context, stream, plan, solution, row_begin, row_end, task);
    for (int row = row_begin; row < row_end; row += plan.bands.halo_band_rows)
        survey.add_rows(row, std::min(row_end, row + plan.bands.halo_band_rows));
    return survey.finish();
}

namespace {

// The most noise one mode can hold, over the residual's v, where the choice
// counts noise that repeats (repeating_noise.h): share c of the per-sample noise
// repeats, r = c / (1 − c) of the part that is new in each frame (the part v
// measures), and a mode's temporal weights V_j put at most (Σ_t V_tj)² ≤ F times
// the repeating part's variance into its coefficients (Cauchy–Schwarz,
// Σ_t V_tj² = 1). Infinite where nothing is new.
double noise_scale_cap(const RepeatingNoise& repeating, int frames)
{
    const double share = repeating.counted_share();
    if (share <= 0)
        return kMaximumNoiseScale;
    if (share >= 1)
        return std::numeric_limits<double>::infinity();
    return kMaximumNoiseScale + frames * share / (1 - share);
}

} // namespace

Survey finish_survey(const Settings& settings, const ShotShape& shape, const RunPlan& plan,
                     const Solution& solution, std::vector<std::vector<double>> rows)
{
    Survey result;
    result.modes = survey_modes(settings, shape, solution.basis);
    SureSurvey survey(plan.filter, shape.width, shape.height, shape.channels, result.modes);
    survey.restore_row_sums(0, std::move(rows));
    const bool fixed = settings.rank_rule.rule == lowrank::RankRule::Fixed;
    result.plan = survey.finish(fixed ? settings.rank_rule.fixed_modes : 0,
                                noise_scale_cap(plan.repeating, shape.frames));
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
