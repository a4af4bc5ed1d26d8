// `denoise --whiten` (whitening.h): the weights are 1/σ of the variance layer
// (their ratio between a noisy and a quiet region is exactly the ratio of the
// noise deviations); the whitened run rebuilds a noise-free low-rank shot exactly
// (the weights change the modes only); on a shot whose noisy half hides the weak mode of
// its quiet half, hard truncation without whitening spends its modes on the noise
// and loses it, the whitened run keeps it; bad variances are input errors.
#include "core/common/error.h"
#include "core/denoise/engine.h"
#include "core/denoise/whitening.h"
#include "tests/denoise/memory_shot.h"

#include <doctest/doctest.h>

#include <cmath>
#include <random>
#include <vector>

using namespace modestack;
using namespace modestack::denoise;
using namespace modestack::denoise::testing;

namespace {

constexpr int kWidth = 32, kHeight = 24, kFrames = 24;
constexpr float kNoisy = 0.5f, kQuiet = 0.02f;  // noise deviations of the left and right halves

float truth(int t, int x, int y, int c)
{
    const float time = static_cast<float>(t) / kFrames;
    if (x < kWidth / 2)  // a bright region with a strong mode
        return 4.0f + 2.0f * std::sin(0.2f * y + c) * std::cos(3.0f * time);
    // a dim region with a weak mode of its own
    return 0.3f + 0.1f * std::cos(0.4f * x + 0.3f * y + c) * std::sin(5.0f * time + 1.0f);
}

MemoryShot half_noisy_shot(bool with_noise, unsigned seed, int height = kHeight)
{
    MemoryShot shot;
    shot.size = {kFrames, kWidth, height, 3};
    std::mt19937 generator(seed);
    std::normal_distribution<float> normal(0.0f, 1.0f);
    for (int t = 0; t < kFrames; ++t) {
        std::vector<float> frame, variance;
        for (int y = 0; y < height; ++y)
            for (int x = 0; x < kWidth; ++x)
                for (int c = 0; c < 3; ++c) {
                    const float deviation = x < kWidth / 2 ? kNoisy : kQuiet;
                    frame.push_back(truth(t, x, y, c) + (with_noise ? deviation * normal(generator) : 0.0f));
                    variance.push_back(deviation * deviation);
                }
        shot.frames.push_back(frame);
        shot.variance.push_back(variance);
    }
    return shot;
}

Settings fixed(int kept_modes)
{
    Settings settings;
    settings.outliers.fireflies = false;
    settings.mode_filter.enabled = false;
    settings.rank_rule.rule = lowrank::RankRule::Fixed;
    settings.rank_rule.fixed_modes = kept_modes;
    return settings;
}

// Runs the engine on `shot`, whitened or not; returns the rebuilt frames.
std::vector<std::vector<float>> rebuild_shot(MemoryShot& shot, bool whiten, const Settings& settings)
{
    MemorySink sink(shot.size);
    if (!whiten) {
        run_denoise(shot, sink, settings, Progress::silent());
        return sink.rebuilt;
    }
    const WhiteningWeights weights = whitening_weights(shot);
    Settings whitened = settings;
    whitened.whitening = &weights.weights;
    run_denoise(shot, sink, whitened, Progress::silent());
    for (const auto& frame : sink.sigma)
        for (float value : frame)
            REQUIRE((std::isfinite(value) && value >= 0.0f));
    return sink.rebuilt;
}

// Mean squared error against the truth over the quiet (right) half.
double quiet_error(const std::vector<std::vector<float>>& rebuilt)
{
    double sum = 0;
    int count = 0;
    for (int t = 0; t < kFrames; ++t)
        for (int y = 0; y < kHeight; ++y)
            for (int x = kWidth / 2; x < kWidth; ++x)
                for (int c = 0; c < 3; ++c, ++count) {
                    const double error = rebuilt[size_t(t)][(size_t(y) * kWidth + x) * 3 + c] - truth(t, x, y, c);
                    sum += error * error;
                }
    return sum / count;
}

}  // namespace

