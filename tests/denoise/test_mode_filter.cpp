// The mode filter (core/denoise/mode_filter.h): SURE picks no filter on noise-free
// data and a real width on noisy smooth data, and its estimate matches the true
// error; a lit mode's hard edges do not pass for noise in its noise scale; the
// guided filter keeps a step edge sharper than a plain Gaussian; with
// filtering the engine keeps a weak but real mode that press drops, and lowers the
// error; sigma stays calibrated; streamed, kept, 1- and 2-thread runs give the same bits.
#include "core/denoise/engine.h"
#include "core/denoise/mode_filter.h"
#include "tests/denoise/memory_shot.h"

#include <doctest/doctest.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

using namespace modestack;
using namespace modestack::denoise;
using namespace modestack::denoise::testing;

namespace {

// Coefficient images of `modes` modes, one channel, [mode][y][x], with their noise.
struct Images {
    int width, height, modes;
    std::vector<float> clean, noisy, variance;
    lowrank::ImageBandShape shape() const { return {width, height, 1}; }
    lowrank::BandView view() const { return {noisy.data(), std::int64_t(width) * height, modes, std::int64_t(width) * height}; }
};

template <typename Pattern> Images make_images(int width, int height, int modes, double noise, Pattern pattern)
{
    Images images{width, height, modes, {}, {}, {}};
    std::mt19937 generator(7);
    std::normal_distribution<double> normal(0.0, 1.0);
    for (int j = 0; j < modes; ++j)
        for (int y = 0; y < height; ++y)
            for (int x = 0; x < width; ++x) {
                double value = pattern(j, x, y);
                images.clean.push_back(static_cast<float>(value));
                images.noisy.push_back(static_cast<float>(value + noise * normal(generator)));
            }
    images.variance.assign(std::size_t(width) * height, static_cast<float>(noise * noise));
    return images;
}

// Filters all rows of `images` with `plan` and returns ‖A c − s‖² of mode j.
double true_error(const Images& images, const ModeFilterPlan& plan, int j)
{
    std::int64_t rows = std::int64_t(images.width) * images.height;
    std::vector<float> filtered(static_cast<std::size_t>(rows) * images.modes), gains;
    filter_coefficients(images.view(), images.variance, images.shape(), 0, images.height, plan, images.modes,
                        {filtered.data(), rows, images.modes, rows}, gains);
    double error = 0;
    for (std::int64_t i = j * rows; i < (j + 1) * rows; ++i)
        error += (double(filtered[i]) - images.clean[i]) * (double(filtered[i]) - images.clean[i]);
    return error;
}

ModeFilterPlan survey(const Images& images, const ModeFilterOptions& options, int fixed_modes = 0)
{
    SureSurvey survey(options, images.width, images.height, 1, images.modes);
    survey.add_band(images.view(), images.variance, images.shape(), 0, 0, images.height);
    return survey.finish(fixed_modes);
}

// A shot of `frames` frames: a bright mode with an edge, a weak smooth mode with
// `weak` amplitude per frame, and Gaussian noise.
MemoryShot two_mode_shot(int width, int height, int frames, double weak, double noise, unsigned seed)
{
    MemoryShot shot;
    shot.size = {frames, width, height, 3};
    std::mt19937 generator(seed);
    std::normal_distribution<double> normal(0.0, noise);
    for (int t = 0; t < frames; ++t) {
        double phase = 6.283185307 * t / frames;
        std::vector<float> frame;
        for (int y = 0; y < height; ++y)
            for (int x = 0; x < width; ++x)
                for (int c = 0; c < 3; ++c) {
                    double base = (x < width / 3 ? 1.0 : 2.0) + 0.2 * c;
                    double smooth = std::sin(6.283185307 * x / width) * std::cos(3.14159 * y / height);
                    double value = base + weak * smooth * std::sin(phase) * 1.41421356;
                    frame.push_back(static_cast<float>(value + (noise > 0 ? normal(generator) : 0.0)));
                }
        shot.frames.push_back(frame);
    }
    return shot;
}

}  // namespace

TEST_CASE("mode filter: SURE keeps every mode unfiltered when there is no noise")
{
    // Textured patterns: any blur changes them, so with v = 0 the identity wins.
    Images images = make_images(40, 30, 3, 0.0, [](int j, int x, int y) {
        return std::sin(0.9 * x + j) * std::cos(0.7 * y) + ((x * 7 + y * 3 + j) % 5) * 0.1;
    });
    ModeFilterPlan plan = survey(images, ModeFilterOptions{});
    REQUIRE(plan.modes.size() == 3);
    for (const ModeFilterChoice& choice : plan.modes) {
        CHECK(choice.width == 0);
        CHECK(choice.sure == 0);
        CHECK(choice.signal > 0);
        CHECK(choice.kept);
    }
    CHECK(plan.kept_modes == 3);
}

