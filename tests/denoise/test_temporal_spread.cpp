// The input's spread in time (core/denoise/temporal_spread.h): zero where the
// input is steady or changes evenly, the noise variance of white noise, the
// quieter side taken, a lone firefly raising it enough that it cannot pass the
// test alone, the degrees of freedom at the image's and the shot's ends, the
// χ² bound's values.
#include "core/common/error.h"
#include "core/denoise/temporal_spread.h"

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

using namespace modestack;
using namespace modestack::denoise;

namespace {

constexpr int kWidth = 40, kHeight = 30, kChannels = 3, kWindow = 2 * kSpreadFrames + 1;
constexpr size_t kSamples = static_cast<size_t>(kWidth) * kHeight * kChannels;

// kWindow frames of white noise of standard deviation `noise` around `level`.
std::vector<std::vector<float>> noise_frames(float level, float noise, unsigned seed)
{
    std::mt19937 generator(seed);
    std::normal_distribution<float> normal(0.0f, noise);
    std::vector<std::vector<float>> frames(kWindow, std::vector<float>(kSamples));
    for (auto& frame : frames)
        for (float& value : frame)
            value = level + normal(generator);
    return frames;
}

// The window around frame `judged` of a shot of `shot_frames` frames, laid on
// `frames` (frame f − K at index 0).
SpreadWindow window_of(const std::vector<std::vector<float>>& frames, int judged = kSpreadFrames,
                       int shot_frames = 1000)
{
    SpreadWindow window;
    window.image = {kWidth, kHeight, kChannels};
    for (int k = 0; k < kWindow; ++k) {
        const int t = judged + k - kSpreadFrames;
        if (t >= 0 && t < shot_frames)
            window.frames[static_cast<size_t>(k)] = frames[static_cast<size_t>(k)].data();
    }
    return window;
}

struct Spread {
    std::vector<float> spread, terms;
    size_t index(int x, int y, SpreadEstimate e) const
    {
        return (static_cast<size_t>(y) * kWidth + x) * kSpreadEstimates + static_cast<size_t>(e);
    }
    float at(int x, int y, SpreadEstimate e = SpreadEstimate::Steady) const { return spread[index(x, y, e)]; }
    float terms_at(int x, int y, SpreadEstimate e = SpreadEstimate::Steady) const
    {
        return terms[index(x, y, e)];
    }
};

Spread spread_of(const SpreadWindow& window, int row = 0, int end = kHeight)
{
    Spread result;
    result.spread.resize(static_cast<size_t>(kWidth) * (end - row) * kSpreadEstimates);
    result.terms.resize(result.spread.size());
    spread_rows(window, row, end, result.spread.data(), result.terms.data());
    return result;
}

size_t at(int x, int y, int c = 0)
{
    return (static_cast<size_t>(y) * kWidth + x) * kChannels + c;
}

} // namespace

TEST_CASE("spread: a steady input has none, and its terms are the row's pixels times a side's differences "
          "(less one for the trend)")
{
    std::vector<std::vector<float>> frames = noise_frames(0.5f, 0.1f, 1);
    for (auto& frame : frames)
        frame = frames[0]; // every frame the same image
    const Spread inside = spread_of(window_of(frames));
    constexpr auto kSteady = SpreadEstimate::Steady, kTrend = SpreadEstimate::Trend;
    for (int y = 0; y < kHeight; ++y)
        for (int x = 0; x < kWidth; ++x) {
            CAPTURE(x);
            CAPTURE(y);
            const int pixels = x == 0 || x == kWidth - 1 ? 2 : 3;
            CHECK(inside.at(x, y, kSteady) == 0.0f);
            CHECK(inside.at(x, y, kTrend) == 0.0f);
            CHECK(inside.terms_at(x, y, kSteady) == pixels * kSpreadFrames);
            CHECK(inside.terms_at(x, y, kTrend) == pixels * (kSpreadFrames - 1));
        }
    // The shot's second frame: one difference on the left (taken: equal means, the left first), four on the
    // right; for the trend, too few on the left, so the right. Its third: two on the left for the trend.
    const Spread second = spread_of(window_of(frames, 1));
    CHECK(second.terms_at(5, 5, kSteady) == 3);
    CHECK(second.terms_at(5, 5, kTrend) == 3 * (kSpreadFrames - 1));
    CHECK(spread_of(window_of(frames, 2)).terms_at(5, 5, kTrend) == 3);
    // A shot of one frame: no neighbour in time, no test; of two, none for the trend.
    for (int shot_frames : {1, 2}) {
        CAPTURE(shot_frames);
        const Spread alone = spread_of(window_of(frames, 0, shot_frames));
        CHECK(std::isinf(alone.at(5, 5, kTrend)));
        CHECK(alone.terms_at(5, 5, kTrend) == 0);
        CHECK(std::isinf(alone.at(5, 5, kSteady)) == (shot_frames == 1));
        CHECK(alone.terms_at(5, 5, kSteady) == (shot_frames == 1 ? 0 : 3));
    }
}

