// Pass 1 and the solve (passes.h): the shot fed to the Gram sums (or the
// randomized SVD) in fixed chunks of rows, so that the summation order does not
// depend on the bands, and the temporal modes and N that follow.
#include "core/denoise/passes.h"

#include "core/denoise/block_gram.h"
#include "core/denoise/frame_weighting.h"
#include "core/lowrank/gram.h"

#include <fmt/format.h>

#include <chrono>

namespace modestack::denoise {
namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point start)
{
    return std::chrono::duration<double>(Clock::now() - start).count();
}

// Feeds a band to `add(first image row, chunk)` in fixed chunks of kChunkRows
// image rows, so the summation order does not depend on the band height.
template <typename Add> void for_each_chunk(const ShotShape& shape, Band& band, Add&& add)
{
    const std::int64_t row_samples = static_cast<std::int64_t>(shape.width) * shape.channels;
    for (int row = band.row_begin; row < band.row_end; row += kChunkRows) {
        const int end = std::min(band.row_end, row + kChunkRows);
        lowrank::BandView chunk{band.data + (row - band.row_begin) * row_samples, (end - row) * row_samples,
                                shape.frames, band.stride};
        add(row, chunk);
    }
}

// --whiten (whitening.h): hands `use` the chunk's sample rows scaled by their
// weights, for the modes only, one image row at a time so that the copy stays
// 1/kChunkRows of a band; without weights the chunk itself.
template <typename Use>
void visit_whitened(const Settings& settings, const ShotShape& shape, const Band& band,
                    const lowrank::BandView& chunk, std::vector<float>& scratch, Use&& use)
{
    if (!settings.whitening) {
        use(chunk);
        return;
    }
    const std::vector<float>& weights = *settings.whitening;
    const std::int64_t row_samples = static_cast<std::int64_t>(shape.width) * shape.channels;
    const std::int64_t chunk_first =
        static_cast<std::int64_t>(band.row_begin) * row_samples + (chunk.data - band.data);
    scratch.resize(static_cast<size_t>(row_samples) * shape.frames);
    for (std::int64_t begin = 0; begin < chunk.rows; begin += row_samples) {
        for (int t = 0; t < shape.frames; ++t)
            for (std::int64_t i = 0; i < row_samples; ++i)
                scratch[static_cast<size_t>(t * row_samples + i)] =
                    chunk.data[t * chunk.frame_stride + begin + i] *
                    weights[static_cast<size_t>(chunk_first + begin + i)];
        use(lowrank::BandView{scratch.data(), row_samples, shape.frames, row_samples});
    }
}

// The basis and N of a solve, with the solve's seconds and the frame scales it used.
Solution solved(lowrank::Basis basis, const Settings& settings, std::optional<TrainingGram> training,
                double seconds, Eigen::VectorXd frame_scales = {})
{
    Solution solution{std::move(basis), {}, std::move(training), seconds, std::move(frame_scales)};
    solution.rank_decision = lowrank::choose_rank(solution.basis, settings.rank_rule);
    return solution;
}

} // namespace

GramPass::GramPass(const Settings& settings, const ShotShape& shape)
    : m_settings(settings), m_shape(shape), m_gram(settings.training_frames.empty() ? shape.frames : 1, false)
{
    if (!settings.training_frames.empty()) // --train-frames: training.h
        m_training.emplace(shape.frames, settings.training_frames);
}

void GramPass::add(Band& band)
{
    for_each_chunk(m_shape, band, [&](int row, const lowrank::BandView& chunk) {
        visit_whitened(m_settings, m_shape, band, chunk, m_scratch, [&](const lowrank::BandView& rows) {
            m_training ? m_training->add(rows) : m_gram.add(row, rows);
        });
    });
}

Solution GramPass::finish(const std::vector<double>& noise_factors)
{
    m_gram.finish();
    if (!m_training)
        return solution_from_gram(m_settings, m_gram.total(), noise_factors);
    const auto start = Clock::now();
    lowrank::Basis basis = m_training->basis();
    basis.passes = 1;
    return solved(std::move(basis), m_settings, std::move(m_training), seconds_since(start));
}

Solution gram_solution(const PassContext& context, ShotStream& stream)
{
    GramPass gram(context.settings, stream.shape());
    stream.for_each_band([&](Band& band) { gram.add(band); });
    return gram.finish(stream.frame_scale_factors());
}

