#include "core/denoise/engine.h"
#include "core/denoise/block_gram.h"
#include "core/denoise/stage_modes.h"
#include "core/denoise/training.h"

#include "core/common/error.h"
#include "core/common/scratch_buffer.h"
#include "core/lowrank/basis.h"
#include "core/lowrank/confidence.h"
#include "core/lowrank/gram.h"
#include "core/lowrank/projection.h"
#include "core/lowrank/shrinkage.h"

#include <fmt/format.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <mutex>
#include <optional>
#include <utility>

namespace modestack::denoise {
namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

// Per-sample images the mode filter's guide holds over a band with its halo: the
// guide and its noise (float) and the smoothing's horizontal pass (double), see
// filter_weights.cpp.
constexpr int kGuideImages = 4;

// Rows [row_begin, row_end) of every frame: sample i of frame t is data[t * stride + i].
// Either read from the source into `storage`, or a window into the kept shot.
struct Band {
    int row_begin = 0;
    int row_end = 0;
    std::int64_t rows = 0;    // samples per frame: width * (row_end - row_begin) * channels
    std::int64_t stride = 0;  // samples from one frame to the next
    float* data = nullptr;
    ScratchBuffer<float> storage;  // read_band writes every sample

    lowrank::MutableBandView view(int frames) const { return {data, rows, frames, stride}; }
};

class Engine {
public:
    Engine(FrameSource& source, FrameSink& sink, const Settings& settings, Progress& progress)
        : m_source(source), m_sink(sink), m_settings(settings), m_progress(progress), m_shape(source.shape())
    {
    }

    Report run()
    {
        validate();
        int largest_rank = m_settings.rank.rule == lowrank::RankRule::Fixed ? m_settings.rank.fixed_rank
                                                                            : std::min(m_shape.frames - 1, 32);
        m_report.shape = m_shape;
        // Sigma's window reads radius + 1 rows around a pixel (see confidence.h); the
        // mode filter reads its kernel and guide around a pixel.
        PassNeeds needs;
        needs.halo_rows = needs.sigma_halo_rows = sigma_halo_rows();
        needs.halo_images = largest_rank;  // the projected coefficients
        needs.source_row_bytes = m_source.band_bytes_per_row();
        m_filter_options = m_settings.mode_filter;
        if (m_settings.mode_filter.enabled) {
            if (!m_settings.feature_guide.kinds.empty() && !in_stage(Stage::Statistics) && !in_stage(Stage::Solve)) {
                m_features.emplace(m_source, m_settings.feature_guide, m_progress);
                m_filter_options.feature_channels = m_features->channels();
                m_report.feature_guide = m_features->summary();
            }
            needs.halo_rows = std::max(needs.halo_rows, mode_filter_halo(m_filter_options));
            // Over the halo: the surveyed coefficients, the guide with its noise (a
            // few images) and the feature rows twice (as read and the guide's planar
            // copy); the survey alone also holds its [pixel][mode] copy. Over the
            // band: the filtered coefficients, their gains and one frame's kept
            // noise per worker.
            const int surveyed = std::max(m_settings.mode_filter.max_modes, largest_rank);
            needs.survey_images = surveyed;
            needs.halo_images = surveyed + kGuideImages +
                                2 * ((m_filter_options.feature_channels + m_shape.channels - 1) / m_shape.channels);
            needs.band_images = 2 * surveyed + tbb::this_task_arena::max_concurrency();
        }
        // Each worker's residual rows (double) of sigma's windows.
        needs.band_images += 4 * tbb::this_task_arena::max_concurrency();
        m_report.plan = plan_bands(m_shape, m_settings.max_memory_bytes, needs);
        Solver solver = m_settings.solver;
        if (solver == Solver::Auto)
            solver = m_shape.frames >= m_settings.randomized_from_frames && m_settings.training_frames.empty() &&
                             !m_settings.stage
                         ? Solver::RandomizedSvd
                         : Solver::Gram;
        m_report.solver = solver_name(solver);

        auto start = Clock::now();
        if (in_stage(Stage::Statistics)) {
            statistics_stage();
            m_report.seconds_statistics = seconds_since(start);
            return m_report;
        }
        lowrank::Basis basis = solver == Solver::Gram ? gram_basis() : randomized_basis();
        m_report.seconds_statistics = seconds_since(start);

        start = Clock::now();
        m_report.rank = lowrank::choose_rank(basis, m_settings.rank);
        double survey_seconds = 0;
        // A farm's solve task leaves the survey to the survey tasks (stage_task.h).
        if (m_settings.mode_filter.enabled && !in_stage(Stage::Solve)) {
            auto survey_start = Clock::now();
            if (in_stage(Stage::Modes) || in_stage(Stage::Write))
                restore_mode_filter_survey(basis);
            else
                survey_mode_filter(basis);
            survey_seconds = seconds_since(survey_start);
            m_report.seconds_filter_survey = survey_seconds;
            if (in_stage(Stage::Survey))
                return m_report;
        }
        int rank = m_report.rank.rank;
        describe_basis(basis, rank);
        m_report.seconds_solve = seconds_since(start) - survey_seconds + m_solve_seconds;
        m_report.seconds_statistics -= m_solve_seconds;
        if (in_stage(Stage::Solve) || in_stage(Stage::Survey))
            return m_report;

        start = Clock::now();
        rebuild(basis, rank);
        m_report.seconds_rebuild = seconds_since(start);
        return m_report;
    }

private:
    bool in_stage(Stage stage) const { return m_settings.stage && m_settings.stage->stage == stage; }

