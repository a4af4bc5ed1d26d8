#include "core/denoise/engine.h"

#include "core/common/error.h"
#include "core/lowrank/basis.h"
#include "core/lowrank/confidence.h"
#include "core/lowrank/gram.h"
#include "core/lowrank/projection.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>

namespace modestack::denoise {
namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

// A band of rows [row_begin, row_end) of every frame, frame-major.
struct Band {
    int row_begin = 0;
    int row_end = 0;
    std::int64_t rows = 0;  // samples per frame: width * (row_end - row_begin) * channels
    std::vector<float> values;

    lowrank::MutableBandView view(int frames)
    {
        return {values.data(), rows, frames, rows};
    }
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
        // Sigma's window reads radius + 1 rows around a pixel (see confidence.h).
        m_report.plan = plan_bands(m_shape, m_settings.max_memory_bytes, m_settings.sigma_radius + 1, largest_rank);
        Solver solver = m_settings.solver;
        if (solver == Solver::Auto)
            solver = m_shape.frames >= m_settings.randomized_from_frames ? Solver::RandomizedSvd : Solver::Gram;
        m_report.solver = solver_name(solver);

        auto start = Clock::now();
        lowrank::Basis basis = solver == Solver::Gram ? gram_basis() : randomized_basis();
        m_report.seconds_statistics = seconds_since(start);

        start = Clock::now();
        m_report.rank = lowrank::choose_rank(basis, m_settings.rank);
        int rank = m_report.rank.rank;
        describe_basis(basis, rank);
        m_report.seconds_solve = seconds_since(start) + m_solve_seconds;
        m_report.seconds_statistics -= m_solve_seconds;