Solution randomized_solution(const PassContext& context, ShotStream& stream)
{
    const Settings& settings = context.settings;
    const ShotShape& shape = stream.shape();
    lowrank::BandPass pass = [&](const std::function<void(const lowrank::BandView&)>& visit) {
        std::vector<float> scratch;
        stream.for_each_band([&](Band& band) {
            for_each_chunk(shape, band, [&](int, const lowrank::BandView& chunk) {
                visit_whitened(settings, shape, band, chunk, scratch, visit);
            });
        });
    };
    const int modes = std::min(shape.frames - 1, std::max(settings.randomized_modes,
                                                          settings.rank_rule.rule == lowrank::RankRule::Fixed
                                                              ? settings.rank_rule.fixed_modes + 2
                                                              : 0));
    lowrank::Basis basis =
        lowrank::randomized_svd(pass, shape.frames, modes, settings.randomized, Progress::silent());
    return solved(std::move(basis), settings, std::nullopt, 0);
}

// The modes of X D⁻¹ with the measured frame scales (frame_weighting.h), of X
// with --frame-noise even.
Solution solution_from_gram(const Settings& settings, const lowrank::GramAccumulator& gram,
                            const std::vector<double>& noise_factors)
{
    const auto start = Clock::now();
    Eigen::VectorXd scales = settings.measured_frame_noise ? frame_scales(noise_factors) : Eigen::VectorXd();
    lowrank::Basis basis = lowrank::basis_from_gram(scaled_gram(gram, scales));
    basis.passes = 1;
    return solved(std::move(basis), settings, std::nullopt, seconds_since(start), std::move(scales));
}

Statistics block_statistics(const PassContext& context, ShotStream& stream, int row_begin, int row_end)
{
    const ShotShape& shape = stream.shape();
    BlockGram gram(shape.frames, true);
    context.progress.begin(
        fmt::format("statistics of rows {}-{}: reading {} frames", row_begin, row_end - 1, shape.frames),
        row_end - row_begin);
    Band band;
    std::vector<float> scratch;
    stream.count_pass();
    for (int row = row_begin; row < row_end; row += stream.plan().band_rows) {
        const int end = std::min(row_end, row + stream.plan().band_rows);
        stream.read_band(band, row, end, ShotStream::Cleaning::Count);
        for_each_chunk(shape, band, [&](int chunk_row, const lowrank::BandView& chunk) {
            visit_whitened(context.settings, shape, band, chunk, scratch,
                           [&](const lowrank::BandView& rows) { gram.add(chunk_row, rows); });
        });
        context.progress.advance(end - row);
    }
    context.progress.end();
    gram.finish();
    return {row_begin,
            row_end,
            std::move(gram.blocks()),
            stream.outliers(),
            stream.roughness_blocks(row_begin, row_end),
            stream.roughness_blocks(row_begin, row_end, ShotStream::Roughness::Cleaned)};
}

void describe_solution(const Settings& settings, const ShotShape& shape, const Solution& solution,
                       int kept_modes, Report& report)
{
    const lowrank::Basis& basis = solution.basis;
    const double total = basis.frame_energy.sum();
    for (int j = 0; j < basis.modes(); ++j) {
        report.singular_values.push_back(basis.singular_values[j]);
        const double energy = basis.singular_values[j] * basis.singular_values[j];
        report.explained.push_back(total > 0 ? energy / total : 0.0);
    }
    const auto temporal_modes = [&](int modes) {
        const Eigen::MatrixXd temporal = solution.training ? solution.training->temporal_modes(basis, modes)
                                                           : Eigen::MatrixXd(basis.temporal.leftCols(modes));
        std::vector<std::vector<double>> weights(static_cast<size_t>(modes),
                                                 std::vector<double>(shape.frames));
        for (int j = 0; j < modes; ++j)
            for (int t = 0; t < shape.frames; ++t)
                weights[static_cast<size_t>(j)][static_cast<size_t>(t)] = temporal(t, j);
        return weights;
    };
    report.temporal_modes = temporal_modes(kept_modes);
    if (settings.report_modes <= 0)
        return;
    const int preview =
        std::min({std::max(2 * kept_modes, settings.report_modes), shape.frames - 1, basis.modes()});
    report.preview_temporal_modes = temporal_modes(preview);
}

} // namespace modestack::denoise