    // What a farm task cannot do (each needs the whole shot in one process) and
    // the inputs its stage needs.
    void validate_stage() const
    {
        const StageTask& task = *m_settings.stage;
        const std::string name = stage_name(task.stage);
        if (m_settings.solver == Solver::RandomizedSvd)
            throw usage_error(fmt::format("--stage {}: the farm stages use the gram solver, not --method rsvd", name));
        if (!m_settings.training_frames.empty())
            throw usage_error(fmt::format("--stage {} cannot be combined with --train-frames", name));
        if (task.stage == Stage::Statistics)
            check_statistics_rows(task.row_begin, task.row_end, m_shape.height);
        if (task.stage == Stage::Solve && static_cast<int>(task.gram_blocks.size()) != stage_blocks(m_shape.height))
            throw internal_error("the solve stage needs every block's sums");
        const bool after_solve =
            task.stage == Stage::Survey || task.stage == Stage::Modes || task.stage == Stage::Write;
        if (task.stage == Stage::Survey || task.stage == Stage::Modes)
            check_task_rows(task.row_begin, task.row_end, m_shape.height);
        if (after_solve && m_settings.non_negative == NonNegativeMode::KeepSum)
            throw usage_error(fmt::format("--stage {} cannot be combined with --non-negative-mode keep-sum: it "
                                          "needs every frame of a pixel; use clamp or run on one machine",
                                          name));
        if (after_solve && !task.gram)
            throw internal_error("the survey, modes and write stages need the merged sums");
        if (after_solve && task.stage != Stage::Survey && m_settings.mode_filter.enabled &&
            static_cast<int>(task.survey_rows.size()) != m_shape.height)
            throw internal_error("the modes and write stages need the mode filter's survey of every row");
    }

    // --stage stats: pass 1 over the task's rows, each block's sums kept apart.
    void statistics_stage()
    {
        StageTask& task = *m_settings.stage;
        BlockGram gram(m_shape.frames, true);
        m_progress.begin(fmt::format("statistics of rows {}-{}: reading {} frames", task.row_begin, task.row_end - 1,
                                     m_shape.frames),
                         task.row_end - task.row_begin);
        Band band;
        std::vector<float> scratch;
        ++m_report.passes;
        for (int row = task.row_begin; row < task.row_end; row += m_report.plan.band_rows) {
            int end = std::min(task.row_end, row + m_report.plan.band_rows);
            read_band(band, row, end, &m_report.outliers);
            for_each_chunk(band, [&](int chunk_row, const lowrank::BandView& chunk) {
                visit_whitened(band, chunk, scratch,
                               [&](const lowrank::BandView& rows) { gram.add(chunk_row, rows); });
            });
            m_progress.advance(end - row);
        }
        m_progress.end();
        gram.finish();
        task.gram_blocks = std::move(gram.blocks());
        task.outliers = m_report.outliers;
    }

    // --stage modes and write: the survey the survey tasks made, without a pass over the shot.
    void restore_mode_filter_survey(const lowrank::Basis& basis)
    {
        m_filter_modes = filter_survey_modes(basis);
        SureSurvey survey(m_filter_options, m_shape.width, m_shape.height, m_shape.channels, m_filter_modes);
        survey.restore_row_sums(0, m_settings.stage->survey_rows);
        finish_mode_filter_survey(survey);
    }

    void validate() const
    {
        if (m_shape.frames < 3)
            throw usage_error(fmt::format("denoising needs at least 3 frames, got {}", m_shape.frames));
        if (m_shape.width <= 0 || m_shape.height <= 0 || m_shape.channels <= 0)
            throw usage_error("the shot has no pixels");
        if (m_settings.rank.rule == lowrank::RankRule::Fixed &&
            (m_settings.rank.fixed_rank < 1 || m_settings.rank.fixed_rank >= m_shape.frames))
            throw usage_error(fmt::format("--rank {} is out of range: use 1 to {} for {} frames",
                                          m_settings.rank.fixed_rank, m_shape.frames - 1, m_shape.frames));
        if (m_settings.sigma_radius < 0)
            throw usage_error("--sigma-radius must be 0 or more");
        if (m_settings.rank_map.enabled && !m_settings.mode_filter.enabled)
            throw usage_error("--rank-map needs the mode filter: the local estimates use its noise and filters");
        if (m_settings.optimal_shrinkage && m_settings.mode_filter.enabled)
            throw usage_error("--shrink optimal needs --no-mode-filter: the mode filter already shrinks each mode");
        if (!m_settings.training_frames.empty())
            check_training_frames(m_settings, m_shape.frames);
        if (m_settings.stage)
            validate_stage();
        if (m_settings.whitening &&
            m_settings.whitening->size() != static_cast<size_t>(m_shape.width) * m_shape.height * m_shape.channels)
            throw internal_error("the whitening weights do not match the shot");
    }

    // Reads rows [row_begin, row_end) of every frame (frames in parallel) and cleans them.
    void read_band(Band& band, int row_begin, int row_end, lowrank::OutlierCounts* counts)
    {
        throw_if_cancelled();
        band.row_begin = row_begin;
        band.row_end = row_end;
        band.rows = static_cast<std::int64_t>(m_shape.width) * (row_end - row_begin) * m_shape.channels;
        band.stride = band.rows;
        band.storage.resize(static_cast<size_t>(band.rows) * m_shape.frames);
        band.data = band.storage.data();
        tbb::parallel_for(0, m_shape.frames, [&](int frame) {
            m_source.read_rows(frame, row_begin, row_end, band.data + frame * band.rows);
        });
        const PatchRows patch_rows = m_patches;
        std::vector<float> as_read;  // --stage modes: the patch rows as the files hold them
        const std::int64_t row_samples = static_cast<std::int64_t>(m_shape.width) * m_shape.channels;
        const std::int64_t patch_first = (patch_rows.row_begin - row_begin) * row_samples;
        const std::int64_t patch_samples = (patch_rows.row_end - patch_rows.row_begin) * row_samples;
        if (patch_rows.patches) {
            as_read.resize(static_cast<size_t>(patch_samples) * m_shape.frames);
            for (int t = 0; t < m_shape.frames; ++t)
                std::copy_n(band.data + t * band.rows + patch_first, patch_samples, as_read.begin() + t * patch_samples);
        }
        // The first read of a row finds its outliers and marks the rows it changed;
        // later reads of a streamed shot redo only the marked rows (same input,
        // same result), instead of three medians for every sample again.
        const std::int64_t first_sample = static_cast<std::int64_t>(row_begin) * m_shape.width * m_shape.channels;
        if (!counts && m_cleaned_samples.empty()) {  // no pass 1 in this process (a farm task): clean in full
            lowrank::clean_outliers(band.view(m_shape.frames), m_settings.outliers, nullptr);
        } else if (counts) {
            std::uint8_t* marks =
                m_report.plan.in_memory || m_cleaned_samples.empty() ? nullptr : m_cleaned_samples.data() + first_sample;
            lowrank::OutlierCounts found = lowrank::clean_outliers(band.view(m_shape.frames), m_settings.outliers, marks);
            counts->non_finite += found.non_finite;
            counts->fireflies += found.fireflies;
        } else {
            lowrank::clean_marked_outliers(band.view(m_shape.frames), m_settings.outliers,
                                           m_cleaned_samples.data() + first_sample);
        }
        if (patch_rows.patches) {  // bitwise, so that a replaced NaN counts too
            const std::int64_t first = (patch_rows.row_begin - patch_rows.first_row) * row_samples;
            for (int t = 0; t < m_shape.frames; ++t)
                for (std::int64_t i = 0; i < patch_samples; ++i) {
                    const float cleaned = band.data[t * band.rows + patch_first + i];
                    if (std::memcmp(&cleaned, &as_read[static_cast<size_t>(t * patch_samples + i)], sizeof cleaned))
                        patch_rows.patches->push_back({t, first + i, cleaned});
                }
        }
    }

