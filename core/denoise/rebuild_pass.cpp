// Pass 2 of a whole run (passes.h, rebuild_shot): band by band, every frame
// rebuilt from the modes (filtered, shrunk, made non-negative as the settings
// say), its sigma, and the rows handed to the sink; the spatial modes and the
// rank map when the sink or the settings ask for them.
// chosen_modes, which every rebuild starts from (a farm's modes and write
// tasks too), and choose_frame_rows, which a farm's write task shares, live
// here beside it.
#include "core/denoise/frame_weighting.h"
#include "core/denoise/passes.h"
#include "core/denoise/temporal_misfit.h"
#include "core/denoise/temporal_spread.h"

#include "core/lowrank/projection.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

namespace modestack::denoise {
namespace {

// Spatial modes ps(x, y, j) = coefficient_j / σ_j of rows [row, end), for inspection ([0048]).
void write_spatial_modes(FrameSink& sink, const ShotShape& shape, const ScratchBuffer<float>& coefficients,
                         const Band& data, const Solution& solution, int kept_modes, int row, int end,
                         std::int64_t offset)
{
    const std::int64_t samples = static_cast<std::int64_t>(shape.width) * (end - row) * shape.channels;
    std::vector<float> modes(static_cast<size_t>(samples) * kept_modes);
    for (int j = 0; j < kept_modes; ++j) {
        const double singular = solution.basis.singular_values[j];
        const double scale = solution.training ? 1.0 : singular > 0 ? 1.0 / singular : 0.0;
        for (std::int64_t i = 0; i < samples; ++i)
            modes[j * samples + i] = static_cast<float>(coefficients[j * data.rows + offset + i] * scale);
    }
    sink.write_mode_rows(row, end, kept_modes, modes.data());
}

} // namespace

RebuildBasis chosen_modes(const Settings& settings, const ShotShape& shape, const Solution& solution,
                          const Survey& survey, Report& report)
{
    report.rank_decision = survey.rank_decision;
    report.mode_filter = survey.plan;
    describe_solution(settings, shape, solution, survey.rank_decision.kept_modes, report);
    RebuildBasis modes = make_rebuild_basis(settings, solution.basis, survey.rank_decision.kept_modes,
                                            survey.modes, solution.training ? &*solution.training : nullptr,
                                            survey.rank_decision.noise_sigma, solution.frame_scales);
    report.shrinkage = modes.shrinkage;
    report.rebuild_weights.assign(static_cast<size_t>(modes.temporal.cols()),
                                  std::vector<double>(static_cast<size_t>(modes.temporal.rows())));
    for (Eigen::Index j = 0; j < modes.temporal.cols(); ++j)
        for (Eigen::Index t = 0; t < modes.temporal.rows(); ++t)
            report.rebuild_weights[static_cast<size_t>(j)][static_cast<size_t>(t)] = modes.temporal(t, j);
    report.weight_smoothing = modes.weight_smoothing;
    report.frame_scales.assign(modes.frame_scales.data(),
                               modes.frame_scales.data() + modes.frame_scales.size());
    return modes;
}

ChoiceCounts choose_frame_rows(const Settings& settings, const ChoiceFrame& frame, int row, int end,
                               float* values, float* sigma, std::uint8_t* chosen)
{
    const ChoiceCounts counts =
        choose_estimators(settings.estimators, frame, row, end, values, sigma, chosen);
    const std::int64_t samples =
        static_cast<std::int64_t>(frame.image.width) * frame.image.channels * (end - row);
    clamp_chosen_values(values, samples, settings.non_negative, settings.non_negative_floor);
    return counts;
}

RebuildPass::RebuildPass(const PassContext& context, ShotStream& stream, const RunPlan& plan,
                         const Solution& solution, const Survey& survey, const RebuildBasis& modes)
    : m_context(context), m_stream(stream), m_plan(plan), m_solution(solution), m_modes(modes),
      m_rebuilder(context.settings, stream.shape(), modes, plan.filter, survey.plan, survey.modes,
                  plan.features ? &*plan.features : nullptr)
{
    const Settings& settings = context.settings;
    stream.ensure_whole_shot();
    if (!plan.bands.in_memory) // pass 2 reuses a kept shot: no second read
        stream.count_pass();
    context.sink.begin({modes.kept_modes, survey.rank_decision.rule, solver_name(plan.solver), {}});
    context.progress.begin("rebuilding frames", stream.shape().height);
    if (settings.rank_map.enabled)
        m_report.rank_map.largest_rank = modes.rebuild_modes;
    if (settings.estimators.enabled()) {
        m_report.estimator_choice.assign(static_cast<size_t>(stream.shape().frames), {});
        m_report.frame_noise_factors = stream.frame_noise_factors(); // the first pass has read every row
    }
}

void RebuildPass::add_rows(int row, int end)
{
    const Settings& settings = m_context.settings;
    FrameSink& sink = m_context.sink;
    const ShotShape& shape = m_stream.shape();
    const RebuildBasis& modes = m_modes;
    BandRebuilder& rebuilder = m_rebuilder;
    const bool kept = m_plan.bands.in_memory;
    const bool rank_map = settings.rank_map.enabled, filter = settings.mode_filter.enabled;
    const int frames = shape.frames, output = modes.output_modes, kept_modes = modes.kept_modes;
    const std::int64_t row_samples = m_stream.row_samples();
    const EstimatorOptions& estimators = settings.estimators;
    // --estimators: rows around each band are rebuilt too, for the choice's windows.
    const int reach = estimator_rebuilt_reach(estimators);
    const int input_reach = estimator_input_reach(estimators);
    Band& band = m_band;
    ScratchBuffer<float>& kept_sigma = m_kept_sigma;
    std::vector<float>& ranks = m_ranks;
    RebuildReport& report = m_report;

    // Sigma of the rebuilt rows: prepare leaves each frame's windowed residual
    // mean there (the pass that finds s²), finished frame by frame. A
    // streamed band's own input rows hold it (nothing reads them after
    // prepare); a kept shot's must stay, and so must the input the choice
    // reads, so sigma then gets its own buffer. A band whose rows stay as read
    // lends the next band the rows they share.
    const bool sigma_apart = kept || estimators.enabled();
    Band& data = m_stream.band_with_halo(band, row, end, true, sigma_apart);
    throw_if_cancelled();
    // Rows [first, last) are rebuilt, with their sigma: the band's own, and
    // the choice's reach around them.
    const int first = std::max(0, row - reach), last = std::min(shape.height, end + reach);
    const std::int64_t offset = (first - data.row_begin) * row_samples, valid = (last - first) * row_samples;
    float* sigma = nullptr;
    std::int64_t sigma_stride = valid;
    if (sigma_apart) {
        kept_sigma.resize(static_cast<size_t>(valid) * frames);
        sigma = kept_sigma.data();
    } else {
        sigma = band.storage.data() + offset;
        sigma_stride = data.stride;
    }
    rebuilder.prepare(data, first, last, nullptr, rank_map ? &ranks : nullptr, sigma, sigma_stride);
    // rebuilt() holds the unfiltered rebuild of sigma's rows; the output goes over its rebuilt ones.
    const auto [residual_begin, residual_end] = rebuilder.sigma_rows(data, first, last);
    const std::int64_t rebuilt_stride = (residual_end - residual_begin) * row_samples;
    const lowrank::ImageBandShape residual_shape{shape.width, residual_end - residual_begin, shape.channels};
    const int first_valid = first - residual_begin, last_valid = last - residual_begin;
    auto kept_noise_of = [&](int t, std::vector<float>& kept_noise, KeptNoise what) {
        kept_noise.resize(static_cast<size_t>(valid));
        rebuilder.kept_noise_of_frame(modes.temporal, t, modes.rebuild_modes, rebuilder.gains().data(), valid,
                                      kept_noise.data(), what);
    };
    // Each row's bias prior from all its frames' means, before any frame's sigma.
    const std::vector<lowrank::BiasPosterior> posteriors = lowrank::row_bias_posteriors(
        residual_shape, first_valid, last_valid, rebuilder.confidence(), rebuilder.noise_variance().data(),
        modes.leverages, sigma, sigma_stride, modes.frame_scales);
    tbb::parallel_for(0, frames, [&](int t) {
        std::vector<float>& kept_noise = m_kept_noise_of_worker.local(); // nothing below runs in parallel
        if (filter)
            kept_noise_of(t, kept_noise, KeptNoise::Noise);
        lowrank::sigma_from_mean(residual_shape, first_valid, last_valid, rebuilder.confidence(),
                                 rebuilder.noise_variance().data(), modes.leverages(t),
                                 filter ? kept_noise.data() : nullptr, posteriors.data(),
                                 sigma + t * sigma_stride,
                                 first_mode_term(modes.temporal, t, rebuilder.first_mode_bias()),
                                 lowrank::frame_noise_variance(modes.frame_scales, t));
    });
    lowrank::MutableBandView output_view{rebuilder.rebuilt().data() + (first - residual_begin) * row_samples,
                                         valid, frames, rebuilt_stride};
    if (output > 0) // the rebuilt rows from the changed coefficients
        lowrank::rebuild_from_coefficients(
            {rebuilder.coefficients().data() + offset, valid, output, data.rows},
            modes.temporal.leftCols(output), output_view);
    // Counted over the band's own rows only (the rows around it belong to other bands).
    const std::int64_t own_offset = (row - first) * row_samples, own = (end - row) * row_samples;
    auto rows_of = [&](std::int64_t from, std::int64_t count) {
        return lowrank::MutableBandView{output_view.data + from, count, frames, output_view.frame_stride};
    };
    make_non_negative(rows_of(0, own_offset), settings.non_negative, settings.non_negative_floor);
    report.non_negative +=
        make_non_negative(rows_of(own_offset, own), settings.non_negative, settings.non_negative_floor);
    make_non_negative(rows_of(own_offset + own, valid - own_offset - own), settings.non_negative,
                      settings.non_negative_floor);

    const int raw_begin = std::max(0, row - input_reach), raw_end = std::min(shape.height, end + input_reach);
    if (estimators.enabled()) {
        m_noise_scale.resize(static_cast<size_t>(valid / shape.channels));
        noise_scale_rows(rebuilder.noise_variance().data(), valid / shape.channels, shape.channels,
                         m_noise_scale.data());
    }
    // The spread's differences between the band's cleaned frames, made once
    // for every frame whose window holds them (pair t: frames t and t + 1).
    const bool spread = estimator_frame_reach(estimators) > 0;
    const std::int64_t own_pixels = static_cast<std::int64_t>(shape.width) * (end - row);
    const std::int64_t own_first = (row - data.row_begin) * row_samples;
    if (spread) {
        m_pair_terms.resize(static_cast<size_t>(std::max(frames - 1, 0) * own_pixels));
        tbb::parallel_for(0, frames - 1, [&](int t) {
            spread_pair_rows({shape.width, shape.height, shape.channels}, row,
                             data.data + t * data.stride + own_first,
                             data.data + (t + 1) * data.stride + own_first, row, end,
                             m_pair_terms.data() + t * own_pixels);
        });
    }
    tbb::parallel_for(0, frames, [&](int frame) { // a window of the kept shot has no pass-through rows
        const PassThroughRows* pass_through =
            data.pass_through.empty() ? nullptr : &data.pass_through[static_cast<size_t>(frame)];
        const float* frame_sigma = sigma + frame * sigma_stride;
        const float* frame_output = output_view.data + frame * output_view.frame_stride;
        if (!estimators.enabled()) {
            sink.write_rows(frame, row, end, frame_output + own_offset, frame_sigma + own_offset,
                            pass_through);
            return;
        }
        // Made again rather than kept from sigma's loop, and the input read
        // here: one frame per worker, not every frame's.
        std::vector<float>& kept_noise = m_kept_noise_of_worker.local();
        if (filter)
            kept_noise_of(frame, kept_noise, KeptNoise::Gain);
        ScratchBuffer<float>& raw = m_raw_of_worker.local();
        m_stream.read_raw_frame_rows(frame, raw_begin, raw_end, data, raw);
        ChoiceFrame choice_frame;
        choice_frame.image = {shape.width, shape.height, shape.channels};
        choice_frame.input = raw.data();
        choice_frame.input_begin = raw_begin, choice_frame.input_end = raw_end;
        choice_frame.rebuilt = frame_output, choice_frame.sigma = frame_sigma;
        choice_frame.kept_noise = filter ? kept_noise.data() : nullptr;
        choice_frame.noise_scale = m_noise_scale.data();
        choice_frame.noise_factor = frame_noise_factor(modes, report.frame_noise_factors, frame);
        choice_frame.count_repeating(m_plan.repeating);
        Chosen& chosen = m_chosen_of_worker.local();
        if (spread) { // the per-pixel test's spread and the misfit's statistics, from the band's rows
            SpreadWindow window;
            window.image = choice_frame.image, window.rows_begin = row;
            for (int k = 0; k < static_cast<int>(window.frames.size()); ++k) {
                const int t = frame + k - kSpreadFrames;
                if (t >= 0 && t < frames && k != kSpreadFrames)
                    window.frames[static_cast<size_t>(k)] = data.data + t * data.stride + own_first;
                if (t >= 0 && t + 1 < frames && k < static_cast<int>(window.pair_terms.size()))
                    window.pair_terms[static_cast<size_t>(k)] = m_pair_terms.data() + t * own_pixels;
            }
            chosen.judged.resize(static_cast<size_t>(own));
            judged_samples(raw.data() + (row - raw_begin) * row_samples,
                           data.data + frame * data.stride + own_first, own, chosen.judged.data());
            window.frames[kSpreadFrames] = chosen.judged.data();
            chosen.spread.resize(static_cast<size_t>(own_pixels) * kSpreadEstimates);
            chosen.spread_terms.resize(chosen.spread.size());
            spread_rows(window, row, end, chosen.spread.data(), chosen.spread_terms.data());
            choice_frame.spread = chosen.spread.data();
            choice_frame.spread_terms = chosen.spread_terms.data();
            choice_frame.spread_begin = row;
            // The residual's statistics in time, from the same rows and their rebuilds.
            MisfitWindow misfit_window;
            misfit_window.image = choice_frame.image, misfit_window.rows_begin = row;
            for (int k = 0; k < static_cast<int>(misfit_window.input.size()); ++k) {
                const int t = frame + k - kMisfitFrames;
                if (t < 0 || t >= frames)
                    continue;
                misfit_window.input[static_cast<size_t>(k)] =
                    k == kMisfitFrames ? raw.data() + (row - raw_begin) * row_samples
                                       : data.data + t * data.stride + own_first;
                misfit_window.rebuilt[static_cast<size_t>(k)] =
                    output_view.data + t * output_view.frame_stride + own_offset;
            }
            chosen.misfit.resize(static_cast<size_t>(own_pixels) * kMisfitValues);
            misfit_rows(misfit_window, row, end, chosen.misfit.data());
            choice_frame.misfit = chosen.misfit.data(), choice_frame.misfit_begin = row;
        }
        choice_frame.leverage = modes.leverages(frame);
        choice_frame.rebuilt_begin = first, choice_frame.rebuilt_end = last;
        chosen.values.resize(static_cast<size_t>(own)), chosen.sigma.resize(static_cast<size_t>(own));
        chosen.estimators.resize(static_cast<size_t>(shape.width) * (end - row));
        report.estimator_choice[static_cast<size_t>(frame)].add(
            choose_frame_rows(settings, choice_frame, row, end, chosen.values.data(), chosen.sigma.data(),
                              chosen.estimators.data()));
        sink.write_rows(frame, row, end, chosen.values.data(), chosen.sigma.data(), pass_through);
        sink.write_choice_rows(frame, row, end, chosen.estimators.data());
    });
    if (sink.wants_modes())
        write_spatial_modes(sink, shape, rebuilder.coefficients(), data, m_solution, kept_modes, row, end,
                            (row - data.row_begin) * row_samples);
    if (rank_map) {
        sink.write_rank_rows(row, end, ranks.data());
        report.rank_map.add(ranks);
    }
    m_context.progress.advance(end - row);
}

RebuildReport RebuildPass::finish()
{
    if (m_context.settings.rank_map.enabled)
        m_report.rank_map.finish();
    m_context.progress.end();
    return std::move(m_report);
}

RebuildReport rebuild_shot(const PassContext& context, ShotStream& stream, const RunPlan& plan,
                           const Solution& solution, const Survey& survey, const RebuildBasis& modes)
{
    RebuildPass pass(context, stream, plan, solution, survey, modes);
    const int height = stream.shape().height;
    for (int row = 0; row < height; row += plan.bands.halo_band_rows)
        pass.add_rows(row, std::min(height, row + plan.bands.halo_band_rows));
    return pass.finish();
}

} // namespace modestack::denoise
