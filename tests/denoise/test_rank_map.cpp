// The per-pixel fractional rank (core/denoise/rank_map.h): on a shot lit by 2
// modes everywhere and a third in a patch only, denoised with N = 2, the map
// keeps 2 modes outside the patch and adds the third inside it, and the rebuild's
// error against the truth is lower than with N = 2 alone; the summary counts
// every pixel; streamed, kept, 1- and 2-thread runs give the same bits.
#include "core/denoise/engine.h"
#include "core/denoise/rank_map.h"
#include "tests/denoise/memory_shot.h"

#include <doctest/doctest.h>
#include <tbb/task_arena.h>

#include <cmath>
#include <numeric>
#include <random>
#include <vector>

using namespace modestack;
using namespace modestack::denoise;
using namespace modestack::denoise::testing;

namespace {

constexpr int kWidth = 64, kHeight = 48, kFrames = 24;

constexpr int kPatch = 40;  // the third mode lights x >= kPatch only

// Light of frame t at (x, y): 2 modes everywhere, a third in the patch. Its
// pattern is a full period across the patch and the temporal profiles full
// periods over the shot, so the modes are orthogonal: the SVD finds them
// unrotated, and the third holds nothing but noise outside the patch.
double truth(int t, int x, int y, int c)
{
    const double time = 6.283185307 * t / kFrames;
    double value = 1.0 + 0.1 * c + 0.6 * std::sin(time) * std::cos(0.15 * y);
    if (x >= kPatch)
        value += 0.5 * std::cos(2 * time) * std::cos(6.283185307 * (x - kPatch) / (kWidth - kPatch));
    return value;
}

MemoryShot shot_of(double noise, unsigned seed, int height = kHeight)
{
    MemoryShot shot;
    shot.size = {kFrames, kWidth, height, 3};
    std::mt19937 generator(seed);
    std::normal_distribution<double> normal(0.0, noise);
    for (int t = 0; t < kFrames; ++t) {
        std::vector<float> frame;
        for (int y = 0; y < height; ++y)
            for (int x = 0; x < kWidth; ++x)
                for (int c = 0; c < 3; ++c)
                    frame.push_back(static_cast<float>(truth(t, x, y, c) + (noise > 0 ? normal(generator) : 0.0)));
        shot.frames.push_back(frame);
    }
    return shot;
}

// A sink that also keeps the rank map.
struct RankSink : MemorySink {
    std::vector<float> ranks;
    int next_rank_row = 0;
    explicit RankSink(const ShotShape& shape)
        : MemorySink(shape), ranks(static_cast<std::size_t>(shape.width) * shape.height, -1.0f)
    {
    }
    void write_rank_rows(int row_begin, int row_end, const float* values) override
    {
        CHECK(row_begin == next_rank_row);
        next_rank_row = row_end;
        std::copy(values, values + (row_end - row_begin) * size.width, ranks.begin() + row_begin * size.width);
    }
};

struct Result {
    Report report;
    RankSink sink;
};

Result run(const MemoryShot& shot, bool rank_map, int fixed_modes = 0,
           std::int64_t memory = std::int64_t(1) << 30, int threads = 2)
{
    Settings settings;
    settings.mode_filter.enabled = true;
    settings.rank_map.enabled = rank_map;
    settings.max_memory_bytes = memory;
    if (fixed_modes > 0) {
        settings.rank_rule.rule = lowrank::RankRule::Fixed;
        settings.rank_rule.fixed_modes = fixed_modes;
    }
    Result result{Report{}, RankSink(shot.size)};
    MemoryShot copy = shot;
    tbb::task_arena arena(threads);
    arena.execute([&] { result.report = run_denoise(copy, result.sink, settings, Progress::silent()); });
    return result;
}

double error_against_truth(const MemorySink& sink)
{
    double sum = 0;
    std::size_t count = 0;
    for (int t = 0; t < kFrames; ++t)
        for (int y = 0; y < kHeight; ++y)
            for (int x = 0; x < kWidth; ++x)
                for (int c = 0; c < 3; ++c, ++count) {
                    const double difference =
                        sink.rebuilt[t][(std::size_t(y) * kWidth + x) * 3 + c] - truth(t, x, y, c);
                    sum += difference * difference;
                }
    return sum / count;
}

double mean_rank(const std::vector<float>& ranks, int x0, int x1)
{
    double sum = 0;
    int count = 0;
    for (int y = 0; y < kHeight; ++y)
        for (int x = x0; x < x1; ++x, ++count)
            sum += ranks[std::size_t(y) * kWidth + x];
    return sum / count;
}

}  // namespace