TEST_CASE("mode filter: on noisy smooth modes SURE picks a width and estimates the true error")
{
    const double noise = 0.5;
    Images images = make_images(96, 80, 3, noise, [](int j, int x, int y) {
        return (3.0 - j) * (1.0 + 0.5 * std::sin(0.08 * x + j) * std::cos(0.06 * y));
    });
    ModeFilterPlan plan = survey(images, ModeFilterOptions{});
    const double pixels = 96.0 * 80.0;
    for (int j = 0; j < 3; ++j) {
        CAPTURE(j);
        const ModeFilterChoice& choice = plan.modes[j];
        CHECK(choice.width >= 1.5);
        // The noise scale (high-pass energy over Σ v) finds v itself on smooth modes.
        CHECK(choice.noise_scale == doctest::Approx(1.0).epsilon(0.05));
        CHECK(choice.unfiltered_sure == doctest::Approx(pixels * noise * noise).epsilon(0.05));
        // The filter removes most of the noise: error well below Σ v.
        double error = true_error(images, plan, j);
        CHECK(error < 0.1 * pixels * noise * noise);
        // SURE is unbiased; its own spread is about √(2·pixels)·v (the noise of
        // ‖A c − c‖²), so it must lie within three of those of the true error.
        CHECK(std::abs(choice.sure - error) < 3 * std::sqrt(2 * pixels) * noise * noise);
        CHECK(choice.kept);
    }
}

TEST_CASE("mode filter: a lit mode's hard edges do not pass for noise, noise modes keep their scale")
{
    // Mode 0: blocks of 32 pixels whose levels jump by 40 noise deviations
    // (about one pixel in nine touches an edge); modes 1 to 7: noise alone.
    const double noise = 0.5;
    Images images = make_images(128, 96, 8, noise, [](int j, int x, int y) {
        return j == 0 ? 20.0 * (((x / 32) + (y / 32)) % 2) : 0.0;
    });
    // The plain ratio of high-pass energy to Σ v that the mean alone would give.
    double high_pass = 0;
    int samples = 0;
    for (int y = 1; y + 1 < images.height; ++y)
        for (int x = 1; x + 1 < images.width; ++x) {
            auto at = [&](int u, int v) { return double(images.noisy[std::size_t(v) * images.width + u]); };
            const double d = at(x, y) - (at(x - 1, y) + at(x + 1, y) + at(x, y - 1) + at(x, y + 1)) / 4;
            high_pass += d * d / 1.25, ++samples;
        }
    CHECK(high_pass / (samples * noise * noise) > 2 * kMaximumNoiseScale);

    SureSurvey sums(ModeFilterOptions{}, images.width, images.height, 1, images.modes);
    sums.add_band(images.view(), images.variance, images.shape(), 0, 0, images.height);
    const ModeFilterPlan plan = sums.finish(0);
    // Its median says how much noise it holds: about v (the median of a ninth
    // of edge pixels and the rest noise lies a little above the noise's own).
    CHECK(plan.modes[0].noise_scale >= 1.0);
    CHECK(plan.modes[0].noise_scale < 1.6);
    for (int j = 1; j < images.modes; ++j) {
        CAPTURE(j);
        CHECK(plan.modes[j].noise_scale == doctest::Approx(1.0).epsilon(0.06));
    }
    // Where noise that repeats is counted (a raised cap) the mean stands: that
    // noise gathers in the first modes with a spread of its own.
    const ModeFilterPlan repeating = sums.finish(0, 100.0);
    CHECK(repeating.modes[0].noise_scale > 2 * kMaximumNoiseScale);

    // The same edges with no noise at all in that mode: most of its ratios are
    // 0, and it gets v_p itself, the least a mode holds.
    Images clean_edges = images;
    std::copy_n(clean_edges.clean.begin(), std::size_t(clean_edges.width) * clean_edges.height,
                clean_edges.noisy.begin());
    SureSurvey clean_sums(ModeFilterOptions{}, images.width, images.height, 1, images.modes);
    clean_sums.add_band(clean_edges.view(), clean_edges.variance, clean_edges.shape(), 0, 0, images.height);
    CHECK(clean_sums.finish(0).modes[0].noise_scale == 1.0);
}

