#include "core/denoise/layer_runs.h"

#include "core/common/error.h"
#include "core/denoise/layer_views.h"
#include "core/denoise/passes.h"

#include <fmt/format.h>

#include <chrono>
#include <memory>
#include <optional>

namespace modestack::denoise {
namespace {

// Frames decoded at a time for every layer when the shot is kept: enough for
// both of a 2-core machine's threads and a few more.
constexpr int kSharedFrames = 8;

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point start)
{
    return std::chrono::duration<double>(Clock::now() - start).count();
}

// One layer's run: its view of the shot, its own settings and passes' state.
struct Layer {
    Layer(SharedRows& rows, LayerCombiner& combiner, int index, ChannelRange range, const Settings& shared)
        : source(rows, range, index == 0), sink(combiner, index),
          settings(shared), context{source, sink, settings, Progress::silent()}
    {
        settings.layer_channels.clear();
        settings.layer_whitening.clear();
        // The layer's own weights (from its own variance), as a run of it alone would have them.
        settings.whitening = shared.layer_whitening.empty() ? nullptr : shared.layer_whitening[index];
    }

    LayerSource source;
    LayerSink sink;
    Settings settings;
    PassContext context;
    std::optional<RunPlan> plan; // RunPlan holds a FeatureGuide, which cannot be assigned
    std::optional<ShotStream> stream;
    std::optional<Solution> solution;
    Survey survey;
    std::optional<RebuildBasis> modes;
    Report report;
};

// Calls `step(layer index, row, end)` for every band of rows, each band for every layer in turn.
template <typename Step>
void for_each_band_of_layers(size_t layers, const BandPlan& bands, int height, Progress& progress,
                             Step&& step)
{
    for (int row = 0; row < height; row += bands.halo_band_rows) {
        const int end = std::min(height, row + bands.halo_band_rows);
        for (size_t i = 0; i < layers; ++i)
            step(i, row, end);
        progress.advance(end - row);
    }
}

} // namespace