    // The window of rows [row_begin, row_end) of the kept shot.
    Band window(int row_begin, int row_end) const
    {
        const std::int64_t row_samples = static_cast<std::int64_t>(m_shape.width) * m_shape.channels;
        Band band;
        band.row_begin = row_begin;
        band.row_end = row_end;
        band.rows = row_samples * (row_end - row_begin);
        band.stride = m_whole.stride;
        band.data = m_whole.data + row_samples * row_begin;
        return band;
    }

    // Visits the shot in bands in a fixed order: the kept shot when it is in
    // memory, otherwise a fresh read of each band. Counts outliers on the first pass.
    template <typename Visit> void for_each_band(Visit&& visit)
    {
        const BandPlan& plan = m_report.plan;
        bool first_pass = m_report.passes == 0;
        ++m_report.passes;
        if (plan.in_memory && !first_pass) {
            visit(m_whole);
            return;
        }
        m_progress.begin(fmt::format("pass {}: reading {} frames", m_report.passes, m_shape.frames), m_shape.height);
        if (plan.in_memory) {
            read_band(m_whole, 0, m_shape.height, &m_report.outliers);
            visit(m_whole);
            m_progress.advance(m_shape.height);
        } else {
            if (first_pass)
                m_cleaned_samples.assign(static_cast<size_t>(m_shape.width) * m_shape.height * m_shape.channels, 0);
            Band band;
            for (int row = 0; row < m_shape.height; row += plan.band_rows) {
                int end = std::min(m_shape.height, row + plan.band_rows);
                read_band(band, row, end, first_pass ? &m_report.outliers : nullptr);
                visit(band);
                m_progress.advance(end - row);
            }
        }
        m_progress.end();
    }

    // Feeds a band to `add(first image row, chunk)` in fixed chunks of kChunkRows
    // image rows, so the summation order does not depend on the band height.
    template <typename Add> void for_each_chunk(Band& band, Add&& add)
    {
        std::int64_t row_samples = static_cast<std::int64_t>(m_shape.width) * m_shape.channels;
        for (int row = band.row_begin; row < band.row_end; row += kChunkRows) {
            int end = std::min(band.row_end, row + kChunkRows);
            lowrank::BandView chunk{band.data + (row - band.row_begin) * row_samples, (end - row) * row_samples,
                                    m_shape.frames, band.stride};
            add(row, chunk);
        }
    }

    // --whiten (whitening.h): hands `use` the chunk's sample rows scaled by their
    // weights, for the modes only, one image row at a time so that the copy stays
    // 1/kChunkRows of a band; without weights the chunk itself.
    template <typename Use>
    void visit_whitened(const Band& band, const lowrank::BandView& chunk, std::vector<float>& scratch, Use&& use) const
    {
        if (!m_settings.whitening) {
            use(chunk);
            return;
        }
        const std::vector<float>& weights = *m_settings.whitening;
        const std::int64_t row_samples = static_cast<std::int64_t>(m_shape.width) * m_shape.channels;
        const std::int64_t chunk_first = static_cast<std::int64_t>(band.row_begin) * row_samples + (chunk.data - band.data);
        scratch.resize(static_cast<size_t>(row_samples) * m_shape.frames);
        for (std::int64_t begin = 0; begin < chunk.rows; begin += row_samples) {
            for (int t = 0; t < m_shape.frames; ++t)
                for (std::int64_t i = 0; i < row_samples; ++i)
                    scratch[static_cast<size_t>(t * row_samples + i)] =
                        chunk.data[t * chunk.frame_stride + begin + i] *
                        weights[static_cast<size_t>(chunk_first + begin + i)];
            use(lowrank::BandView{scratch.data(), row_samples, m_shape.frames, row_samples});
        }
    }

    lowrank::Basis gram_basis()
    {
        if (m_settings.stage)
            return staged_gram_basis();
        const bool training = !m_settings.training_frames.empty();  // --train-frames: training.h
        BlockGram gram(training ? 1 : m_shape.frames, false);
        if (training)
            m_training.emplace(m_shape.frames, m_settings.training_frames);
        std::vector<float> scratch;
        for_each_band([&](Band& band) {
            for_each_chunk(band, [&](int row, const lowrank::BandView& chunk) {
                visit_whitened(band, chunk, scratch, [&](const lowrank::BandView& rows) {
                    training ? m_training->add(rows) : gram.add(row, rows);
                });
            });
        });
        gram.finish();
        auto start = Clock::now();
        lowrank::Basis basis = training ? m_training->basis() : lowrank::basis_from_gram(gram.total());
        basis.passes = 1;
        m_solve_seconds = seconds_since(start);
        return basis;
    }

    // --stage solve and write: the modes from the statistics tasks' sums, merged in
    // the order gram_basis() merges its blocks.
    lowrank::Basis staged_gram_basis()
    {
        StageTask& task = *m_settings.stage;
        auto start = Clock::now();
        if (task.stage == Stage::Solve)
            task.gram = BlockGram::merge(task.gram_blocks, m_shape.frames);
        m_report.outliers = task.outliers;
        lowrank::Basis basis = lowrank::basis_from_gram(*task.gram);
        basis.passes = 1;
        m_solve_seconds = seconds_since(start);
        return basis;
    }