TEST_CASE("rank map: with N = 2 it adds the third mode where it lights the patch, and lowers the error")
{
    const MemoryShot shot = shot_of(0.3, 3);
    Result mapped = run(shot, true, 2);
    const double outside = mean_rank(mapped.sink.ranks, 0, kPatch - 4);
    // The pattern's zero crossings (x = kPatch + 6, + 18) carry no signal: look at its crests.
    const double inside = (mean_rank(mapped.sink.ranks, kPatch + 10, kPatch + 14) +
                           mean_rank(mapped.sink.ranks, kWidth - 2, kWidth)) / 2;
    MESSAGE("mean rank outside the patch " << outside << ", on its crests " << inside);
    CHECK(outside == doctest::Approx(2.0).epsilon(0.05));
    CHECK(inside > 2.8);
    const RankMapSummary& summary = mapped.report.rank_map;
    CHECK(summary.largest_rank == 6);  // N + extra_modes
    CHECK(std::accumulate(summary.histogram.begin(), summary.histogram.end(), std::int64_t(0)) ==
          std::int64_t(kWidth) * kHeight);
    CHECK(summary.smallest >= 2.0);
    CHECK(summary.largest <= summary.largest_rank);
    CHECK(summary.mean == doctest::Approx(mean_rank(mapped.sink.ranks, 0, kWidth)).epsilon(1e-6));

    const double with_map = error_against_truth(mapped.sink);
    const double two = error_against_truth(run(shot, false, 2).sink);
    const double three = error_against_truth(run(shot, false, 3).sink);
    MESSAGE("MSE: N = 2 with the map " << with_map << ", N = 2 " << two << ", N = 3 " << three);
    CHECK(with_map < 0.5 * two);
    CHECK(with_map < 1.1 * three);
}

TEST_CASE("rank map: streamed, kept, 1 and 2 threads give the same bits")
{
    const int height = 160;  // tall enough to stream in bands
    const MemoryShot shot = shot_of(0.3, 5, height);
    Result kept = run(shot, true, 2);
    Result streamed = run(shot, true, 2, 4'500'000);
    Result single = run(shot, true, 2, 4'500'000, 1);
    CHECK(kept.report.plan.in_memory);
    CHECK_FALSE(streamed.report.plan.in_memory);
    CHECK(streamed.report.plan.band_rows < height);
    CHECK(kept.sink.ranks == streamed.sink.ranks);
    CHECK(kept.sink.rebuilt == streamed.sink.rebuilt);
    CHECK(kept.sink.sigma == streamed.sink.sigma);
    CHECK(streamed.sink.ranks == single.sink.ranks);
    CHECK(streamed.sink.rebuilt == single.sink.rebuilt);
    CHECK(streamed.sink.sigma == single.sink.sigma);
    CHECK(kept.report.rank_map.mean == streamed.report.rank_map.mean);
}

TEST_CASE("rank map: needs the mode filter")
{
    MemoryShot shot = shot_of(0.1, 1);
    Settings settings;
    settings.rank_map.enabled = true;
    MemorySink sink(shot.size);
    CHECK_THROWS_WITH(run_denoise(shot, sink, settings, Progress::silent()),
                      doctest::Contains("--rank-map needs the mode filter"));
}
