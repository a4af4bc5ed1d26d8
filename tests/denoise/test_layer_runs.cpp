// Several layers in one run, each on its own modes (core/denoise/layer_runs.h):
// every layer gets the bits of a run of that layer alone (kept and streamed,
// gram and rsvd, with and without the mode filter and the estimator choice);
// the files are decoded once per pass, not once per layer; and a layer whose
// light differs from the other's is denoised better on its own modes than on
// shared ones. With --whiten a layer that has its own variance is whitened by
// weights from that variance alone, the same bits as a run of it alone.
#include "core/common/error.h"
#include "core/denoise/engine.h"
#include "core/denoise/passes.h"
#include "core/denoise/whitening.h"
#include "tests/denoise/memory_shot.h"

#include <doctest/doctest.h>

#include <atomic>
#include <cmath>
#include <optional>
#include <random>
#include <string>
#include <vector>

using namespace modestack;
using namespace modestack::denoise;
using namespace modestack::denoise::testing;

namespace {

constexpr int kWidth = 40, kHeight = 240, kFrames = 20; // tall enough to stream

// Layer A: a static image times a slow fade (rank 1). Layer B: a light that
// switches on at frame 12 over a moving gradient (rank 3), unlike A.
float layer_value(int layer, int x, int y, int c, int t)
{
    const float time = static_cast<float>(t) / kFrames;
    if (layer == 0)
        return (1.0f + 0.5f * std::sin(0.3f * x + c)) * (1.0f + 0.2f * time);
    return 0.5f + 0.3f * std::cos(0.2f * y + c) * std::sin(5.0f * time) +
           (t >= 12 ? 0.8f * ((x + 2 * y) % 9) / 9.0f : 0.0f);
}

// Layer `layer` (0, 1) alone, or both (-1) interleaved per pixel [A rgb, B rgb].
MemoryShot shot_of(int layer, float noise)
{
    MemoryShot shot;
    const int channels = layer < 0 ? 6 : 3;
    shot.size = {kFrames, kWidth, kHeight, channels};
    for (int t = 0; t < kFrames; ++t) {
        std::mt19937 generator(1000 + t);
        std::normal_distribution<float> normal(0.0f, noise);
        std::vector<float> frame(std::size_t(kWidth) * kHeight * channels);
        for (int y = 0; y < kHeight; ++y)
            for (int x = 0; x < kWidth; ++x)
                for (int l = 0; l < 2; ++l)
                    for (int c = 0; c < 3; ++c) {
                        const float value =
                            layer_value(l, x, y, c, t) + (noise > 0 ? normal(generator) : 0.0f);
                        if (layer < 0)
                            frame[(std::size_t(y) * kWidth + x) * 6 + l * 3 + c] = value;
                        else if (l == layer)
                            frame[(std::size_t(y) * kWidth + x) * 3 + c] = value;
                    }
        shot.frames.push_back(frame);
    }
    return shot;
}

// Channels [first, first + 3) of every pixel of a 6-channel shot's frames.
std::vector<std::vector<float>> layer_of(const std::vector<std::vector<float>>& frames, int first)
{
    std::vector<std::vector<float>> layer;
    for (const auto& frame : frames) {
        std::vector<float> values;
        for (std::size_t p = 0; p < frame.size() / 6; ++p)
            for (int c = 0; c < 3; ++c)
                values.push_back(frame[p * 6 + first + c]);
        layer.push_back(values);
    }
    return layer;
}

// Counts the rows the engine asks the shot for.
struct CountingShot : ForwardingSource {
    using ForwardingSource::ForwardingSource;
    std::atomic<std::int64_t> reads{0}, rows{0};
    void read_rows(int frame, int row_begin, int row_end, float* destination,
                   PassThroughRows* pass_through) override
    {
        ++reads;
        rows += row_end - row_begin;
        ForwardingSource::read_rows(frame, row_begin, row_end, destination, pass_through);
    }
};

Settings layered(Settings settings)
{
    settings.layer_channels = {3, 3};
    return settings;
}

// The largest budget (in steps of 10 %) at which a layered run of `shot` streams,
// from the band plan itself (cheap: no run), as run_layers makes it.
std::int64_t streaming_budget(const MemoryShot& shot, const Settings& settings)
{
    PassNeeds needs = pass_needs(settings, shot.size, settings.mode_filter, 0);
    needs.shared_rows = true;
    needs.shared_frames = 8;
    for (std::int64_t memory = 40'000'000; memory > 1'000'000; memory = memory * 9 / 10) {
        try {
            if (!plan_bands(shot.size, memory, needs).in_memory)
                return memory;
        } catch (const Error&) { // too small for a band
            break;
        }
    }
    FAIL("no budget streams the shot");
    return 0;
}

// A noise variance for layer `layer`'s channel c that varies over the image
// and over time, per frame [row][x][channel] (3 channels: one layer; 6: both).
std::vector<std::vector<float>> variance_of(int layer)
{
    const int channels = layer < 0 ? 6 : 3;
    std::vector<std::vector<float>> frames;
    for (int t = 0; t < kFrames; ++t) {
        std::vector<float> frame(std::size_t(kWidth) * kHeight * channels);
        for (std::size_t p = 0; p < std::size_t(kWidth) * kHeight; ++p)
            for (int c = 0; c < channels; ++c) {
                const int l = layer < 0 ? c / 3 : layer;
                const std::size_t x = p % kWidth, y = p / kWidth;
                frame[p * channels + c] =
                    0.01f * (1 + l * 4) * (1.0f + float((x * 3 + y + c) % 11)) * (1.0f + 0.1f * float(t % 3));
            }
        frames.push_back(frame);
    }
    return frames;
}

} // namespace

