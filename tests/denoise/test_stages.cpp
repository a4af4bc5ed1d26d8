// The farm tasks of the engine (farm_tasks.h): statistics tasks over bands of
// rows, a solve task, survey and modes tasks over other bands of rows and write tasks over
// some frames each give the same bits as one whole run, with and without the
// mode filter, whitening and shrinkage, kept and streamed; bad row ranges are
// refused.
#include "core/common/error.h"
#include "core/denoise/engine.h"
#include "core/denoise/estimator_choice.h"
#include "core/denoise/farm_tasks.h"
#include "core/denoise/whitening.h"
#include "tests/denoise/memory_shot.h"

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <utility>
#include <vector>

using namespace modestack;
using namespace modestack::denoise;
using namespace modestack::denoise::testing;

namespace {

// A noisy rank-2 shot with a few fireflies and a NaN, 150 rows: blocks 0-63,
// 64-127 and a short last one 128-149. With `variance`, a variance layer that
// grows to the right (for whitening).
MemoryShot noisy_shot(bool variance)
{
    const int width = 24, height = 150, frames = 9;
    MemoryShot shot;
    shot.size = {frames, width, height, 3};
    std::mt19937 generator(11);
    std::normal_distribution<float> normal(0.0f, 0.2f);
    for (int t = 0; t < frames; ++t) {
        std::vector<float> frame(std::size_t(width) * height * 3), noise_variance(frame.size());
        for (int y = 0; y < height; ++y)
            for (int x = 0; x < width; ++x)
                for (int c = 0; c < 3; ++c) {
                    const std::size_t i = (std::size_t(y) * width + x) * 3 + c;
                    const float scale = 0.5f + float(x) / width;
                    frame[i] = 1.0f + 0.4f * std::sin(0.2f * y + c) * std::cos(0.7f * t) +
                               0.3f * (x > width / 2) * t / frames + scale * normal(generator);
                    noise_variance[i] = 0.04f * scale * scale;
                }
        if (t == 3)
            frame[(std::size_t(70) * width + 5) * 3] = 400.0f;  // a firefly
        if (t == 5)
            frame[(std::size_t(140) * width + 9) * 3 + 1] = NAN;
        shot.frames.push_back(frame);
        if (variance)
            shot.variance.push_back(noise_variance);
    }
    return shot;
}

struct Result {
    Report report;
    MemorySink sink;
};

Result run(MemoryShot& shot, const Settings& settings)
{
    Result result{{}, MemorySink(shot.size)};
    result.report = run_denoise(shot, result.sink, settings, Progress::silent());
    return result;
}

// A task's context over `shot`, its outputs going to `sink`.
PassContext context_of(MemoryShot& shot, MemorySink& sink, const Settings& settings)
{
    return {shot, sink, settings, Progress::silent()};
}

// A source that counts the frames read, to check that a write task reads only its own.
struct CountingSource : ForwardingSource {
    explicit CountingSource(FrameSource& inner) : ForwardingSource(inner) {}
    std::vector<int> reads = std::vector<int>(64, 0);
    void read_rows(int frame, int row_begin, int row_end, float* destination,
                   PassThroughRows* pass_through) override
    {
        ++reads[std::size_t(frame)];
        ForwardingSource::read_rows(frame, row_begin, row_end, destination, pass_through);
    }
};

// stats over `bands` → solve → survey → modes over `mode_bands` → write tasks over two
// halves of the frames, as a farm would, the task data passed on as the files
// would pass it. The result is the two write tasks' frames together.
Result run_staged(MemoryShot& shot, const Settings& settings, const std::vector<std::pair<int, int>>& bands,
                  const std::vector<std::pair<int, int>>& mode_bands = {{0, 37}, {37, 150}})
{
    MemorySink unused(shot.size);
    const PassContext context = context_of(shot, unused, settings);
    // The statistics tasks' blocks, joined in row order as the solve file reader joins them.
    std::vector<Statistics> tasks;
    for (auto [begin, end] : bands)
        tasks.push_back(statistics_task(context, begin, end).output);
    std::sort(tasks.begin(), tasks.end(),
              [](const Statistics& a, const Statistics& b) { return a.row_begin < b.row_begin; });
    Statistics shot_statistics{0, shot.size.height, {}, {}, {}, {}};
    for (Statistics& task : tasks) {
        for (auto& block : task.blocks)
            shot_statistics.blocks.push_back(std::move(block));
        shot_statistics.roughness.insert(shot_statistics.roughness.end(), task.roughness.begin(),
                                         task.roughness.end());
        shot_statistics.cleaned_roughness.insert(shot_statistics.cleaned_roughness.end(),
                                                 task.cleaned_roughness.begin(),
                                                 task.cleaned_roughness.end());
        shot_statistics.outliers.non_finite += task.outliers.non_finite;
        shot_statistics.outliers.fireflies += task.outliers.fireflies;
    }
    const SolvedSums solved = solve_task(context, shot_statistics).output;
    for (const auto& frame : unused.rebuilt)
        for (float value : frame)
            REQUIRE(value == 0.0f);  // no task before the write writes frames
    // Survey tasks over yet other bands, their row sums joined in row order.
    SurveyRows survey{0, shot.size.height, {}};
    for (auto [begin, end] : {std::pair{0, 50}, std::pair{50, 150}}) {
        const SurveyRows rows = survey_task(context, solved, begin, end).output;
        CHECK(rows.sums.size() == (settings.mode_filter.enabled ? std::size_t(end - begin) : 0));
        survey.sums.insert(survey.sums.end(), rows.sums.begin(), rows.sums.end());
    }
    std::vector<ModeImages> modes;
    for (auto [begin, end] : mode_bands) {
        modes.push_back(modes_task(context, solved, survey, begin, end).output);
        CHECK(modes.back().row_begin == begin);
    }
    for (const auto& frame : unused.rebuilt)
        for (float value : frame)
            REQUIRE(value == 0.0f);
    std::sort(modes.begin(), modes.end(),
              [](const ModeImages& a, const ModeImages& b) { return a.row_begin < b.row_begin; });
    Result joined{{}, MemorySink(shot.size)};
    const int frames = shot.size.frames, half = frames / 2;
    for (auto [first, last] : {std::pair{0, half}, std::pair{half, frames}}) {
        MemorySink sink(shot.size);
        sink.written.assign(std::size_t(frames), false);
        std::fill(sink.written.begin() + first, sink.written.begin() + last, true);
        CountingSource source(shot);
        joined.report = write_task({source, sink, settings, Progress::silent()}, solved, survey, modes);

        // Its own frames and, for the choice's spread, those within its reach, each once.
        const int reach = estimator_frame_reach(settings.estimators);
        for (int t = 0; t < frames; ++t) {
            CAPTURE(t);
            CHECK(source.reads[std::size_t(t)] == (t >= first - reach && t < last + reach ? 1 : 0));
            if (t >= first && t < last) {
                joined.sink.rebuilt[std::size_t(t)] = sink.rebuilt[std::size_t(t)];
                joined.sink.sigma[std::size_t(t)] = sink.sigma[std::size_t(t)];
            }
        }
    }
    return joined;
}

// Returns whether the whole run kept the shot in memory.
bool check_same_bits(MemoryShot& shot, const Settings& settings)
{
    Result whole = run(shot, settings);
    Result staged = run_staged(shot, settings, {{0, 64}, {64, 150}});
    Result three = run_staged(shot, settings, {{128, 150}, {0, 64}, {64, 128}});
    CHECK(whole.report.outliers.fireflies > 0);
    CHECK(whole.report.outliers.non_finite == 1);
    CHECK(staged.report.outliers.fireflies == whole.report.outliers.fireflies);
    CHECK(staged.report.outliers.non_finite == 1);
    CHECK(staged.report.rank_decision.kept_modes == whole.report.rank_decision.kept_modes);
    CHECK(staged.sink.rebuilt == whole.sink.rebuilt);
    CHECK(staged.sink.sigma == whole.sink.sigma);
    CHECK(three.sink.rebuilt == whole.sink.rebuilt);
    CHECK(three.sink.sigma == whole.sink.sigma);
    return whole.report.plan.in_memory;
}

}  // namespace