    // The kept shot, read and cleaned when no pass 1 read it (a farm task).
    void ensure_whole_shot()
    {
        if (!m_report.plan.in_memory || m_whole.data)
            return;
        ++m_report.passes;
        m_progress.begin(fmt::format("reading {} frames", m_shape.frames), m_shape.height);
        read_band(m_whole, 0, m_shape.height, nullptr);
        m_progress.end();
    }

    lowrank::Basis randomized_basis()
    {
        lowrank::BandPass pass = [&](const std::function<void(const lowrank::BandView&)>& visit) {
            std::vector<float> scratch;
            for_each_band([&](Band& band) {
                for_each_chunk(band, [&](int, const lowrank::BandView& chunk) {
                    visit_whitened(band, chunk, scratch, visit);
                });
            });
        };
        int modes = std::min(m_shape.frames - 1, std::max(m_settings.randomized_modes,
                                                          m_settings.rank.rule == lowrank::RankRule::Fixed
                                                              ? m_settings.rank.fixed_rank + 2
                                                              : 0));
        return lowrank::randomized_svd(pass, m_shape.frames, modes, m_settings.randomized, Progress::silent());
    }

    void describe_basis(const lowrank::Basis& basis, int rank)
    {
        double total = basis.frame_energy.sum();
        for (int j = 0; j < basis.modes(); ++j) {
            m_report.singular_values.push_back(basis.singular_values[j]);
            double energy = basis.singular_values[j] * basis.singular_values[j];
            m_report.explained.push_back(total > 0 ? energy / total : 0.0);
        }
        const Eigen::MatrixXd temporal =
            m_training ? m_training->temporal_modes(basis, rank) : Eigen::MatrixXd(basis.temporal.leftCols(rank));
        for (int j = 0; j < rank; ++j) {
            std::vector<double> weights(m_shape.frames);
            for (int t = 0; t < m_shape.frames; ++t)
                weights[t] = temporal(t, j);
            m_report.temporal_modes.push_back(weights);
        }
        if (m_settings.report_modes <= 0)
            return;
        const int preview =
            std::min({std::max(2 * rank, m_settings.report_modes), m_shape.frames - 1, basis.modes()});
        const Eigen::MatrixXd preview_temporal = m_training ? m_training->temporal_modes(basis, preview)
                                                            : Eigen::MatrixXd(basis.temporal.leftCols(preview));
        for (int j = 0; j < preview; ++j) {
            std::vector<double> weights(m_shape.frames);
            for (int t = 0; t < m_shape.frames; ++t)
                weights[t] = preview_temporal(t, j);
            m_report.preview_temporal_modes.push_back(weights);
        }
    }

    // Rows around a band's own that sigma's windows read (see confidence.h).
    int sigma_halo_rows() const { return m_settings.sigma_radius + 1; }

    // The image rows [begin, end) of `data` that sigma's windows read for rows
    // [row, end): prepare_band rebuilds those unfiltered into m_rebuilt.
    std::pair<int, int> sigma_rows(const Band& data, int row, int end) const
    {
        return {std::max(data.row_begin, row - sigma_halo_rows()), std::min(data.row_end, end + sigma_halo_rows())};
    }

    // Pass 2 reads (or, for a kept shot, points at) rows [row, end) of every frame
    // with the plan's halo rows around them.
    Band& band_with_halo(Band& band, int row, int end)
    {
        int halo = m_report.plan.halo_rows;
        int begin = std::max(0, row - halo), stop = std::min(m_shape.height, end + halo);
        if (m_report.plan.in_memory)
            band = window(begin, stop);
        else
            read_band(band, begin, stop, nullptr);
        return band;
    }

    // The feature guide's rows for a band (with its halo), or null without features.
    const float* band_features(const Band& data, std::vector<float>& features) const
    {
        if (m_filter_options.feature_channels == 0)
            return nullptr;
        m_features->read_rows(data.row_begin, data.row_end, features);
        return features.data();
    }

    // Modes the mode filter surveys (and the K of its noise estimate): at most F − 2
    // so that the noise estimate has two degrees of freedom, at least a fixed N.
    int filter_survey_modes(const lowrank::Basis& basis) const
    {
        int modes = std::min({m_filter_options.max_modes, m_shape.frames - 2, basis.modes()});
        if (m_settings.rank.rule == lowrank::RankRule::Fixed)
            modes = std::max(modes, m_settings.rank.fixed_rank);
        return std::max(1, modes);
    }

    // The mode filter's SURE pass: a filter per mode and, for auto rank, N.
    void survey_mode_filter(const lowrank::Basis& basis)
    {
        const BandPlan& plan = m_report.plan;
        m_filter_modes = filter_survey_modes(basis);
        Eigen::MatrixXd temporal = basis.temporal.leftCols(m_filter_modes);
        SureSurvey survey(m_filter_options, m_shape.width, m_shape.height, m_shape.channels, m_filter_modes);
        // A survey task (stage_task.h) reads its own rows only, with their halo.
        const bool task = in_stage(Stage::Survey);
        const int first_row = task ? m_settings.stage->row_begin : 0;
        const int last_row = task ? m_settings.stage->row_end : m_shape.height;
        if (!task)
            ensure_whole_shot();
        if (task || !plan.in_memory)
            ++m_report.passes;
        m_progress.begin("mode filter: choosing widths", last_row - first_row);
        Band band;
        std::vector<float> coefficients, noise_variance, features;
        for (int row = first_row; row < last_row; row += plan.band_rows) {
            int end = std::min(last_row, row + plan.band_rows);
            Band& data = task ? read_task_band(band, row, end) : band_with_halo(band, row, end);
            lowrank::BandView noisy = data.view(m_shape.frames).view();
            coefficients.resize(static_cast<size_t>(data.rows) * m_filter_modes);
            lowrank::MutableBandView coefficient_view{coefficients.data(), data.rows, m_filter_modes, data.rows};
            lowrank::project_coefficients(noisy, temporal, coefficient_view);
            lowrank::ImageBandShape shape{m_shape.width, data.row_end - data.row_begin, m_shape.channels};
            coefficient_noise_variance(noisy, coefficient_view.view(), shape, m_settings.mode_filter.noise_radius,
                                       noise_variance);
            survey.add_band(coefficient_view.view(), noise_variance, shape, data.row_begin, row - data.row_begin,
                            end - data.row_begin, band_features(data, features));
            m_progress.advance(end - row);
        }
        m_progress.end();
        if (task)
            m_settings.stage->survey_rows = survey.row_sums(first_row, last_row);
        else
            finish_mode_filter_survey(survey);
    }

