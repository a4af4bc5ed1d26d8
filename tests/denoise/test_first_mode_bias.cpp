// Sigma's term for the mode filter's bias of the first mode
// (core/denoise/band_rebuild.h, first_mode_filter_bias): near zero on noise,
// the bias itself where noise cannot explain it, a firefly left in the mode not
// counted, and in the engine a hard shadow edge in a static shot, which the
// first mode's Gaussian blurs, covered by sigma.
#include "core/common/error.h"
#include "core/denoise/band_rebuild.h"
#include "core/denoise/engine.h"
#include "tests/denoise/memory_shot.h"

#include <doctest/doctest.h>

#include <cmath>
#include <random>
#include <vector>

using namespace modestack;
using namespace modestack::denoise;
using namespace modestack::denoise::testing;

namespace {

struct Rows {
    int width = 200, height = 4, channels = 3;
    std::vector<float> filtered, unfiltered, noise_variance, gains, bias;
    explicit Rows(unsigned seed, float noise = 0.1f)
    {
        const size_t samples = static_cast<size_t>(width) * height * channels;
        std::mt19937 generator(seed);
        std::normal_distribution<float> normal(0.0f, noise);
        filtered.assign(samples, 1.0f), unfiltered.resize(samples), bias.resize(samples);
        noise_variance.assign(samples, noise * noise), gains.assign(samples / channels, 0.0f);
        for (size_t i = 0; i < samples; ++i)
            unfiltered[i] = 1.0f + normal(generator); // the filter took all of the noise away
    }
    size_t at(int x, int y, int c) const { return (static_cast<size_t>(y) * width + x) * channels + c; }
    void run()
    {
        first_mode_filter_bias(filtered.data(), unfiltered.data(), noise_variance.data(), gains.data(),
                               static_cast<std::int64_t>(filtered.size()), width, channels, bias.data());
    }
};

} // namespace

TEST_CASE("first mode bias: near zero where the filter only took noise away")
{
    for (unsigned seed = 1; seed <= 3; ++seed) {
        CAPTURE(seed);
        Rows rows(seed);
        rows.run();
        double mean = 0;
        for (float value : rows.bias)
            mean += value;
        mean /= static_cast<double>(rows.bias.size());
        MESSAGE("mean bias " << mean / 0.01 << " of the noise variance");
        CHECK(mean < 0.02 * 0.01);
    }
}

TEST_CASE("first mode bias: a blurred edge counts about whole, a firefly left in the mode does not")
{
    Rows rows(7);
    // Row 1: a step from 1 to 3 at x = 100 that the filter smeared over 4 pixels
    // (the unfiltered values are right, with noise); row 2: a firefly at x = 50
    // that the filter removed.
    const float smear[4] = {1.4f, 1.9f, 2.1f, 2.6f};
    for (int x = 98; x < 200; ++x)
        for (int c = 0; c < rows.channels; ++c) {
            rows.unfiltered[rows.at(x, 1, c)] += 2.0f;
            rows.filtered[rows.at(x, 1, c)] = x < 102 ? smear[x - 98] : 3.0f;
        }
    for (int c = 0; c < rows.channels; ++c)
        rows.unfiltered[rows.at(50, 2, c)] += 5.0f;
    rows.run();
    for (int x = 98; x < 102; ++x)
        for (int c = 0; c < rows.channels; ++c) {
            CAPTURE(x);
            const double d = double(rows.filtered[rows.at(x, 1, c)]) - rows.unfiltered[rows.at(x, 1, c)];
            if (std::abs(d) > 0.5) { // well beyond the noise of 0.1
                CHECK(rows.bias[rows.at(x, 1, c)] > 0.5 * d * d);
                CHECK(rows.bias[rows.at(x, 1, c)] < 1.5 * d * d + 0.01);
            }
        }
    for (int c = 0; c < rows.channels; ++c)
        CHECK(rows.bias[rows.at(50, 2, c)] < 0.05); // 25 without the cut to its neighbours' range
}

TEST_CASE("first mode bias: a partial image row is an internal error")
{
    Rows rows(3);
    CHECK_THROWS_AS(first_mode_filter_bias(rows.filtered.data(), rows.unfiltered.data(),
                                           rows.noise_variance.data(), rows.gains.data(), 100, rows.width,
                                           rows.channels, rows.bias.data()),
                    Error);
}

TEST_CASE("first mode bias: sigma covers a hard shadow edge that the first mode's Gaussian blurs")
{
    // A static shot (rank 1) of a lit floor with a hard shadow edge at x = 32,
    // under Gaussian noise: the first mode's survey blurs it (the flat parts
    // ask for a wide filter), which no other term of sigma sees.
    const int width = 64, height = 48, frames = 32;
    const float noise = 0.3f;
    MemoryShot shot;
    shot.size = {frames, width, height, 3};
    std::mt19937 generator(11);
    std::normal_distribution<float> normal(0.0f, noise);
    auto truth = [](int x) { return x < 32 ? 0.2f : 1.0f; };
    for (int t = 0; t < frames; ++t) {
        std::vector<float> frame(static_cast<size_t>(width) * height * 3);
        for (int y = 0; y < height; ++y)
            for (int x = 0; x < width; ++x)
                for (int c = 0; c < 3; ++c)
                    frame[(static_cast<size_t>(y) * width + x) * 3 + c] = truth(x) + normal(generator);
        shot.frames.push_back(frame);
    }
    MemorySink sink(shot.size);
    const Report report = run_denoise(shot, sink, gaussian_noise_settings(), Progress::silent());
    REQUIRE(report.mode_filter.modes.size() > 0);
    MESSAGE("first mode's width " << report.mode_filter.modes[0].width);
    REQUIRE(report.mode_filter.modes[0].width > 0);
    double error = 0, sigma = 0;
    for (int t = 0; t < frames; ++t)
        for (int y = 0; y < height; ++y)
            for (int x = 30; x < 34; ++x) // the edge's two pixels on each side
                for (int c = 0; c < 3; ++c) {
                    const size_t i = (static_cast<size_t>(y) * width + x) * 3 + c;
                    const double e = sink.rebuilt[static_cast<size_t>(t)][i] - truth(x);
                    error += e * e, sigma += double(sink.sigma[static_cast<size_t>(t)][i]) *
                                             sink.sigma[static_cast<size_t>(t)][i];
                }
    // Without the term the ratio is 6.2. The row's prior, learnt where 2 pixels
    // of 64 are biased, counts part of it (empirical Bayes shrinks a sparse
    // bias): 1.56.
    const double ratio = std::sqrt(error / sigma);
    MESSAGE("at the edge, RMS(error) / RMS(sigma) = " << ratio);
    CHECK(ratio > 0.7);
    CHECK(ratio < 2.0);
}