TEST_CASE("layer runs: a layer's whitening weights are those of the layer alone, not a slice of all layers'")
{
    MemoryShot both = shot_of(-1, 0.1f);
    both.layer_variance = {{}, variance_of(1)}; // like our renders: DiffInd has DiffIndVar, DiffDir none
    CHECK(both.layer_variance_channels(0) == 0);
    REQUIRE(both.layer_variance_channels(1) == 3);
    MemoryShot alone = shot_of(1, 0.1f);
    alone.variance = variance_of(1);
    const WhiteningWeights layer = layer_whitening_weights(both, 1, 3);
    const WhiteningWeights single = whitening_weights(alone);
    CHECK(layer.weights == single.weights);
    CHECK(layer.mean_variance == single.mean_variance);
    CHECK(layer.floor == single.floor);
    CHECK(layer.floored_samples == single.floored_samples);

    // Weights of both layers' variance together are normalised over both: their slice is not the layer's.
    MemoryShot whole = shot_of(-1, 0.1f);
    whole.variance = variance_of(-1);
    const std::vector<float> slice = layer_of({whitening_weights(whole).weights}, 3).front();
    REQUIRE(slice.size() == single.weights.size());
    CHECK(slice != single.weights);
}

TEST_CASE("layer runs: whitened per layer, each layer gets the bits of a run of it alone, kept and streamed")
{
    MemoryShot both = shot_of(-1, 0.1f);
    both.layer_variance = {{}, variance_of(1)};
    const WhiteningWeights weights = layer_whitening_weights(both, 1, 3);
    for (bool kept : {true, false}) {
        CAPTURE(kept);
        Settings settings;
        settings.mode_filter.enabled = true;
        settings.estimators.input = settings.estimators.spatial = true;
        if (!kept)
            settings.max_memory_bytes = streaming_budget(both, settings);
        Settings layers = layered(settings);
        layers.layer_whitening = {nullptr, &weights.weights};
        MemorySink sink(both.size);
        MemoryShot input = both;
        const Report report = run_denoise(input, sink, layers, Progress::silent());
        CHECK(report.plan.in_memory == kept);
        REQUIRE(report.layers.size() == 2);
        for (int layer : {0, 1}) {
            CAPTURE(layer);
            MemoryShot alone = shot_of(layer, 0.1f);
            Settings alone_settings = settings;
            std::optional<WhiteningWeights> alone_weights;
            if (layer == 1) {
                alone.variance = variance_of(1);
                alone_weights = whitening_weights(alone);
                alone_settings.whitening = &alone_weights->weights;
            }
            MemorySink alone_sink(alone.size);
            run_denoise(alone, alone_sink, alone_settings, Progress::silent());
            CHECK(layer_of(sink.rebuilt, 3 * layer) == alone_sink.rebuilt);
            CHECK(layer_of(sink.sigma, 3 * layer) == alone_sink.sigma);
            if (layer == 1) { // the weights changed something: unwhitened B is another result
                MemorySink plain(alone.size);
                run_denoise(alone, plain, settings, Progress::silent());
                CHECK(plain.rebuilt != alone_sink.rebuilt);
            }
        }
    }
}

TEST_CASE("layer runs: weights of every channel together are refused, they would not be any layer's")
{
    MemoryShot both = shot_of(-1, 0.1f);
    both.variance = variance_of(-1);
    const WhiteningWeights weights = whitening_weights(both);
    MemorySink sink(both.size);
    Settings settings;
    settings.layer_channels = {3, 3};
    settings.whitening = &weights.weights;
    CHECK_THROWS_AS(run_denoise(both, sink, settings, Progress::silent()), Error);
    settings.whitening = nullptr;
    settings.layer_whitening = {&weights.weights}; // one layer's worth for two layers
    CHECK_THROWS_AS(run_denoise(both, sink, settings, Progress::silent()), Error);
}