std::vector<Report> run_layers(FrameSource& source, FrameSink& sink, const Settings& settings,
                               Progress& progress)
{
    const ShotShape shape = source.shape();
    const std::vector<ChannelRange> ranges = layer_ranges(settings.layer_channels, shape);
    if (ranges.size() < 2)
        throw internal_error("run_layers needs at least two layers");
    // Weights of every channel together have the wrong normalisation for any one layer.
    if (settings.whitening)
        throw internal_error(
            "layers apart are whitened by Settings::layer_whitening, not Settings::whitening");
    if (!settings.layer_whitening.empty() && settings.layer_whitening.size() != ranges.size())
        throw internal_error(fmt::format("{} layers' whitening weights for {} layers",
                                         settings.layer_whitening.size(), ranges.size()));
    SharedRows rows(source);
    LayerCombiner combiner(sink, shape, ranges);
    std::vector<std::unique_ptr<Layer>> layers;
    for (size_t i = 0; i < ranges.size(); ++i) {
        layers.push_back(std::make_unique<Layer>(rows, combiner, static_cast<int>(i), ranges[i], settings));
        check_settings(layers.back()->settings, layers.back()->source.shape());
    }
    // One band plan for all: the layers read the same rows in turn. Beside each
    // layer's own rows it counts the shared rows of a band and the gathered write.
    // Noise that repeats, each layer's from one read of the frames it takes.
    std::vector<ChannelGroup> groups;
    for (const ChannelRange& range : ranges)
        groups.push_back({range.first, range.count});
    const std::vector<RepeatingNoise> repeating = measure_repeating_noise(source, groups, progress);
    for (size_t i = 0; i < layers.size(); ++i) {
        Layer& layer = *layers[i];
        layer.plan.emplace(plan_run(layer.context, true));
        layer.plan->repeating = layer.report.repeating_noise = repeating[i];
    }
    PassNeeds needs = pass_needs(settings, shape, layers.front()->plan->filter, source.band_bytes_per_row());
    needs.shared_rows = true;
    needs.shared_frames = kSharedFrames;
    const BandPlan bands = plan_bands(shape, settings.max_memory_bytes, needs);
    for (auto& layer : layers) {
        layer->plan->bands = bands;
        layer->stream.emplace(layer->source, layer->settings.outliers, bands, Progress::silent());
        layer->report.shape = layer->source.shape();
        layer->report.plan = bands;
        layer->report.solver = solver_name(layer->plan->solver);
        if (layer->plan->features)
            layer->report.feature_guide = layer->plan->features->summary();
    }
    const std::string counted = fmt::format("{} frames, {} layers", shape.frames, layers.size());

    // A kept shot: read a few frames for every layer at a time and let them go,
    // so that the decoded rows never hold more than those frames beside the
    // layers' own copies.
    if (bands.in_memory) {
        progress.begin(fmt::format("reading {}", counted), shape.frames);
        for (int frame = 0; frame < shape.frames; frame += kSharedFrames) {
            const int end = std::min(shape.frames, frame + kSharedFrames);
            for (auto& layer : layers)
                layer->stream->read_whole_frames(frame, end);
            rows.release(frame, end);
            progress.advance(end - frame);
        }
        for (auto& layer : layers)
            layer->stream->finish_whole_shot();
        progress.end();
    }

    // Statistics and solve. The randomized SVD's passes are inside its solver: each layer reads on its own.
    auto start = Clock::now();
    if (layers.front()->plan->solver == Solver::Gram) {
        std::vector<GramPass> grams;
        std::vector<std::unique_ptr<ShotStream::BandPass>> passes;
        for (auto& layer : layers) {
            grams.emplace_back(layer->settings, layer->stream->shape());
            passes.push_back(std::make_unique<ShotStream::BandPass>(*layer->stream));
        }
        progress.begin(fmt::format("pass 1: reading {}", counted), shape.height);
        for (bool more = true; more;) {
            int rows_done = 0;
            for (size_t i = 0; i < layers.size(); ++i)
                if (Band* band = passes[i]->next()) {
                    grams[i].add(*band);
                    rows_done = band->row_end - band->row_begin;
                } else {
                    more = false;
                }
            progress.advance(rows_done);
        }
        progress.end();
        for (size_t i = 0; i < layers.size(); ++i)
            layers[i]->solution.emplace(grams[i].finish(layers[i]->stream->frame_scale_factors()));
    } else {
        for (auto& layer : layers)
            layer->solution.emplace(randomized_solution(layer->context, *layer->stream));
    }
    const double statistics_seconds = seconds_since(start);

    // Survey: each layer's filters and N.
    start = Clock::now();
    for (auto& layer : layers)
        layer->survey = unfiltered_survey(*layer->solution);
    double survey_seconds = 0;
    if (settings.mode_filter.enabled) {
        std::vector<std::unique_ptr<SurveyPass>> surveys;
        for (auto& layer : layers)
            surveys.push_back(std::make_unique<SurveyPass>(layer->context, *layer->stream, *layer->plan,
                                                           *layer->solution, 0, shape.height, false));
        progress.begin(fmt::format("mode filter: choosing widths ({})", counted), shape.height);
        for_each_band_of_layers(layers.size(), bands, shape.height, progress,
                                [&](size_t i, int row, int end) { surveys[i]->add_rows(row, end); });
        progress.end();
        for (size_t i = 0; i < layers.size(); ++i)
            layers[i]->survey = finish_survey(layers[i]->settings, layers[i]->stream->shape(),
                                              *layers[i]->plan, *layers[i]->solution, surveys[i]->finish());
        survey_seconds = seconds_since(start);
    }
    for (auto& layer : layers)
        layer->modes.emplace(chosen_modes(layer->settings, layer->stream->shape(), *layer->solution,
                                          layer->survey, layer->report));
    const double solve_seconds = seconds_since(start) - survey_seconds;

    // Pass 2: every layer's rows of a band, then the band written.
    start = Clock::now();
    std::vector<std::unique_ptr<RebuildPass>> rebuilds;
    for (auto& layer : layers)
        rebuilds.push_back(std::make_unique<RebuildPass>(layer->context, *layer->stream, *layer->plan,
                                                         *layer->solution, layer->survey, *layer->modes));
    progress.begin(fmt::format("rebuilding frames ({})", counted), shape.height);
    for_each_band_of_layers(layers.size(), bands, shape.height, progress,
                            [&](size_t i, int row, int end) { rebuilds[i]->add_rows(row, end); });
    progress.end();
    const double rebuild_seconds = seconds_since(start);

    std::vector<Report> reports;
    for (size_t i = 0; i < layers.size(); ++i) {
        Layer& layer = *layers[i];
        const RebuildReport rebuilt = rebuilds[i]->finish();
        layer.report.outliers = layer.stream->outliers();
        layer.report.non_negative = rebuilt.non_negative;
        layer.report.rank_map = rebuilt.rank_map;
        layer.report.estimator_choice = rebuilt.estimator_choice;
        layer.report.frame_noise_factors = rebuilt.frame_noise_factors;
        layer.report.passes = layer.stream->passes();
        layer.report.seconds_statistics = statistics_seconds;
        layer.report.seconds_filter_survey = survey_seconds;
        layer.report.seconds_solve = solve_seconds;
        layer.report.seconds_rebuild = rebuild_seconds;
        reports.push_back(std::move(layer.report));
    }
    return reports;
}

Report merge_layer_reports(std::vector<Report> layers, const ShotShape& shape)
{
    Report merged = layers.front();
    merged.shape = shape;
    for (size_t i = 1; i < layers.size(); ++i) {
        const Report& layer = layers[i];
        merged.outliers.non_finite += layer.outliers.non_finite;
        merged.outliers.fireflies += layer.outliers.fireflies;
        merged.non_negative += layer.non_negative;
        for (size_t t = 0; t < merged.estimator_choice.size() && t < layer.estimator_choice.size(); ++t)
            merged.estimator_choice[t].add(layer.estimator_choice[t]);
    }
    merged.layers = std::move(layers);
    return merged;
}

} // namespace modestack::denoise