TEST_CASE("mode filter: the guided filter keeps a step edge of the guide sharper than a plain Gaussian")
{
    const int width = 64, height = 48, edge = 32;
    // Mode 1 (the guide) and mode 2 share a step at x = edge; mode 2 is weak and noisy.
    Images images = make_images(width, height, 2, 0.3, [&](int j, int x, int) {
        return (j == 0 ? 20.0 : 1.5) * (x < edge ? 1.0 : 2.0);
    });
    ModeFilterOptions options;
    options.widths = {2.0};
    options.range_scales = {2.0};
    ModeFilterPlan plan = survey(images, options);
    REQUIRE(plan.candidates.size() == 3);  // identity, Gaussian, guided
    CHECK(plan.modes[0].range == 0);       // c_1 never guides itself
    CHECK(plan.modes[1].width == 2.0);
    CHECK(plan.modes[1].range == 2.0);     // SURE prefers the guided filter

    auto edge_error = [&](int candidate) {
        ModeFilterPlan forced = plan;
        forced.modes[1].candidate = candidate;
        std::int64_t rows = std::int64_t(width) * height;
        std::vector<float> filtered(static_cast<std::size_t>(rows) * 2), gains;
        filter_coefficients(images.view(), images.variance, images.shape(), 0, height, forced, 2,
                            {filtered.data(), rows, 2, rows}, gains);
        double error = 0;
        for (int y = 0; y < height; ++y)
            for (int x = edge - 3; x < edge + 3; ++x) {
                std::int64_t i = rows + std::int64_t(y) * width + x;
                error += (double(filtered[i]) - images.clean[i]) * (double(filtered[i]) - images.clean[i]);
            }
        return error;
    };
    double gaussian = edge_error(1), guided = edge_error(2);
    CHECK(guided < 0.25 * gaussian);
}

TEST_CASE("mode filter: a plain Gaussian is the normalised window clipped at the band, with gain sum w2 over (sum w)2")
{
    // Rows 3-20 of a 40 × 24 band: the window is clipped at the left, right and
    // bottom edges and at the top for the first rows; rank 2, mode 2 unfiltered.
    const int width = 40, height = 24, valid_y0 = 3, valid_y1 = 21;
    Images images = make_images(width, height, 2, 0.5, [&](int j, int x, int y) { return j == 0 ? x * 0.1 + y : 0.0; });
    ModeFilterOptions options;
    options.widths = {1.5};
    ModeFilterPlan plan = survey(images, options, 2);
    plan.modes[0].candidate = 1, plan.modes[1].candidate = 0;
    REQUIRE(plan.candidates[1].width == 1.5);
    REQUIRE(plan.candidates[1].range == 0);
    const std::int64_t rows = std::int64_t(width) * (valid_y1 - valid_y0), pixels = std::int64_t(width) * height;
    std::vector<float> filtered(static_cast<std::size_t>(rows) * 2), gains;
    filter_coefficients(images.view(), images.variance, images.shape(), valid_y0, valid_y1, plan, 2,
                        {filtered.data(), rows, 2, rows}, gains);
    REQUIRE(gains.size() == static_cast<std::size_t>(rows) * 2);
    double largest_error = 0, largest_gain_error = 0;
    const int radius = static_cast<int>(std::ceil(2.5 * 1.5));
    for (int y = valid_y0; y < valid_y1; ++y)
        for (int x = 0; x < width; ++x) {
            double sum = 0, squares = 0, weighted = 0;
            for (int qy = std::max(0, y - radius); qy <= std::min(height - 1, y + radius); ++qy)
                for (int qx = std::max(0, x - radius); qx <= std::min(width - 1, x + radius); ++qx) {
                    const double w = std::exp(-0.5 * ((qx - x) * (qx - x) + (qy - y) * (qy - y)) / (1.5 * 1.5));
                    sum += w, squares += w * w, weighted += w * images.noisy[std::size_t(qy) * width + qx];
                }
            const std::size_t out = std::size_t(y - valid_y0) * width + x;
            largest_error = std::max(largest_error, std::abs(filtered[out] - weighted / sum));
            largest_gain_error = std::max(largest_gain_error, std::abs(gains[out] - squares / (sum * sum)));
            // Mode 2 is copied unfiltered, with gain 1.
            CHECK(filtered[std::size_t(rows) + out] == images.noisy[std::size_t(pixels) + std::size_t(y) * width + x]);
            CHECK(gains[std::size_t(rows) + out] == 1.0f);
        }
    MESSAGE("largest difference from the 2D window: " << largest_error << ", of the gain " << largest_gain_error);
    CHECK(largest_error < 1e-5);
    CHECK(largest_gain_error < 1e-6);
}

