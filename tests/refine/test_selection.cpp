// Selection of unsure pixels: the relative score with its dark floor, and the
// shot-wide --budget threshold from the log histogram.
#include "core/refine/selection.h"

#include "core/refine/blend.h"

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

using namespace modestack::refine;

TEST_CASE("the score is the largest relative error over the channels, judged absolutely below the floor")
{
    // pixel 0: bright, sigma 10 % in G; pixel 1: black, sigma 0.05 → 0.05 / 0.1; pixel 2: NaN sigma.
    std::vector<float> value{2, 4, 1, 0, 0, 0, 1, 1, 1};
    std::vector<float> sigma{0.02f, 0.4f, 0.0f, 0.05f, 0.0f, 0.0f, 0.0f, NAN, 0.0f};
    std::vector<float> scores(3);
    relative_error_scores(value.data(), sigma.data(), 3, 3, 0.1f, scores.data());
    CHECK(scores[0] == doctest::Approx(0.4 / std::sqrt(16.01)));
    CHECK(scores[1] == doctest::Approx(0.5));
    CHECK(std::isinf(scores[2]));
    std::vector<std::uint8_t> chosen = select_pixels(scores.data(), 3, 0.2f);
    CHECK(chosen == std::vector<std::uint8_t>{0, 1, 1});
}

TEST_CASE("a pixel's gain is what the blend with a re-render removes from its predicted relMSE")
{
    // Pixel 0: a noise-free re-render removes all of sigma². Pixel 1: a re-render as noisy
    // as the denoised value halves it. Pixel 2: NaN sigma, an infinite gain.
    std::vector<float> value{1, 1, 1, 0, 0, 0, 1, 1, 1};
    std::vector<float> sigma{0.1f, 0.1f, 0.1f, 0.2f, 0.2f, 0.2f, NAN, 0, 0};
    std::vector<float> variance{0, 0, 0, 0.01f, 0.01f, 0.01f, 0, 0, 0}; // at the input's 4 spp
    std::vector<float> gains(3);
    refine_gains(value.data(), sigma.data(), variance.data(), 4.0, 3, 3, 0.1f, gains.data());
    CHECK(gains[0] == doctest::Approx(0.01 / 1.01));
    CHECK(gains[1] == doctest::Approx(0.5 * 0.04 / 0.01)); // 4 × 0.01 at the refine spp = sigma²
    CHECK(std::isinf(gains[2]));

    // Random pixels: the gain equals sigma² before minus sigma² after blend_refined (weight 1),
    // over value² + floor², the channel mean.
    std::mt19937 generator(3);
    std::uniform_real_distribution<float> uniform(0.0f, 1.0f);
    const std::size_t pixels = 500;
    value.resize(pixels * 3), sigma.resize(pixels * 3), variance.resize(pixels * 3), gains.resize(pixels);
    for (std::size_t i = 0; i < pixels * 3; ++i)
        value[i] = 2 * uniform(generator), sigma[i] = 0.3f * uniform(generator),
        variance[i] = 0.5f * uniform(generator);
    const double scale = 4.0 / 256.0;
    refine_gains(value.data(), sigma.data(), variance.data(), scale, pixels, 3, 0.1f, gains.data());
    std::vector<float> rendered(pixels * 3, 0.0f), rendered_variance(pixels * 3), weights(pixels, 1.0f);
    for (std::size_t i = 0; i < pixels * 3; ++i)
        rendered_variance[i] = static_cast<float>(variance[i] * scale);
    std::vector<float> blended = value, after = sigma;
    blend_refined(weights.data(), pixels, 3, rendered.data(), rendered_variance.data(), blended.data(),
                  after.data());
    for (std::size_t p = 0; p < pixels; ++p) {
        double removed = 0, removed_variance = 0;
        for (int c = 0; c < 3; ++c) {
            const std::size_t i = p * 3 + c;
            const double difference = double(sigma[i]) * sigma[i] - double(after[i]) * after[i];
            removed += difference / (double(value[i]) * value[i] + 0.01);
            removed_variance += difference;
        }
        CHECK(gains[p] == doctest::Approx(removed / 3).epsilon(1e-4));
        // The share is the best one for the pixel's summed variance, which never grows (one
        // channel's relative error may, where the channels' variances differ a lot).
        CHECK(removed_variance >= -1e-9);
    }
}

TEST_CASE("a re-render pays where its gain beats the same samples spread over the shot")
{
    // 256 spp where the input has 4: 64 input samples' worth a pixel, so the least gain is 64 × E.
    CHECK(gain_threshold(0.01, 4, 256) == doctest::Approx(0.64));
    CHECK(gain_threshold(0.01, 16, 256) == doctest::Approx(0.16));
    CHECK(std::isinf(gain_threshold(0.0, 4, 256))); // a shot sigma calls exact: nothing
}

TEST_CASE("the budget threshold selects at most P % of the shot and misses it by less than a bin")
{
    std::mt19937 generator(7);
    std::lognormal_distribution<float> distribution(-2.0f, 1.5f);
    std::vector<float> scores(200000);
    for (float& score : scores)
        score = distribution(generator);
    for (int i = 0; i < 1000; ++i)
        scores[i] = 0.0f; // sigma 0: never worth re-rendering
    ScoreHistogram histogram;
    // Counted in two halves, as frames are: the result cannot depend on it.
    histogram.add(scores.data(), scores.size() / 2);
    histogram.add(scores.data() + scores.size() / 2, scores.size() - scores.size() / 2);
    CHECK(histogram.total() == 200000);
    for (double percent : {0.5, 2.0, 10.0, 50.0}) {
        float threshold = histogram.threshold_for_fraction(percent / 100);
        std::vector<std::uint8_t> chosen = select_pixels(scores.data(), scores.size(), threshold);
        double selected = 0;
        for (auto flag : chosen)
            selected += flag;
        CAPTURE(percent);
        CHECK(selected <= percent / 100 * scores.size());
        CHECK(selected >= percent / 100 * scores.size() * 0.99);
    }
    CHECK(std::isinf(histogram.threshold_for_fraction(0.0)));
    std::vector<std::uint8_t> none =
        select_pixels(scores.data(), scores.size(), histogram.threshold_for_fraction(0.0));
    CHECK(std::count(none.begin(), none.end(), 1) == 0);
    std::vector<std::uint8_t> all =
        select_pixels(scores.data(), scores.size(), histogram.threshold_for_fraction(1.0));
    CHECK(std::count(all.begin(), all.end(), 1) == 199000);
}

TEST_CASE("lone selected pixels are dropped, coherent regions kept whole")
{
    const int width = 8, height = 6;
    std::vector<std::uint8_t> selection(width * height, 0);
    auto at = [&](int x, int y) -> std::uint8_t& { return selection[y * width + x]; };
    at(0, 0) = 1;               // alone in a corner
    at(6, 0) = at(7, 1) = 1;    // a diagonal pair: one neighbour each
    for (int y = 2; y < 5; ++y) // a 2x3 block: every pixel has 3 or more
        for (int x = 2; x < 4; ++x)
            at(x, y) = 1;
    drop_isolated_pixels(selection, width, height);
    CHECK(at(0, 0) == 0);
    CHECK(at(6, 0) == 0);
    CHECK(at(7, 1) == 0);
    CHECK(std::count(selection.begin(), selection.end(), 1) == 6);
}
