// The farm stages of the engine (stage_task.h): statistics tasks over bands of
// rows, a solve task, survey and modes tasks over other bands of rows and write tasks over
// some frames each give the same bits as one whole run, with and without the
// mode filter, whitening and shrinkage, kept and streamed; bad row ranges are
// refused.
#include "core/common/error.h"
#include "core/denoise/engine.h"
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

StageTask task_of(Stage stage, int row_begin = 0, int row_end = 0)
{
    StageTask task;
    task.stage = stage;
    task.row_begin = row_begin;
    task.row_end = row_end;
    return task;
}

struct Result {
    Report report;
    MemorySink sink;
};

Result run(MemoryShot& shot, Settings settings, StageTask* task)
{
    settings.stage = task;
    Result result{{}, MemorySink(shot.size)};
    result.report = run_denoise(shot, result.sink, settings, Progress::silent());
    return result;
}

// A source that counts the frames read, to check that a write task reads only its own.
struct CountingSource : ForwardingSource {
    explicit CountingSource(FrameSource& inner) : ForwardingSource(inner) {}
    std::vector<int> reads = std::vector<int>(64, 0);
    void read_rows(int frame, int row_begin, int row_end, float* destination) override
    {
        ++reads[std::size_t(frame)];
        ForwardingSource::read_rows(frame, row_begin, row_end, destination);
    }
};

// stats over `bands` → solve → survey → modes over `mode_bands` → write tasks over two
// halves of the frames, as a farm would, the task data passed on as the files
// would pass it. The result is the two write tasks' frames together.
Result run_staged(MemoryShot& shot, const Settings& settings, const std::vector<std::pair<int, int>>& bands,
                  const std::vector<std::pair<int, int>>& mode_bands = {{0, 37}, {37, 150}})
{
    StageTask solve = task_of(Stage::Solve);
    for (auto [begin, end] : bands) {
        StageTask stats = task_of(Stage::Statistics, begin, end);
        run(shot, settings, &stats);
        for (auto& block : stats.gram_blocks)
            solve.gram_blocks.push_back(std::move(block));
        solve.outliers.non_finite += stats.outliers.non_finite;
        solve.outliers.fireflies += stats.outliers.fireflies;
    }
    Result solved = run(shot, settings, &solve);
    for (const auto& frame : solved.sink.rebuilt)
        for (float value : frame)
            REQUIRE(value == 0.0f);  // the solve task writes nothing
    CHECK(solve.survey_rows.empty());  // the survey tasks' work
    // Survey tasks over yet other bands, their row sums joined in row order.
    std::vector<std::vector<double>> survey_rows;
    for (auto [begin, end] : {std::pair{0, 50}, std::pair{50, 150}}) {
        StageTask task = task_of(Stage::Survey, begin, end);
        task.gram = solve.gram;
        task.outliers = solve.outliers;
        run(shot, settings, &task);
        CHECK(task.survey_rows.size() == (settings.mode_filter.enabled ? std::size_t(end - begin) : 0));
        survey_rows.insert(survey_rows.end(), task.survey_rows.begin(), task.survey_rows.end());
    }
    std::vector<ModesBand> modes;
    for (auto [begin, end] : mode_bands) {
        StageTask task = task_of(Stage::Modes, begin, end);
        task.gram = solve.gram;
        task.outliers = solve.outliers;
        task.survey_rows = survey_rows;
        Result result = run(shot, settings, &task);
        REQUIRE(task.modes.size() == 1);
        CHECK(task.modes.front().row_begin == begin);
        modes.push_back(std::move(task.modes.front()));
    }
    std::sort(modes.begin(), modes.end(),
              [](const ModesBand& a, const ModesBand& b) { return a.row_begin < b.row_begin; });
    Result joined{{}, MemorySink(shot.size)};
    const int frames = shot.size.frames, half = frames / 2;
    for (auto [first, last] : {std::pair{0, half}, std::pair{half, frames}}) {
        StageTask write = task_of(Stage::Write);
        write.gram = solve.gram;
        write.outliers = solve.outliers;
        write.survey_rows = survey_rows;
        write.modes = modes;
        Settings task_settings = settings;
        task_settings.stage = &write;
        MemorySink sink(shot.size);
        sink.written.assign(std::size_t(frames), false);
        std::fill(sink.written.begin() + first, sink.written.begin() + last, true);
        CountingSource source(shot);
        joined.report = run_denoise(source, sink, task_settings, Progress::silent());

        for (int t = 0; t < frames; ++t) {
            CAPTURE(t);
            CHECK(source.reads[std::size_t(t)] == (t >= first && t < last ? 1 : 0));  // its own frames, once
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
    Result whole = run(shot, settings, nullptr);
    Result staged = run_staged(shot, settings, {{0, 64}, {64, 150}});
    Result three = run_staged(shot, settings, {{128, 150}, {0, 64}, {64, 128}});
    CHECK(whole.report.outliers.fireflies > 0);
    CHECK(whole.report.outliers.non_finite == 1);
    CHECK(staged.report.outliers.fireflies == whole.report.outliers.fireflies);
    CHECK(staged.report.outliers.non_finite == 1);
    CHECK(staged.report.rank.rank == whole.report.rank.rank);
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
    settings.rank.rule = lowrank::RankRule::Fixed;
    settings.rank.fixed_rank = 4;
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

TEST_CASE("stages: a statistics task must cover whole blocks of rows, a modes task rows of the shot, and rsvd and keep-sum are refused")
{
    MemoryShot shot = noisy_shot(false);
    Settings settings;
    StageTask misaligned = task_of(Stage::Statistics, 10, 64);
    CHECK_THROWS_WITH_AS(run(shot, settings, &misaligned), doctest::Contains("whole blocks of 64 rows"), Error);
    StageTask short_end = task_of(Stage::Statistics, 0, 100);
    CHECK_THROWS_WITH_AS(run(shot, settings, &short_end), doctest::Contains("whole blocks"), Error);
    StageTask last = task_of(Stage::Statistics, 128, 150);
    CHECK_NOTHROW(run(shot, settings, &last));
    CHECK(last.gram_blocks.size() == 1);
    StageTask outside = task_of(Stage::Modes, 100, 151);
    outside.gram = lowrank::GramAccumulator(shot.size.frames);
    CHECK_THROWS_WITH_AS(run(shot, settings, &outside), doctest::Contains("rows 0-149"), Error);
    settings.non_negative = NonNegativeMode::KeepSum;
    StageTask keep_sum = task_of(Stage::Write);
    keep_sum.gram = lowrank::GramAccumulator(shot.size.frames);
    CHECK_THROWS_WITH_AS(run(shot, settings, &keep_sum), doctest::Contains("keep-sum"), Error);
    settings.non_negative = NonNegativeMode::Off;
    settings.solver = Solver::RandomizedSvd;
    StageTask stats = task_of(Stage::Statistics, 0, 64);
    CHECK_THROWS_WITH_AS(run(shot, settings, &stats), doctest::Contains("--method rsvd"), Error);
}