TEST_CASE("spread: light that changes evenly over a side is not noise")
{
    // Every pixel brightens by its own step each frame (a light moving
    // closer), a clean input: no spread, where the frame-to-frame differences
    // alone would count each step²/2 as noise.
    std::vector<std::vector<float>> frames = noise_frames(0.5f, 0.0f, 9);
    for (int k = 0; k < kWindow; ++k)
        for (size_t i = 0; i < kSamples; ++i)
            frames[static_cast<size_t>(k)][i] =
                0.3f + 0.04f * static_cast<float>(k) * (1.0f + 0.01f * (i % 7));
    const Spread result = spread_of(window_of(frames));
    for (int x : {0, 10, kWidth - 1}) {
        CHECK(result.at(x, 10, SpreadEstimate::Trend) <
              1e-6 * 0.04 * 0.04); // float rounding of the steps only
        CHECK(result.at(x, 10, SpreadEstimate::Steady) > 0.5 * 0.04 * 0.04 / 2);
    }
    // With noise on top, the noise's variance on average.
    const float noise = 0.02f;
    const std::vector<std::vector<float>> noisy = noise_frames(0.0f, noise, 10);
    for (int k = 0; k < kWindow; ++k)
        for (size_t i = 0; i < kSamples; ++i)
            frames[static_cast<size_t>(k)][i] += noisy[static_cast<size_t>(k)][i];
    const Spread first = spread_of(window_of(frames, 0)); // one side only, no minimum to bias it
    double mean = 0;
    for (int y = 0; y < kHeight; ++y)
        for (int x = 0; x < kWidth; ++x)
            mean += first.at(x, y, SpreadEstimate::Trend);
    mean /= kWidth * kHeight;
    CHECK(mean == doctest::Approx(noise * noise).epsilon(0.04));
}

TEST_CASE("spread: of white noise it is the noise variance on average")
{
    const float noise = 0.05f;
    const std::vector<std::vector<float>> frames = noise_frames(1.0f, noise, 2);
    // The shot's first frame has one side only, so no minimum biases it.
    const Spread first = spread_of(window_of(frames, 0));
    for (const SpreadEstimate e : {SpreadEstimate::Steady, SpreadEstimate::Trend}) {
        double mean = 0;
        for (int y = 0; y < kHeight; ++y)
            for (int x = 0; x < kWidth; ++x)
                mean += first.at(x, y, e);
        mean /= kWidth * kHeight;
        CHECK(mean == doctest::Approx(noise * noise).epsilon(0.04));
    }
}

TEST_CASE("spread: a change on one side does not hide the steady other")
{
    std::vector<std::vector<float>> frames = noise_frames(0.5f, 0.0f, 3);
    for (int k = kSpreadFrames + 2; k < kWindow; ++k) // a light switched on two frames after
        for (float& value : frames[static_cast<size_t>(k)])
            value = 3.0f;
    const Spread result = spread_of(window_of(frames));
    for (const SpreadEstimate e : {SpreadEstimate::Steady, SpreadEstimate::Trend})
        CHECK(result.at(10, 10, e) == 0.0f);
    CHECK(result.terms_at(10, 10) == 3 * kSpreadFrames);
}

