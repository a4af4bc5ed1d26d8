// The denoise engine on in-memory shots: exact recovery of a rank-3 sequence,
// noise removal at the expected rate, bit-identical results for streamed and
// kept shots and for 1 and 2 threads, and clear errors for bad settings.
#include "core/common/error.h"
#include "core/denoise/engine.h"
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

// Rank-3 signal: three smooth spatial patterns with smooth temporal weights.
MemoryShot low_rank_shot(int width, int height, int frames, float noise, unsigned seed)
{
    MemoryShot shot;
    shot.size = {frames, width, height, 3};
    std::mt19937 generator(seed);
    std::normal_distribution<float> normal(0.0f, noise);
    for (int t = 0; t < frames; ++t) {
        float time = static_cast<float>(t) / frames;
        std::vector<float> frame(std::size_t(width) * height * 3);
        for (int y = 0; y < height; ++y)
            for (int x = 0; x < width; ++x)
                for (int c = 0; c < 3; ++c) {
                    float a = 1.0f + 0.5f * std::sin(0.3f * x + c), b = std::cos(0.2f * y) * (x < width / 2),
                          d = 0.8f * ((x + y) % 7) / 7.0f;
                    float value = a + b * std::sin(3.0f * time) + d * std::cos(9.0f * time);
                    frame[(std::size_t(y) * width + x) * 3 + c] = value + (noise > 0 ? normal(generator) : 0.0f);
                }
        shot.frames.push_back(frame);
    }
    return shot;
}

}  // namespace

TEST_CASE("engine: a rank-3 shot is recovered exactly with 3 modes")
{
    MemoryShot shot = low_rank_shot(33, 21, 16, 0.0f, 1);
    MemorySink sink(shot.size);
    Settings settings;
    settings.rank_rule.rule = lowrank::RankRule::Fixed;
    settings.rank_rule.fixed_modes = 3;
    Report report = run_denoise(shot, sink, settings, Progress::silent());
    CHECK(report.plan.in_memory);
    CHECK(report.passes == 1);
    CHECK(mean_square(sink.rebuilt, shot.frames) < 1e-10);
    CHECK(report.singular_values[3] < 1e-5 * report.singular_values[0]);
}

TEST_CASE("engine: with noise, press chooses the 3 modes and the rebuild keeps about 3/F of the noise")
{
    for (int frames : {12, 24, 48}) {
        CAPTURE(frames);
        MemoryShot clean = low_rank_shot(40, 30, frames, 0.0f, 1);
        MemoryShot noisy = low_rank_shot(40, 30, frames, 0.2f, 2);
        MemorySink sink(noisy.size);
        Settings settings;
        settings.outliers.fireflies = false;  // Gaussian noise has no fireflies to treat
        Report report = run_denoise(noisy, sink, settings, Progress::silent());
        CHECK(report.rank_decision.kept_modes == 3);
        double kept = mean_square(sink.rebuilt, clean.frames) / (0.2 * 0.2);
        CHECK(kept == doctest::Approx(3.0 / frames).epsilon(0.2));
    }
}

TEST_CASE("engine: streamed and kept shots, gram and rsvd, 1 and 2 threads give the same bits")
{
    MemoryShot shot = low_rank_shot(48, 70, 20, 0.1f, 3);
    auto run = [&](std::int64_t memory, Solver solver, int threads, bool measured_frame_noise = true) {
        MemorySink sink(shot.size);
        Settings settings;
        settings.max_memory_bytes = memory;
        settings.solver = solver;
        settings.measured_frame_noise = measured_frame_noise;
        Report report;
        tbb::task_arena arena(threads);
        arena.execute([&] { report = run_denoise(shot, sink, settings, Progress::silent()); });
        return std::make_pair(report, sink);
    };
    // Budgets for this shot (0.8 MB of input): everything at once; the shot kept
    // but pass 2 in windows of 16 rows; streamed in bands of 16 rows.
    const std::int64_t whole = std::int64_t(1) << 30, windows = 1'900'000, bands = 1'500'000;
    auto [kept_report, kept] = run(whole, Solver::Gram, 2);
    auto [windowed_report, windowed] = run(windows, Solver::Gram, 2);
    auto [streamed_report, streamed] = run(bands, Solver::Gram, 2);
    auto [single_report, single] = run(bands, Solver::Gram, 1);
    CHECK(kept_report.plan.in_memory);
    CHECK(kept_report.plan.band_rows == 70);
    CHECK(windowed_report.plan.in_memory);
    CHECK(windowed_report.plan.band_rows < 70);
    CHECK(windowed_report.passes == 1);
    CHECK_FALSE(streamed_report.plan.in_memory);
    CHECK(streamed_report.plan.band_rows < 70);
    CHECK(streamed_report.passes == 2);
    CHECK(kept.rebuilt == windowed.rebuilt);
    CHECK(kept.sigma == windowed.sigma);
    CHECK(kept.rebuilt == streamed.rebuilt);
    CHECK(kept.sigma == streamed.sigma);
    CHECK(streamed.rebuilt == single.rebuilt);
    CHECK(kept_report.outliers.fireflies == streamed_report.outliers.fireflies);

    auto [rsvd_kept_report, rsvd_kept] = run(whole, Solver::RandomizedSvd, 2);
    auto [rsvd_streamed_report, rsvd_streamed] = run(bands, Solver::RandomizedSvd, 1);
    CHECK(rsvd_kept_report.solver == "rsvd");
    CHECK(rsvd_streamed_report.passes > 2);
    CHECK(rsvd_kept.rebuilt == rsvd_streamed.rebuilt);
    // The randomized SVD fits its modes with even frame noise (frame_weighting.h),
    // as the Gram route does with --frame-noise even.
    CHECK(rsvd_kept_report.frame_scales.empty());
    CHECK(kept_report.frame_scales.size() == static_cast<size_t>(shot.size.frames));
    auto [even_report, even] = run(whole, Solver::Gram, 2, false);
    CHECK(even_report.frame_scales.empty());
    CHECK(rsvd_kept_report.rank_decision.kept_modes == even_report.rank_decision.kept_modes);
    CHECK(mean_square(rsvd_kept.rebuilt, even.rebuilt) < 1e-10);
}

TEST_CASE("engine: bad settings are usage errors before anything is written")
{
    MemoryShot two = low_rank_shot(8, 8, 2, 0.0f, 1);
    MemorySink sink(two.size);
    CHECK_THROWS_AS(run_denoise(two, sink, Settings{}, Progress::silent()), Error);
    MemoryShot shot = low_rank_shot(8, 8, 6, 0.0f, 1);
    MemorySink shot_sink(shot.size);
    Settings fixed;
    fixed.rank_rule.rule = lowrank::RankRule::Fixed;
    fixed.rank_rule.fixed_modes = 6;
    CHECK_THROWS_WITH_AS(run_denoise(shot, shot_sink, fixed, Progress::silent()), doctest::Contains("--rank 6"), Error);
    Settings tiny;
    tiny.max_memory_bytes = 1000;
    CHECK_THROWS_WITH_AS(run_denoise(shot, shot_sink, tiny, Progress::silent()), doctest::Contains("--max-memory"),
                         Error);
    for (int next : shot_sink.next_row)
        CHECK(next == 0);
}