    // A farm task's band: rows [row, end) with the plan's halo rows around them,
    // read from the source (never the whole shot), cleaned in full.
    Band& read_task_band(Band& band, int row, int end)
    {
        const int halo = m_report.plan.halo_rows;
        read_band(band, std::max(0, row - halo), std::min(m_shape.height, end + halo), nullptr);
        return band;
    }

    // The filter per mode and, for auto rank, N from a finished survey.
    void finish_mode_filter_survey(const SureSurvey& survey)
    {
        bool fixed = m_settings.rank.rule == lowrank::RankRule::Fixed;
        m_report.mode_filter = survey.finish(fixed ? m_settings.rank.fixed_rank : 0);
        if (!fixed) {
            m_report.rank.rank = m_report.mode_filter.rank;
            m_report.rank.rule = "sure";
            m_report.rank.reasoning = m_report.mode_filter.reasoning;
        }
    }

    // The mode filter's part of pass 2 for rows [row, end) of `data`: filters the
    // first `modes` coefficient images in place (valid rows only) and leaves in
    // `gains` the noise each filtered mode keeps per valid pixel (gain_j(p)), from
    // which sigma's kept noise per frame follows (kept_noise_of_frame).
    // With --rank-map, `ranks` receives each valid pixel's rank and every filtered
    // mode is scaled by its blend weight at the pixel (rank_map.h).
    void filter_band(ScratchBuffer<float>& coefficients, const Band& data, int modes, int row, int end,
                     std::vector<float>& gains, std::vector<float>* ranks)
    {
        const std::int64_t row_samples = static_cast<std::int64_t>(m_shape.width) * m_shape.channels;
        const std::int64_t offset = (row - data.row_begin) * row_samples, valid = (end - row) * row_samples;
        lowrank::BandView noisy = data.view(m_shape.frames).view();
        lowrank::BandView surveyed{coefficients.data(), data.rows, m_filter_modes, data.rows};
        lowrank::ImageBandShape shape{m_shape.width, data.row_end - data.row_begin, m_shape.channels};
        std::vector<float>& filtered = m_filtered;  // filter_coefficients writes every value
        filtered.resize(static_cast<size_t>(valid) * modes);
        std::vector<float> noise_variance, features;
        coefficient_noise_variance(noisy, surveyed, shape, m_settings.mode_filter.noise_radius, noise_variance);
        filter_coefficients(surveyed, noise_variance, shape, row - data.row_begin, end - data.row_begin,
                            m_report.mode_filter, modes, {filtered.data(), valid, modes, valid}, gains,
                            band_features(data, features));
        const std::int64_t valid_pixels = valid / m_shape.channels;
        if (ranks) {
            std::vector<float> weights;
            local_rank(surveyed, noise_variance, shape, row - data.row_begin, end - data.row_begin,
                       m_report.mode_filter, m_report.rank.rank, modes, gains, m_settings.rank_map.radius, weights,
                       *ranks);
            for (int j = 0; j < modes; ++j)
                for (std::int64_t i = 0; i < valid; ++i) {
                    const float weight = weights[static_cast<size_t>(j * valid_pixels + i / m_shape.channels)];
                    filtered[static_cast<size_t>(j * valid + i)] *= weight;
                    if (i % m_shape.channels == 0)  // the kept noise of a scaled mode: w² · gain
                        gains[static_cast<size_t>(j * valid_pixels + i / m_shape.channels)] *= weight * weight;
                }
        }
        for (int j = 0; j < modes; ++j)
            std::copy(filtered.begin() + j * valid, filtered.begin() + (j + 1) * valid,
                      coefficients.begin() + j * data.rows + offset);
    }

    // The temporal matrices of pass 2 (what a whole run, a modes task and a write task share).
    struct RebuildBasis {
        int rank = 0;           // N
        int rebuild_modes = 0;  // modes the outputs are rebuilt from (more than N with --rank-map)
        int projected = 0;      // modes projected on (the mode filter's noise estimate needs its survey's)
        Eigen::MatrixXd temporal;            // F × rebuild_modes: the rebuild weights (B, smoothed)
        Eigen::MatrixXd temporal_rank;       // F × N of them: the unfiltered rebuild sigma's residual uses
        Eigen::MatrixXd temporal_projected;  // F × projected: the projection (A)
        Eigen::VectorXd leverages;           // h_t for sigma
    };

    RebuildBasis rebuild_basis(const lowrank::Basis& basis, int rank)
    {
        RebuildBasis result;
        result.rank = rank;
        // --rank-map: pixels may use modes beyond N, up to those the filter surveyed.
        result.rebuild_modes = m_settings.rank_map.enabled
                                   ? std::max(rank, std::min(rank + m_settings.rank_map.extra_modes, m_filter_modes))
                                   : rank;
        // With training frames the projection (A) and the rebuild (B) differ: training.h.
        result.temporal =
            m_training ? m_training->weights(basis, rank) : Eigen::MatrixXd(basis.temporal.leftCols(result.rebuild_modes));
        const bool smooth = m_settings.weight_smoothing.enabled;  // --weight-smoothing: B smoothed, A kept
        if (smooth)
            result.temporal =
                smooth_temporal_weights(result.temporal, m_settings.weight_smoothing, m_report.weight_smoothing);
        result.temporal_rank = result.temporal.leftCols(rank);
        result.leverages =
            m_training || smooth
                ? training_leverages(m_training ? m_training->projector(basis, rank) : basis.temporal.leftCols(rank),
                                     result.temporal_rank)
                : lowrank::leverages(basis, rank);
        if (m_settings.optimal_shrinkage)
            m_report.shrinkage = lowrank::optimal_shrinkage_factors(basis, m_report.rank.noise_sigma, rank);
        result.projected = m_settings.mode_filter.enabled ? std::max(result.rebuild_modes, m_filter_modes) : rank;
        result.temporal_projected =
            m_training ? m_training->projector(basis, result.projected) : basis.temporal.leftCols(result.projected);
        return result;
    }