TEST_CASE("spread: a lone firefly raises either spread so far that it stands within its reach, so it cannot "
          "pass alone")
{
    for (const float firefly : {2.0f, 50.0f, 1e4f}) {
        for (const float step : {0.0f, 0.05f}) { // on a steady input, and on one that brightens each frame
            CAPTURE(firefly);
            CAPTURE(step);
            std::vector<std::vector<float>> frames = noise_frames(0.5f, 0.02f, 4);
            for (int k = 0; k < kWindow; ++k)
                for (float& value : frames[static_cast<size_t>(k)])
                    value += step * static_cast<float>(k);
            for (int c = 0; c < kChannels; ++c)
                frames[kSpreadFrames][at(7, 9, c)] = firefly;
            const Spread result = spread_of(window_of(frames));
            // How far it stands above its neighbour in time, and above the trend
            // of the frames beyond (per frame, away from it), on the nearer side.
            double above_neighbour = INFINITY, above_trend = INFINITY;
            for (int side : {-1, 1}) {
                double d = 0, t = 0;
                for (int c = 0; c < kChannels; ++c) {
                    const float neighbour = frames[static_cast<size_t>(kSpreadFrames + side)][at(7, 9, c)];
                    const float far =
                        frames[static_cast<size_t>(kSpreadFrames + side * kSpreadFrames)][at(7, 9, c)];
                    d += (firefly - neighbour) / kChannels;
                    t += (firefly - neighbour - (neighbour - far) / (kSpreadFrames - 1.0)) / kChannels;
                }
                above_neighbour = std::min(above_neighbour, d * d),
                above_trend = std::min(above_trend, t * t);
            }
            for (const SpreadEstimate e : {SpreadEstimate::Steady, SpreadEstimate::Trend}) {
                const double reach = lone_sample_reach(e, static_cast<int>(result.terms_at(7, 9, e)));
                const double stands = e == SpreadEstimate::Steady ? above_neighbour : above_trend;
                CHECK(stands <= reach * reach * result.at(7, 9, e) * (1 + 1e-5));
            }
        }
    }
    CHECK(lone_sample_reach(SpreadEstimate::Steady, 12) == doctest::Approx(std::sqrt(24.0)));
    CHECK(lone_sample_reach(SpreadEstimate::Trend, 9) == doctest::Approx(std::sqrt(30.0)));
    CHECK_THROWS_AS(lone_sample_reach(SpreadEstimate::Trend, 0), Error);
}

TEST_CASE("spread: rows of a call are the rows of the image, from any first row")
{
    const std::vector<std::vector<float>> frames = noise_frames(0.5f, 0.1f, 6);
    const Spread whole = spread_of(window_of(frames));
    const Spread part = spread_of(window_of(frames), 11, 17);
    for (int y = 11; y < 17; ++y)
        for (int x = 0; x < kWidth; ++x)
            for (const SpreadEstimate e : {SpreadEstimate::Steady, SpreadEstimate::Trend})
                CHECK(part.at(x, y - 11, e) == whole.at(x, y, e));
}

TEST_CASE("spread: the judged samples are the larger of as read and cleaned")
{
    const std::vector<float> as_read{0.0f, 5.0f, 0.3f}, cleaned{0.1f, 1.1f, 0.3f};
    std::vector<float> judged(3);
    judged_samples(as_read.data(), cleaned.data(), 3, judged.data());
    CHECK(judged == std::vector<float>{0.1f, 5.0f, 0.3f});
}

TEST_CASE("spread: the bound is n over the 0.001 quantile of chi-squared with n degrees of freedom")
{
    // The quantiles from scipy.stats.chi2.ppf(0.001, n).
    CHECK(spread_bound(1) == doctest::Approx(1 / 1.5707971492624921e-06).epsilon(1e-6));
    CHECK(spread_bound(2) == doctest::Approx(2 / 0.002001000667167068).epsilon(1e-6));
    CHECK(spread_bound(12) == doctest::Approx(12 / 2.2142093205112787).epsilon(1e-6));
    CHECK(spread_bound(36) == doctest::Approx(36 / 15.324112791615619).epsilon(1e-6));
    for (int n = 1; n < 40; ++n)
        CHECK(spread_bound(n + 1) < spread_bound(n));
    CHECK_THROWS_AS(spread_bound(0), Error);
}

TEST_CASE("spread: no judged frame or rows outside the image are internal errors")
{
    const std::vector<std::vector<float>> frames = noise_frames(0.5f, 0.1f, 7);
    SpreadWindow window = window_of(frames);
    std::vector<float> spread(kSamples * kSpreadEstimates), terms(kSamples * kSpreadEstimates);
    CHECK_THROWS_AS(spread_rows(window, 0, kHeight + 1, spread.data(), terms.data()), Error);
    window.frames[kSpreadFrames] = nullptr;
    CHECK_THROWS_AS(spread_rows(window, 0, kHeight, spread.data(), terms.data()), Error);
}