TEST_CASE("whitening: weights are 1/sigma of the variance layer, and a noise-free low-rank shot comes back exactly")
{
    MemoryShot clean = half_noisy_shot(false, 1);
    const WhiteningWeights weights = whitening_weights(clean);
    CHECK(weights.mean_variance == doctest::Approx(0.5 * (kNoisy * kNoisy + kQuiet * kQuiet)));
    CHECK(weights.floored_samples == 0);
    // Away from the border between the halves (the 3 x 3 pooling): ratio σ_noisy/σ_quiet.
    const size_t left = (size_t(5) * kWidth + 3) * 3, right = (size_t(5) * kWidth + kWidth - 4) * 3;
    CHECK(weights.weights[right] / weights.weights[left] == doctest::Approx(kNoisy / kQuiet).epsilon(1e-6));
    double mean = 0;
    for (float w : weights.weights)
        mean += w;
    CHECK(mean / weights.weights.size() == doctest::Approx(1.0).epsilon(1e-6));

    // truth() is rank 4 over time (constant + one mode per half, each a sum of two
    // products in c): the whitened rank-4 rebuild must return every value.
    const std::vector<std::vector<float>> rebuilt = rebuild_shot(clean, true, fixed(4));
    double worst = 0;
    for (int t = 0; t < kFrames; ++t)
        for (size_t i = 0; i < rebuilt[size_t(t)].size(); ++i)
            worst = std::max(worst, double(std::abs(rebuilt[size_t(t)][i] - clean.frames[size_t(t)][i])));
    CHECK(worst < 2e-5);

    MemoryShot bad = clean;
    bad.variance[3][17] = -1.0f;
    CHECK_THROWS_WITH_AS(whitening_weights(bad), doctest::Contains("frame 4 holds a variance of -1"), Error);
}

TEST_CASE("whitening: the weak mode of a quiet region hidden by a noisy region's noise is kept")
{
    MemoryShot shot = half_noisy_shot(true, 9);
    for (int kept_modes : {3, 4}) {
        CAPTURE(kept_modes);
        const double plain = quiet_error(rebuild_shot(shot, false, fixed(kept_modes)));
        const double whitened = quiet_error(rebuild_shot(shot, true, fixed(kept_modes)));
        MESSAGE("rank " << kept_modes << ": quiet-half MSE plain " << plain << ", whitened " << whitened
                        << " (its noise variance " << kQuiet * kQuiet << ")");
        CHECK(whitened < plain / 4);
        CHECK(whitened < kQuiet * kQuiet);  // below the input's own noise
    }
}

TEST_CASE("whitening: streamed and kept shots, gram and rsvd give the same modes' effect (bits for gram)")
{
    MemoryShot shot = half_noisy_shot(true, 4, 160);  // tall enough to stream in bands
    const WhiteningWeights weights = whitening_weights(shot);
    auto run = [&](std::int64_t memory, Solver solver) {
        MemorySink sink(shot.size);
        Settings settings = fixed(3);
        settings.whitening = &weights.weights;
        settings.max_memory_bytes = memory;
        settings.solver = solver;
        Report report = run_denoise(shot, sink, settings, Progress::silent());
        return std::make_pair(report, sink);
    };
    auto [kept_report, kept] = run(std::int64_t(1) << 30, Solver::Gram);
    // The smallest budget that plans the shot at all streams it in bands.
    std::int64_t budget = 1 << 20;
    while (true) {
        try {
            run(budget, Solver::Gram);
            break;
        } catch (const Error&) {
            budget += 1 << 16;
        }
    }
    auto [streamed_report, streamed] = run(budget, Solver::Gram);
    CHECK(kept_report.plan.in_memory);
    REQUIRE_FALSE(streamed_report.plan.in_memory);
    CHECK(streamed_report.plan.band_rows < 160);
    CHECK(kept.rebuilt == streamed.rebuilt);  // the weights follow the band's rows
    auto [randomized_report, randomized] = run(std::int64_t(1) << 30, Solver::RandomizedSvd);
    CHECK(quiet_error(randomized.rebuilt) == doctest::Approx(quiet_error(kept.rebuilt)).epsilon(0.02));
}