    // Modes the outputs are rebuilt from (0: the unfiltered N of sigma's residual).
    int output_modes(const RebuildBasis& modes) const
    {
        return m_settings.mode_filter.enabled ? modes.rebuild_modes : m_settings.optimal_shrinkage ? modes.rank : 0;
    }

    // Pass 2 up to the frames, for rows [row, end) of `data` (a band with its halo):
    // the coefficients (valid rows filtered and shrunk, halo rows as projected), the
    // unfiltered rebuild of the rows sigma's windows read (m_rebuilt), s² and the
    // kept-noise gains of the valid rows. `residual` (optional; valid rows × N modes)
    // receives the valid rows' unfiltered coefficient images before the filter
    // changes them; `means` (optional; frame t's valid rows at means + t · means_stride)
    // each frame's windowed residual mean for sigma. `means` may be the valid rows
    // of `data` itself (a streamed band): nothing reads them afterwards.
    void prepare_band(const Band& data, int row, int end, const RebuildBasis& modes,
                      const lowrank::MutableBandView* residual, std::vector<float>* ranks, float* means = nullptr,
                      std::int64_t means_stride = 0)
    {
        const int frames = m_shape.frames;
        const std::int64_t row_samples = static_cast<std::int64_t>(m_shape.width) * m_shape.channels;
        const std::int64_t offset = (row - data.row_begin) * row_samples, valid = (end - row) * row_samples;
        lowrank::BandView noisy = data.view(frames).view();
        m_coefficients.resize(static_cast<size_t>(data.rows) * modes.projected);  // every value written below
        lowrank::MutableBandView coefficient_view{m_coefficients.data(), data.rows, modes.projected, data.rows};
        lowrank::project_coefficients(noisy, modes.temporal_projected, coefficient_view);
        if (residual) {
            for (int j = 0; j < modes.rank; ++j)
                std::copy_n(m_coefficients.begin() + j * data.rows + offset, valid,
                            residual->data + j * residual->frame_stride);
        }
        // Only the rows sigma's windows read are rebuilt unfiltered (the mode
        // filter's wider halo needs coefficients only).
        const auto [residual_begin, residual_end] = sigma_rows(data, row, end);
        const std::int64_t residual_first = (residual_begin - data.row_begin) * row_samples;
        const std::int64_t rebuilt_stride = (residual_end - residual_begin) * row_samples;
        m_rebuilt.resize(static_cast<size_t>(rebuilt_stride) * frames);
        lowrank::rebuild_from_coefficients(
            {m_coefficients.data() + residual_first, rebuilt_stride, modes.rank, data.rows}, modes.temporal_rank,
            {m_rebuilt.data(), rebuilt_stride, frames, rebuilt_stride});
        // The filter reads the noisy band, which the means may overwrite: it goes first.
        if (m_settings.mode_filter.enabled)
            filter_band(m_coefficients, data, modes.rebuild_modes, row, end, m_gains, ranks);
        lowrank::ImageBandShape shape{m_shape.width, residual_end - residual_begin, m_shape.channels};
        m_noise_variance.resize(static_cast<size_t>(valid));
        lowrank::residual_noise_variance({noisy.data + residual_first, rebuilt_stride, frames, noisy.frame_stride},
                                         {m_rebuilt.data(), rebuilt_stride, frames, rebuilt_stride}, shape,
                                         modes.rank, row - residual_begin, end - residual_begin, m_confidence,
                                         m_noise_variance.data(), means, means_stride);
        for (size_t j = 0; j < m_report.shrinkage.size(); ++j)  // --shrink optimal, the band's own rows
            for (std::int64_t i = 0; i < valid; ++i)
                m_coefficients[j * data.rows + offset + i] *= static_cast<float>(m_report.shrinkage[j]);
    }

    // The noise each rebuilt sample of frame t keeps under the mode filter,
    // h_t(p) = Σ_j V_tj² · gain_j(p), for `samples` samples of the gains' pixels.
    void kept_noise_of_frame(const Eigen::MatrixXd& temporal, int t, int modes, const float* gains,
                             std::int64_t samples, float* kept) const
    {
        const std::int64_t pixels = samples / m_shape.channels;
        for (std::int64_t pixel = 0; pixel < pixels; ++pixel) {
            double sum = 0;
            for (int j = 0; j < modes; ++j)
                sum += temporal(t, j) * temporal(t, j) * gains[static_cast<size_t>(j * pixels + pixel)];
            std::fill_n(kept + pixel * m_shape.channels, m_shape.channels, static_cast<float>(sum));
        }
    }