TEST_CASE("stages: stats, solve, survey, modes and write tasks over other bands and frames give the bits of one run, mode filter on and off")
{
    MemoryShot shot = noisy_shot(false);
    std::vector<bool> kept;
    for (bool filter : {true, false})
        for (std::int64_t memory : {std::int64_t(1) << 30, std::int64_t(950'000)}) {
            CAPTURE(filter);
            CAPTURE(memory);
            Settings settings;
            settings.mode_filter.enabled = filter;
            settings.max_memory_bytes = memory;
            kept.push_back(check_same_bits(shot, settings));
        }
    // With the mode filter's halo, the small budget streams the shot in bands of 16 rows.
    CHECK(kept == std::vector<bool>{true, false, true, true});
}

TEST_CASE("stages: optimal shrinkage and clamped non-negative outputs, staged, give the bits of one run")
{
    MemoryShot shot = noisy_shot(false);
    Settings settings;
    settings.mode_filter.enabled = false;
    settings.optimal_shrinkage = true;
    settings.rank_rule.rule = lowrank::RankRule::Fixed;
    settings.rank_rule.fixed_modes = 4;
    settings.non_negative = NonNegativeMode::Clamp;
    check_same_bits(shot, settings);
}

TEST_CASE("stages: with whitening weights the staged run still gives the bits of one run")
{
    MemoryShot shot = noisy_shot(true);
    const WhiteningWeights weights = whitening_weights(shot);
    Settings settings;
    settings.mode_filter.enabled = true;
    settings.whitening = &weights.weights;
    check_same_bits(shot, settings);
}

TEST_CASE("stages: with the estimator choice the staged run still gives the bits of one run, mode filter on "
          "and off")
{
    // With the mode filter, sigma counts each mode's noise scale and the choice
    // the gains alone (band_rebuild.h, KeptNoise): the write tasks must hand
    // each its own.
    MemoryShot shot = noisy_shot(false);
    for (bool filter : {false, true})
        for (std::int64_t memory : {std::int64_t(1) << 30, std::int64_t(1'900'000)}) {
            CAPTURE(filter);
            CAPTURE(memory);
            Settings settings;
            settings.mode_filter.enabled = filter;
            settings.estimators = parse_estimators("rebuild,input,spatial,nlmeans");
            settings.max_memory_bytes = memory;
            check_same_bits(shot, settings);
        }
}

TEST_CASE("stages: with the estimator choice and --non-negative, and a patch the rebuild misses in the last "
          "frames, the staged run still gives the bits of one run")
{
    // The choice's misfit test reads the frames around each written one and
    // their rebuilds, made non-negative (temporal_misfit.h): a write task makes
    // them from the kept coefficients, a whole run has them in its bands.
    MemoryShot shot = noisy_shot(false);
    for (int t = 5; t < shot.size.frames; ++t)
        for (int y = 40; y < 42; ++y)
            for (int x = 3; x < 6; ++x)
                for (int c = 0; c < 3; ++c)
                    shot.frames[static_cast<size_t>(t)][(std::size_t(y) * shot.size.width + x) * 3 + c] +=
                        2.0f;
    shot.frames[6][(std::size_t(41) * shot.size.width + 6) * 3] = 300.0f; // a firefly beside it
    for (bool filter : {false, true}) {
        CAPTURE(filter);
        Settings settings;
        settings.mode_filter.enabled = filter;
        settings.non_negative = NonNegativeMode::Clamp;
        settings.estimators = parse_estimators("rebuild,input,spatial");
        check_same_bits(shot, settings);
    }
}

TEST_CASE("stages: a statistics task must cover whole blocks of rows, a modes task rows of the shot, and rsvd and keep-sum are refused")
{
    MemoryShot shot = noisy_shot(false);
    Settings settings;
    MemorySink sink(shot.size);
    CHECK_THROWS_WITH_AS(statistics_task(context_of(shot, sink, settings), 10, 64),
                         doctest::Contains("whole blocks of 64 rows"), Error);
    CHECK_THROWS_WITH_AS(statistics_task(context_of(shot, sink, settings), 0, 100), doctest::Contains("whole blocks"),
                         Error);
    Statistics last;
    CHECK_NOTHROW(last = statistics_task(context_of(shot, sink, settings), 128, 150).output);
    CHECK(last.blocks.size() == 1);
    const SolvedSums empty{lowrank::GramAccumulator(shot.size.frames), {}, {}, {}, {}};
    CHECK_THROWS_WITH_AS(modes_task(context_of(shot, sink, settings), empty, {}, 100, 151),
                         doctest::Contains("rows 0-149"), Error);
    settings.non_negative = NonNegativeMode::KeepSum;
    CHECK_THROWS_WITH_AS(write_task(context_of(shot, sink, settings), empty, {}, {}), doctest::Contains("keep-sum"),
                         Error);
    settings.non_negative = NonNegativeMode::Off;
    settings.solver = Solver::RandomizedSvd;
    CHECK_THROWS_WITH_AS(statistics_task(context_of(shot, sink, settings), 0, 64), doctest::Contains("--method rsvd"),
                         Error);
}
