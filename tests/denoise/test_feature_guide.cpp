// The feature guide of the mode filter (core/denoise/feature_guide.h and the
// feature candidates of mode_filter.h): the scale of a feature is its RMS
// neighbour difference, exactly; a constant feature is dropped; features guide
// every mode, the first included, and keep an edge that the first mode is too
// noisy to keep; SURE does not pick a guide made of noise; the engine with
// features gives the same bits streamed, kept and on 1 or 2 threads, and a lower
// error than without them.
#include "core/denoise/engine.h"
#include "core/denoise/feature_guide.h"
#include "core/denoise/mode_filter.h"
#include "tests/denoise/memory_shot.h"

#include <doctest/doctest.h>
#include <tbb/task_arena.h>

#include <cmath>
#include <random>
#include <vector>

using namespace modestack;
using namespace modestack::denoise;
using namespace modestack::denoise::testing;

namespace {

// A shot of a step edge at x = edge in every mode's spatial pattern, lit by two
// temporal modes, plus Gaussian noise; the albedo (one value per channel) has the
// same step, the normal is constant (no information: dropped).
MemoryShot edge_shot(int width, int height, int frames, int edge, double noise, unsigned seed)
{
    MemoryShot shot;
    shot.size = {frames, width, height, 3};
    shot.albedo.channels = 3;
    shot.normal.channels = 3;
    std::mt19937 generator(seed);
    std::normal_distribution<double> normal(0.0, noise);
    for (int t = 0; t < frames; ++t) {
        const double phase = 6.283185307 * t / frames;
        std::vector<float> frame, albedo, normal_frame;
        for (int y = 0; y < height; ++y)
            for (int x = 0; x < width; ++x) {
                const double reflectance = x < edge ? 0.2 : 0.8;
                for (int c = 0; c < 3; ++c) {
                    const double light = 1.0 + 0.5 * std::sin(phase) * std::cos(3.14159 * y / height);
                    frame.push_back(static_cast<float>(reflectance * light + normal(generator)));
                    albedo.push_back(static_cast<float>(reflectance));
                    normal_frame.push_back(c == 1 ? 1.0f : 0.0f);
                }
            }
        shot.frames.push_back(frame);
        shot.albedo.frames.push_back(albedo);
        shot.normal.frames.push_back(normal_frame);
    }
    return shot;
}

MemoryShot clean_edge_shot(int width, int height, int frames, int edge)
{
    return edge_shot(width, height, frames, edge, 0.0, 1);
}

}  // namespace

TEST_CASE("feature guide: the scale is the RMS neighbour difference, a constant feature is dropped")
{
    MemoryShot shot;
    const int width = 10, height = 6;
    shot.size = {3, width, height, 3};
    shot.frames.assign(3, std::vector<float>(width * height * 3, 1.0f));
    shot.depth.channels = 1;
    shot.normal.channels = 3;
    for (int t = 0; t < 3; ++t) {
        std::vector<float> depth;
        for (int y = 0; y < height; ++y)
            for (int x = 0; x < width; ++x)
                depth.push_back(std::exp(0.5f * x));  // log depth: a ramp of 0.5 per pixel in x
        shot.depth.frames.push_back(depth);
        shot.normal.frames.push_back(std::vector<float>(width * height * 3, 0.5f));
    }
    FeatureGuide guide(shot, FeatureGuideOptions{}, Progress::silent());
    REQUIRE(guide.channels() == 1);  // the normal is constant
    REQUIRE(guide.summary().features == std::vector<std::string>{"depth"});
    // Horizontal pairs differ by 0.5, vertical ones by 0: RMS over all pairs.
    const double horizontal = (width - 1.0) * height, vertical = width * (height - 1.0);
    CHECK(guide.summary().scales[0] == doctest::Approx(0.5 * std::sqrt(horizontal / (horizontal + vertical))));
    CHECK(guide.summary().frames == std::vector<int>{0, 1, 2});
    std::vector<float> rows;
    guide.read_rows(2, 4, rows);
    REQUIRE(rows.size() == 2u * width);
    // Normalised: neighbours in x differ by 0.5 / scale.
    CHECK(rows[1] - rows[0] == doctest::Approx(0.5 / guide.summary().scales[0]).epsilon(1e-4));
}