    void rebuild(const lowrank::Basis& basis, int rank)
    {
        const RebuildBasis modes = rebuild_basis(basis, rank);
        m_confidence.radius = m_settings.sigma_radius;
        if (in_stage(Stage::Modes)) {
            modes_stage(modes);
            return;
        }
        if (in_stage(Stage::Write)) {
            write_stage(modes);
            return;
        }
        const BandPlan& plan = m_report.plan;
        const bool rank_map = m_settings.rank_map.enabled, filter = m_settings.mode_filter.enabled;
        const int frames = m_shape.frames, output = output_modes(modes);
        const std::int64_t row_samples = static_cast<std::int64_t>(m_shape.width) * m_shape.channels;

        bool kept = plan.in_memory;  // pass 2 reuses the kept shot: no second read
        ensure_whole_shot();
        if (!kept)
            ++m_report.passes;
        m_sink.begin({rank, m_report.rank.rule, m_report.solver});
        m_progress.begin("rebuilding frames", m_shape.height);
        if (rank_map)
            m_report.rank_map.largest_rank = modes.rebuild_modes;
        Band band;
        // Reused from band to band: fresh buffers of this size cost the kernel's page
        // zeroing every band (7.5 % of a 1080p run's time).
        ScratchBuffer<float> kept_sigma;  // sigma_from_mean writes every value
        std::vector<float> ranks;
        for (int row = 0; row < m_shape.height; row += plan.band_rows) {
            int end = std::min(m_shape.height, row + plan.band_rows);
            Band& data = band_with_halo(band, row, end);
            throw_if_cancelled();
            const std::int64_t offset = (row - data.row_begin) * row_samples, valid = (end - row) * row_samples;
            // Sigma of the band's own rows: prepare_band leaves each frame's windowed
            // residual mean there (the pass that finds s²), finished frame by frame.
            // A streamed band's own input rows hold it (nothing reads them after
            // prepare_band); a kept shot's must stay, so sigma gets its own buffer.
            float* sigma = nullptr;
            std::int64_t sigma_stride = valid;
            if (kept) {
                kept_sigma.resize(static_cast<size_t>(valid) * frames);
                sigma = kept_sigma.data();
            } else {
                sigma = band.storage.data() + offset;
                sigma_stride = data.stride;
            }
            prepare_band(data, row, end, modes, nullptr, rank_map ? &ranks : nullptr, sigma, sigma_stride);
            // m_rebuilt holds the unfiltered rebuild of sigma's rows; the output goes over its valid ones.
            const std::pair<int, int> residual_rows = sigma_rows(data, row, end);
            const int residual_begin = residual_rows.first, residual_end = residual_rows.second;
            const std::int64_t rebuilt_stride = (residual_end - residual_begin) * row_samples;
            const lowrank::ImageBandShape shape{m_shape.width, residual_end - residual_begin, m_shape.channels};
            tbb::parallel_for(0, frames, [&](int t) {
                std::vector<float>& kept_noise = m_kept_noise.local();  // nothing below runs in parallel
                if (filter) {
                    kept_noise.resize(static_cast<size_t>(valid));
                    kept_noise_of_frame(modes.temporal, t, modes.rebuild_modes, m_gains.data(), valid,
                                        kept_noise.data());
                }
                lowrank::sigma_from_mean(shape, row - residual_begin, end - residual_begin, m_confidence,
                                         m_noise_variance.data(), modes.leverages(t),
                                         filter ? kept_noise.data() : nullptr, sigma + t * sigma_stride);
            });
            lowrank::MutableBandView output_view{m_rebuilt.data() + (row - residual_begin) * row_samples, valid,
                                                 frames, rebuilt_stride};
            if (output > 0)  // the band's own rows from the changed coefficients
                lowrank::rebuild_from_coefficients({m_coefficients.data() + offset, valid, output, data.rows},
                                                   modes.temporal.leftCols(output), output_view);
            m_report.non_negative +=
                make_non_negative(output_view, m_settings.non_negative, m_settings.non_negative_floor);

            tbb::parallel_for(0, frames, [&](int frame) {
                m_sink.write_rows(frame, row, end, output_view.data + frame * output_view.frame_stride,
                                  sigma + frame * sigma_stride);
            });
            if (m_sink.wants_modes())
                write_modes(m_coefficients, data, basis, rank, row, end, offset);
            if (rank_map) {
                m_sink.write_rank_rows(row, end, ranks.data());
                m_report.rank_map.add(ranks);
            }
            m_progress.advance(end - row);
        }
        if (rank_map)
            m_report.rank_map.finish();
        m_progress.end();
    }

    // --stage modes: pass 2 over the task's rows up to the frames (stage_task.h):
    // each band read with its halo, its cleaned values that differ from the files
    // kept as patches, and prepare_band's results of the band's own rows kept.
    void modes_stage(const RebuildBasis& modes)
    {
        StageTask& task = *m_settings.stage;
        const std::int64_t row_samples = static_cast<std::int64_t>(m_shape.width) * m_shape.channels;
        const std::int64_t samples = row_samples * (task.row_end - task.row_begin);
        const std::int64_t pixels = samples / m_shape.channels;
        ModesBand result;
        result.row_begin = task.row_begin;
        result.row_end = task.row_end;
        result.residual_modes = modes.rank;
        result.output_modes = output_modes(modes);
        result.gain_modes = m_settings.mode_filter.enabled ? modes.rebuild_modes : 0;
        result.residual.resize(static_cast<size_t>(samples) * result.residual_modes);
        result.output.resize(static_cast<size_t>(samples) * result.output_modes);
        result.noise_variance.resize(static_cast<size_t>(samples));
        result.gains.resize(static_cast<size_t>(pixels) * result.gain_modes);
        ++m_report.passes;
        m_progress.begin(fmt::format("modes of rows {}-{}: reading {} frames", task.row_begin, task.row_end - 1,
                                     m_shape.frames),
                         task.row_end - task.row_begin);
        Band band;
        for (int row = task.row_begin; row < task.row_end; row += m_report.plan.band_rows) {
            const int end = std::min(task.row_end, row + m_report.plan.band_rows);
            m_patches = {row, end, task.row_begin, &result.patches};
            read_task_band(band, row, end);
            m_patches = {};
            // The band's own rows go into the task's images, mode by mode.
            const std::int64_t valid = (end - row) * row_samples, first = (row - task.row_begin) * row_samples;
            const std::int64_t offset = (row - band.row_begin) * row_samples;
            const lowrank::MutableBandView residual{result.residual.data() + first, valid, result.residual_modes,
                                                    samples};
            prepare_band(band, row, end, modes, &residual, nullptr);
            for (int j = 0; j < result.output_modes; ++j)
                std::copy_n(m_coefficients.begin() + j * band.rows + offset, valid,
                            result.output.begin() + j * samples + first);
            std::copy_n(m_noise_variance.begin(), valid, result.noise_variance.begin() + first);
            const std::int64_t valid_pixels = valid / m_shape.channels, first_pixel = first / m_shape.channels;
            for (int j = 0; j < result.gain_modes; ++j)
                std::copy_n(m_gains.begin() + j * valid_pixels, valid_pixels,
                            result.gains.begin() + j * pixels + first_pixel);
            m_progress.advance(end - row);
        }
        m_progress.end();
        task.modes.clear();
        task.modes.push_back(std::move(result));
    }