        start = Clock::now();
        rebuild(basis, rank);
        m_report.seconds_rebuild = seconds_since(start);
        return m_report;
    }

private:
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
    }

    // Reads rows [row_begin, row_end) of every frame (frames in parallel) and cleans them.
    void read_band(Band& band, int row_begin, int row_end, lowrank::OutlierCounts* counts)
    {
        throw_if_cancelled();
        band.row_begin = row_begin;
        band.row_end = row_end;
        band.rows = static_cast<std::int64_t>(m_shape.width) * (row_end - row_begin) * m_shape.channels;
        band.values.resize(static_cast<size_t>(band.rows) * m_shape.frames);
        tbb::parallel_for(0, m_shape.frames, [&](int frame) {
            m_source.read_rows(frame, row_begin, row_end, band.values.data() + frame * band.rows);
        });
        lowrank::OutlierCounts found = lowrank::clean_outliers(band.view(m_shape.frames), m_settings.outliers);
        if (counts) {
            counts->non_finite += found.non_finite;
            counts->fireflies += found.fireflies;
        }
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
        Band band;
        for (int row = 0; row < m_shape.height; row += plan.band_rows) {
            int end = std::min(m_shape.height, row + plan.band_rows);
            read_band(plan.in_memory ? m_whole : band, row, end, first_pass ? &m_report.outliers : nullptr);
            visit(plan.in_memory ? m_whole : band);
            m_progress.advance(end - row);
        }
        m_progress.end();
    }

    // Feeds a band to `add` in fixed chunks of kChunkRows image rows, so the
    // summation order does not depend on the band height.
    template <typename Add> void for_each_chunk(Band& band, Add&& add)
    {
        std::int64_t row_samples = static_cast<std::int64_t>(m_shape.width) * m_shape.channels;
        for (int row = band.row_begin; row < band.row_end; row += kChunkRows) {
            int end = std::min(band.row_end, row + kChunkRows);
            lowrank::BandView chunk{band.values.data() + (row - band.row_begin) * row_samples,
                                    (end - row) * row_samples, m_shape.frames, band.rows};
            add(chunk);
        }
    }

    lowrank::Basis gram_basis()
    {
        lowrank::GramAccumulator gram(m_shape.frames);
        for_each_band([&](Band& band) { for_each_chunk(band, [&](const lowrank::BandView& chunk) { gram.add(chunk); }); });
        auto start = Clock::now();
        lowrank::Basis basis = lowrank::basis_from_gram(gram);
        basis.passes = 1;
        m_solve_seconds = seconds_since(start);
        return basis;
    }

    lowrank::Basis randomized_basis()
    {
        lowrank::BandPass pass = [&](const std::function<void(const lowrank::BandView&)>& visit) {
            for_each_band([&](Band& band) { for_each_chunk(band, visit); });
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
        for (int j = 0; j < rank; ++j) {
            std::vector<double> weights(m_shape.frames);
            for (int t = 0; t < m_shape.frames; ++t)
                weights[t] = basis.temporal(t, j);
            m_report.temporal_modes.push_back(weights);
        }
    }

    void rebuild(const lowrank::Basis& basis, int rank)
    {
        const BandPlan& plan = m_report.plan;
        Eigen::MatrixXd temporal = basis.temporal.leftCols(rank);
        Eigen::VectorXd leverages = lowrank::leverages(basis, rank);
        int frames = m_shape.frames;
        std::int64_t row_samples = static_cast<std::int64_t>(m_shape.width) * m_shape.channels;
        lowrank::ConfidenceOptions confidence;
        confidence.radius = m_settings.sigma_radius;

        bool kept = plan.in_memory;  // pass 2 reuses the kept shot: no second read
        if (!kept)
            ++m_report.passes;
        m_sink.begin({rank, m_report.rank.rule, m_report.solver});
        m_progress.begin("rebuilding frames", m_shape.height);
        Band band, coefficients_band;
        std::vector<float> rebuilt, sigma;
        for (int row = 0; row < m_shape.height; row += plan.band_rows) {
            int end = std::min(m_shape.height, row + plan.band_rows);
            int read_begin = std::max(0, row - plan.halo_rows), read_end = std::min(m_shape.height, end + plan.halo_rows);
            Band& data = kept ? m_whole : band;
            if (!kept)
                read_band(band, read_begin, read_end, nullptr);
            throw_if_cancelled();
            lowrank::BandView noisy{data.values.data(), data.rows, frames, data.rows};

            std::vector<float> coefficients(static_cast<size_t>(data.rows) * rank);
            lowrank::MutableBandView coefficient_view{coefficients.data(), data.rows, rank, data.rows};
            lowrank::project_coefficients(noisy, temporal, coefficient_view);
            rebuilt.resize(data.values.size());
            lowrank::MutableBandView rebuilt_view{rebuilt.data(), data.rows, frames, data.rows};
            lowrank::rebuild_from_coefficients(coefficient_view.view(), temporal, rebuilt_view);
            // Sigma only for the band's own rows, laid out like the rebuilt band.
            std::int64_t offset = (row - data.row_begin) * row_samples;
            sigma.assign(data.values.size(), 0.0f);
            lowrank::MutableBandView sigma_view{sigma.data() + offset, (end - row) * row_samples, frames, data.rows};
            lowrank::ImageBandShape shape{m_shape.width, data.row_end - data.row_begin, m_shape.channels};
            lowrank::confidence_band(noisy, rebuilt_view.view(), shape, leverages, rank, row - data.row_begin,
                                     end - data.row_begin, confidence, sigma_view);

            tbb::parallel_for(0, frames, [&](int frame) {
                m_sink.write_rows(frame, row, end, rebuilt.data() + frame * data.rows + offset,
                                  sigma.data() + frame * data.rows + offset);
            });
            if (m_sink.wants_modes())
                write_modes(coefficients, data, basis, rank, row, end, offset);
            m_progress.advance(end - row);
        }
        m_progress.end();
    }

    // Spatial modes ps(x, y, j) = coefficient_j / σ_j, for inspection ([0048]).
    void write_modes(const std::vector<float>& coefficients, const Band& data, const lowrank::Basis& basis, int rank,
                     int row, int end, std::int64_t offset)
    {
        std::int64_t samples = static_cast<std::int64_t>(m_shape.width) * (end - row) * m_shape.channels;
        std::vector<float> modes(static_cast<size_t>(samples) * rank);
        for (int j = 0; j < rank; ++j) {
            double scale = basis.singular_values[j] > 0 ? 1.0 / basis.singular_values[j] : 0.0;
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
    double m_solve_seconds = 0;
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