TEST_CASE("feature guide: features keep an edge the first mode is too noisy to keep, in every mode")
{
    const int width = 64, height = 40, edge = 32;
    // Two coefficient images with a step at the edge, both weak against the noise
    // (so c_1 is a poor guide), and a clean one-channel feature with the same step.
    const double noise = 0.4;
    std::mt19937 generator(3);
    std::normal_distribution<double> normal(0.0, noise);
    const std::int64_t pixels = std::int64_t(width) * height;
    std::vector<float> clean, noisy, feature;
    for (int j = 0; j < 2; ++j)
        for (int y = 0; y < height; ++y)
            for (int x = 0; x < width; ++x) {
                const double value = (j == 0 ? 1.0 : 0.6) * (x < edge ? 1.0 : 2.0);
                clean.push_back(static_cast<float>(value));
                noisy.push_back(static_cast<float>(value + normal(generator)));
            }
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x)
            feature.push_back(x < edge ? 0.0f : 5.0f);  // far above its scale: an edge
    std::vector<float> variance(static_cast<std::size_t>(pixels), static_cast<float>(noise * noise));
    lowrank::ImageBandShape shape{width, height, 1};
    lowrank::BandView view{noisy.data(), pixels, 2, pixels};

    ModeFilterOptions options;
    options.widths = {2.0};
    options.feature_channels = 1;
    SureSurvey survey(options, width, height, 1, 2);
    survey.add_band(view, variance, shape, 0, 0, height, feature.data());
    ModeFilterPlan plan = survey.finish(2);
    // identity, Gaussian, c_1-guided, then feature 0.25 (alone, with c_1), feature 1 (alone, with c_1)
    REQUIRE(plan.candidates.size() == 7);
    CHECK(plan.modes[0].feature_range > 0);  // the first mode too
    CHECK(plan.modes[0].range == 0);         // never guided by itself
    CHECK(plan.modes[1].feature_range > 0);

    auto errors = [&](int forced_candidate) {
        ModeFilterPlan forced = plan;
        if (forced_candidate >= 0)
            for (ModeFilterChoice& choice : forced.modes)
                choice.candidate = forced_candidate;
        std::vector<float> filtered(static_cast<std::size_t>(pixels) * 2), gains;
        filter_coefficients(view, variance, shape, 0, height, forced, 2, {filtered.data(), pixels, 2, pixels}, gains,
                            feature.data());
        double edge_error = 0, total = 0;
        for (std::int64_t i = 0; i < 2 * pixels; ++i) {
            const double squared = (double(filtered[i]) - clean[i]) * (double(filtered[i]) - clean[i]);
            total += squared;
            if (std::abs(static_cast<int>(i % width) - edge) <= 3)
                edge_error += squared;
        }
        return std::make_pair(edge_error, total);
    };
    auto [gaussian_edge, gaussian_total] = errors(1);
    auto [chosen_edge, chosen_total] = errors(-1);
    CHECK(chosen_edge < 0.25 * gaussian_edge);
    CHECK(chosen_total < 0.6 * gaussian_total);
    // The chosen filter still removes most of the noise (Σ v over both modes).
    CHECK(chosen_total < 0.3 * 2 * pixels * noise * noise);
}

TEST_CASE("feature guide: SURE does not pick a feature made of noise")
{
    const int width = 80, height = 60;
    const std::int64_t pixels = std::int64_t(width) * height;
    const double noise = 0.5;
    std::mt19937 generator(11);
    std::normal_distribution<double> normal(0.0, 1.0);
    std::vector<float> noisy, feature;
    for (int j = 0; j < 3; ++j)
        for (int y = 0; y < height; ++y)
            for (int x = 0; x < width; ++x)
                noisy.push_back(static_cast<float>((3.0 - j) * (1.0 + 0.5 * std::sin(0.08 * x) * std::cos(0.06 * y)) +
                                                   noise * normal(generator)));
    for (std::int64_t p = 0; p < pixels * 2; ++p)  // two channels unrelated to the signal
        feature.push_back(static_cast<float>(normal(generator)));
    std::vector<float> variance(static_cast<std::size_t>(pixels), static_cast<float>(noise * noise));
    ModeFilterOptions options;
    options.feature_channels = 2;
    SureSurvey survey(options, width, height, 1, 3);
    survey.add_band({noisy.data(), pixels, 3, pixels}, variance, {width, height, 1}, 0, 0, height, feature.data());
    ModeFilterPlan plan = survey.finish(3);
    for (const ModeFilterChoice& choice : plan.modes) {
        CHECK(choice.width > 0);
        CHECK(choice.feature_range == 0);
    }
}

TEST_CASE("feature guide: the engine with features gives the same bits streamed, kept, on 1 and 2 threads, and a lower error")
{
    const int width = 48, height = 160, frames = 12, edge = 20;
    MemoryShot shot = edge_shot(width, height, frames, edge, 0.3, 5);
    MemoryShot clean = clean_edge_shot(width, height, frames, edge);
    auto run = [&](std::int64_t memory, int threads, bool features) {
        MemorySink sink(shot.size);
        Settings settings;
        settings.max_memory_bytes = memory;
        settings.mode_filter.enabled = true;
        if (!features)
            settings.feature_guide.kinds.clear();
        Report report;
        tbb::task_arena arena(threads);
        arena.execute([&] { report = run_denoise(shot, sink, settings, Progress::silent()); });
        return std::make_pair(report, sink);
    };
    const std::int64_t whole = std::int64_t(1) << 30, bands = 2'300'000;
    auto [kept_report, kept] = run(whole, 2, true);
    auto [streamed_report, streamed] = run(bands, 2, true);
    auto [single_report, single] = run(bands, 1, true);
    auto [plain_report, plain] = run(whole, 2, false);
    CHECK(kept_report.plan.in_memory);
    CHECK_FALSE(streamed_report.plan.in_memory);
    CHECK(streamed_report.plan.band_rows < height);
    CHECK(kept_report.feature_guide.features == std::vector<std::string>{"albedo"});
    CHECK(kept.rebuilt == streamed.rebuilt);
    CHECK(kept.sigma == streamed.sigma);
    CHECK(streamed.rebuilt == single.rebuilt);
    CHECK(streamed.sigma == single.sigma);
    CHECK(plain_report.feature_guide.features.empty());
    bool guided = false;
    for (const ModeFilterChoice& choice : kept_report.mode_filter.modes)
        guided = guided || (choice.kept && choice.feature_range > 0);
    CHECK(guided);
    const double with_features = mean_square(kept.rebuilt, clean.frames);
    const double without = mean_square(plain.rebuilt, clean.frames);
    MESSAGE("mean squared error with features ", with_features, ", without ", without);
    CHECK(with_features < 0.9 * without);
}