    // --stage write: the outputs of the frames the sink writes, each read alone and
    // rebuilt from the modes tasks' images (stage_task.h) with the arithmetic of a
    // whole run's pass 2, so the bits agree.
    void write_stage(const RebuildBasis& modes)
    {
        StageTask& task = *m_settings.stage;
        const ShotModes shot = join_modes_bands(task.modes, m_shape, modes.rank, output_modes(modes),
                                                m_settings.mode_filter.enabled ? modes.rebuild_modes : 0);
        task.modes.clear();
        std::vector<int> written;
        for (int t = 0; t < m_shape.frames; ++t)
            if (m_sink.writes_frame(t))
                written.push_back(t);
        const std::int64_t samples = static_cast<std::int64_t>(m_shape.width) * m_shape.height * m_shape.channels;
        const lowrank::ImageBandShape shape{m_shape.width, m_shape.height, m_shape.channels};
        const Eigen::MatrixXd output_temporal = modes.temporal.leftCols(std::max(shot.output_modes, 1));
        ++m_report.passes;
        m_sink.begin({modes.rank, m_report.rank.rule, m_report.solver});
        m_progress.begin(fmt::format("writing {} of {} frames", written.size(), m_shape.frames),
                         static_cast<std::int64_t>(written.size()));
        struct Buffers {
            std::vector<float> noisy, unfiltered, kept_noise, sigma, output;
        };
        tbb::enumerable_thread_specific<Buffers> thread_buffers;
        std::mutex counts_mutex;
        tbb::parallel_for(0, static_cast<int>(written.size()), [&](int k) {
            throw_if_cancelled();
            const int t = written[static_cast<size_t>(k)];
            Buffers& buffers = thread_buffers.local();
            for (std::vector<float>* buffer :
                 {&buffers.noisy, &buffers.unfiltered, &buffers.kept_noise, &buffers.sigma, &buffers.output})
                buffer->resize(static_cast<size_t>(samples));
            m_source.read_rows(t, 0, m_shape.height, buffers.noisy.data());
            for (const ModesBand::Patch& patch : shot.patches[static_cast<size_t>(t)])
                buffers.noisy[static_cast<size_t>(patch.sample)] = patch.value;
            lowrank::rebuild_from_coefficients({shot.residual.data(), samples, shot.residual_modes, samples},
                                               modes.temporal_rank.row(t), {buffers.unfiltered.data(), samples, 1, samples});
            if (shot.gain_modes > 0)
                kept_noise_of_frame(modes.temporal, t, shot.gain_modes, shot.gains.data(), samples,
                                    buffers.kept_noise.data());
            lowrank::frame_sigma(buffers.noisy.data(), buffers.unfiltered.data(), shape, 0, m_shape.height,
                                 m_confidence, shot.noise_variance.data(), modes.leverages(t),
                                 shot.gain_modes > 0 ? buffers.kept_noise.data() : nullptr, buffers.sigma.data());
            std::vector<float>& output = shot.output_modes > 0 ? buffers.output : buffers.unfiltered;
            if (shot.output_modes > 0)
                lowrank::rebuild_from_coefficients({shot.output.data(), samples, shot.output_modes, samples},
                                                   output_temporal.row(t), {output.data(), samples, 1, samples});
            const NonNegativeCounts counts = make_non_negative({output.data(), samples, 1, samples},
                                                               m_settings.non_negative, m_settings.non_negative_floor);
            {
                std::lock_guard<std::mutex> lock(counts_mutex);
                m_report.non_negative += counts;
            }
            m_sink.write_rows(t, 0, m_shape.height, output.data(), buffers.sigma.data());
            m_progress.advance(1);
        });
        m_progress.end();
    }

    // Spatial modes ps(x, y, j) = coefficient_j / σ_j, for inspection ([0048]).
    void write_modes(const ScratchBuffer<float>& coefficients, const Band& data, const lowrank::Basis& basis, int rank,
                     int row, int end, std::int64_t offset)
    {
        std::int64_t samples = static_cast<std::int64_t>(m_shape.width) * (end - row) * m_shape.channels;
        std::vector<float> modes(static_cast<size_t>(samples) * rank);
        for (int j = 0; j < rank; ++j) {
            double scale = m_training ? 1.0 : basis.singular_values[j] > 0 ? 1.0 / basis.singular_values[j] : 0.0;
            for (std::int64_t i = 0; i < samples; ++i)
                modes[j * samples + i] = static_cast<float>(coefficients[j * data.rows + offset + i] * scale);
        }
        m_sink.write_mode_rows(row, end, rank, modes.data());
    }

    FrameSource& m_source;
    FrameSink& m_sink;
    const Settings& m_settings;
    Progress& m_progress;
    ShotShape m_shape;
    Report m_report;
    Band m_whole;  // the kept shot, when it fits in memory
    // Streaming: 1 for each sample whose row (over frames) the outlier cleaning changed.
    std::vector<std::uint8_t> m_cleaned_samples;
    double m_solve_seconds = 0;
    int m_filter_modes = 0;  // modes the mode filter surveyed
    std::vector<float> m_filtered;  // filter_band's output, reused from band to band
    // prepare_band's results for the current band, reused from band to band:
    ScratchBuffer<float> m_coefficients;  // [mode][sample] of the band with its halo
    ScratchBuffer<float> m_rebuilt;       // [frame][sample] of sigma_rows(): the unfiltered rebuild, then the output rows
    std::vector<float> m_noise_variance;  // sigma's s² of the valid rows
    std::vector<float> m_gains;           // the mode filter's kept-noise gain per valid pixel and mode
    lowrank::ConfidenceOptions m_confidence;
    tbb::enumerable_thread_specific<std::vector<float>> m_kept_noise;  // one frame's, per worker
    // --stage modes: read_band records the cleaned values of rows [row_begin, row_end)
    // that differ from the files, samples counted from first_row.
    struct PatchRows {
        int row_begin = 0, row_end = 0, first_row = 0;
        std::vector<ModesBand::Patch>* patches = nullptr;
    } m_patches;
    ModeFilterOptions m_filter_options;       // the settings' with the feature channels found
    std::optional<FeatureGuide> m_features;  // the mode filter's feature guide
    std::optional<TrainingGram> m_training;  // --train-frames
};

}  // namespace

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
    case Solver::Gram: return "gram";
    case Solver::RandomizedSvd: return "rsvd";
    default: return "auto";
    }
}

Report run_denoise(FrameSource& source, FrameSink& sink, const Settings& settings, Progress& progress)
{
    return Engine(source, sink, settings, progress).run();
}

}  // namespace modestack::denoise