TEST_CASE("mode filter: the engine keeps a weak smooth mode that press drops, and the error falls")
{
    const int frames = 24;
    MemoryShot clean = two_mode_shot(64, 48, frames, 0.1, 0.0, 1);
    MemoryShot noisy = two_mode_shot(64, 48, frames, 0.1, 0.5, 2);
    Settings press;
    press.outliers.fireflies = false;
    MemorySink press_sink(noisy.size);
    Report press_report = run_denoise(noisy, press_sink, press, Progress::silent());
    CHECK(press_report.rank_decision.kept_modes == 1);

    Settings filtered = press;
    filtered.mode_filter.enabled = true;
    // A wide sigma window makes the confidence's bias floor (the positive part of
    // the windowed mean residual) small, so sigma² is mostly its noise term.
    filtered.sigma_radius = 8;
    MemorySink filtered_sink(noisy.size);
    Report report = run_denoise(noisy, filtered_sink, filtered, Progress::silent());
    CHECK(report.rank_decision.rule == "sure");
    CHECK(report.rank_decision.kept_modes == 2);     // the modes beyond are noise
    REQUIRE(report.mode_filter.modes.size() == 16);  // max_modes
    CHECK(report.mode_filter.modes[1].kept);
    CHECK(report.mode_filter.modes[1].width >= 1.5);
    double press_error = mean_square(press_sink.rebuilt, clean.frames);
    double filtered_error = mean_square(filtered_sink.rebuilt, clean.frames);
    CHECK(filtered_error < 0.5 * press_error);

    // Sigma stays calibrated away from the edge: mean sigma² ≈ mean squared error.
    double error = 0, variance = 0;
    for (int t = 0; t < frames; ++t)
        for (std::size_t i = 0; i < clean.frames[t].size(); ++i) {
            int x = static_cast<int>(i / 3 % 64);
            if (std::abs(x - 64 / 3) < 6)
                continue;
            double difference = double(filtered_sink.rebuilt[t][i]) - clean.frames[t][i];
            error += difference * difference;
            variance += double(filtered_sink.sigma[t][i]) * filtered_sink.sigma[t][i];
        }
    CHECK(variance / error == doctest::Approx(1.0).epsilon(0.35));
}

TEST_CASE("mode filter: streamed and kept shots, 1 and 2 threads give the same bits")
{
    MemoryShot shot = two_mode_shot(40, 160, 12, 0.3, 0.3, 5);
    auto run = [&](std::int64_t memory, int threads) {
        MemorySink sink(shot.size);
        Settings settings;
        settings.max_memory_bytes = memory;
        settings.mode_filter.enabled = true;
        Report report;
        tbb::task_arena arena(threads);
        arena.execute([&] { report = run_denoise(shot, sink, settings, Progress::silent()); });
        return std::make_pair(report, sink);
    };
    // Budgets: everything at once; the shot kept but pass 2 in windows; streamed.
    const std::int64_t whole = std::int64_t(1) << 30, windows = 2'400'000, bands = 1'800'000;
    auto [kept_report, kept] = run(whole, 2);
    auto [windowed_report, windowed] = run(windows, 2);
    auto [streamed_report, streamed] = run(bands, 2);
    auto [single_report, single] = run(bands, 1);
    CHECK(kept_report.plan.in_memory);
    CHECK(windowed_report.plan.in_memory);
    CHECK(windowed_report.plan.band_rows < 160);
    CHECK(kept.rebuilt == windowed.rebuilt);
    CHECK(kept.sigma == windowed.sigma);
    CHECK_FALSE(streamed_report.plan.in_memory);
    CHECK(streamed_report.plan.band_rows < 160);
    CHECK(streamed_report.passes == 3);
    CHECK(kept_report.rank_decision.kept_modes == streamed_report.rank_decision.kept_modes);
    CHECK(kept_report.mode_filter.modes[1].sure == streamed_report.mode_filter.modes[1].sure);
    CHECK(kept.rebuilt == streamed.rebuilt);
    CHECK(kept.sigma == streamed.sigma);
    CHECK(streamed.rebuilt == single.rebuilt);
    CHECK(streamed.sigma == single.sigma);
}