TEST_CASE("layer runs: each layer gets the bits of a run of it alone, kept and streamed, gram and rsvd, "
          "filtered or not")
{
    const MemoryShot both = shot_of(-1, 0.1f);
    for (bool filter : {true, false})
        for (Solver solver : {Solver::Gram, Solver::RandomizedSvd})
            for (bool kept : {true, false}) {
                const std::string solver_used = solver_name(solver);
                CAPTURE(filter);
                CAPTURE(solver_used);
                CAPTURE(kept);
                Settings settings;
                settings.solver = solver;
                settings.mode_filter.enabled = filter; // and the estimator choice with it
                settings.estimators.input = settings.estimators.spatial = filter;
                if (!kept)
                    settings.max_memory_bytes = streaming_budget(both, settings);
                MemorySink sink(both.size);
                MemoryShot input = both;
                const Report report = run_denoise(input, sink, layered(settings), Progress::silent());
                CHECK(report.plan.in_memory == kept);
                REQUIRE(report.layers.size() == 2);
                CHECK(report.shape.channels == 6);
                for (int layer : {0, 1}) {
                    CAPTURE(layer);
                    MemoryShot alone = shot_of(layer, 0.1f);
                    MemorySink alone_sink(alone.size);
                    const Report alone_report = run_denoise(alone, alone_sink, settings, Progress::silent());
                    CHECK(report.layers[layer].rank_decision.kept_modes ==
                          alone_report.rank_decision.kept_modes);
                    CHECK(layer_of(sink.rebuilt, 3 * layer) == alone_sink.rebuilt);
                    CHECK(layer_of(sink.sigma, 3 * layer) == alone_sink.sigma);
                }
            }
}

TEST_CASE("layer runs: the shot is decoded once per pass for all layers, not once per layer")
{
    MemoryShot both = shot_of(-1, 0.1f);
    for (bool kept : {true, false}) {
        CAPTURE(kept);
        Settings settings; // the mode filter and the estimator choice read the most
        settings.mode_filter.enabled = true;
        settings.estimators.input = settings.estimators.spatial = true;
        if (!kept)
            settings.max_memory_bytes = streaming_budget(both, settings);
        CountingShot counted(both);
        MemorySink sink(both.size);
        const Report report = run_denoise(counted, sink, layered(settings), Progress::silent());
        CHECK(report.plan.in_memory == kept);
        const int bands = (kHeight + report.plan.band_rows - 1) / report.plan.band_rows;
        // The look for noise that repeats reads a few frames once for all layers, in its own bands.
        const std::size_t looked = report.layers.at(0).repeating_noise.frames.size();
        CHECK(looked == 9);
        CHECK(report.layers.at(1).repeating_noise.frames.size() == looked);
        const std::int64_t reads =
            counted.reads -
            std::int64_t(looked) * ((kHeight + kRepeatingNoiseBandRows - 1) / kRepeatingNoiseBandRows);
        if (kept) {
            CHECK(report.passes == 1);
            // Every frame whole once, then the input rows the choice reads of each band once,
            // as a run of one layer does.
            CHECK(reads == std::int64_t(kFrames) * (1 + bands));
        } else {
            CHECK(bands > 1);
            CHECK(report.passes == 3); // statistics, survey, rebuild
            // At most one decode of each band of each frame per pass (fewer where a
            // band's rows lie in the last one's); one per layer would be twice that.
            CHECK(reads <= std::int64_t(report.passes) * bands * kFrames);
            CHECK(reads > std::int64_t(report.passes - 1) * bands * kFrames);
        }
    }
}

TEST_CASE("layer runs: a layer lit unlike the other keeps less noise on its own modes than on shared ones")
{
    const MemoryShot clean = shot_of(-1, 0.0f);
    const MemoryShot noisy = shot_of(-1, 0.2f);
    Settings settings;
    settings.outliers.fireflies = false; // Gaussian noise has no fireflies to treat
    MemoryShot joint_input = noisy, separate_input = noisy;
    MemorySink joint(noisy.size), separate(noisy.size);
    const Report joint_report = run_denoise(joint_input, joint, settings, Progress::silent());
    const Report separate_report =
        run_denoise(separate_input, separate, layered(settings), Progress::silent());
    REQUIRE(separate_report.layers.size() == 2);
    CHECK(separate_report.layers[0].rank_decision.kept_modes < joint_report.rank_decision.kept_modes);
    const double joint_error = mean_square(layer_of(joint.rebuilt, 0), layer_of(clean.frames, 0));
    const double separate_error = mean_square(layer_of(separate.rebuilt, 0), layer_of(clean.frames, 0));
    CHECK(separate_error < 0.6 * joint_error);
}

TEST_CASE("layer runs: channel counts that do not add up to the shot's are an internal error")
{
    MemoryShot both = shot_of(-1, 0.0f);
    MemorySink sink(both.size);
    Settings settings;
    settings.layer_channels = {3, 2};
    CHECK_THROWS_AS(run_denoise(both, sink, settings, Progress::silent()), Error);
}
